"""`gonio noise` in bounded memory (issue 26): the stream is read in blocks to find the
rests, only the analysed window's counts are read (in pieces, memory-mapped beyond a size)
and analysed in place. The numbers must be those of the former in-memory path (the whole
stream read, the windows found on whole arrays, the record analysed from a copy): compared
here bit for bit (JSON of every result), with pieces, row groups and the memory-map size
made small so that every seam is crossed; and the ADEV against allantools to 1e-12."""
from __future__ import annotations

import json
import math

import allantools
import numpy as np
import pytest

import gonio.analysis.noise.record as record_mod
import gonio.formats.streams as streams_mod
from gonio.analysis.noise import analyse_record, static_windows
from gonio.cli.cmd_noise import _INPUTS, stream_noise
from gonio.formats.streams import read_stream, write_stream
from gonio.units import S_PER_H

K = 3600.0          # counts per degree
FS = 100.0          # Hz


def _stream(path, seed=5):
    """Three rests (300 s, 200 s, 120 s) joined by 90° moves; white + random-walk rate noise
    and the Earth rate on the counter; encoder without noise."""
    rng = np.random.default_rng(seed)
    segs, table = [], []
    for rest_s, level in ((300.0, 0.0), (200.0, 90.0), (120.0, 180.0)):
        if table:
            move = np.linspace(table[-1][-1], level, int(2.0 * FS) + 1)[1:-1]
            table.append(move)
        table.append(np.full(int(rest_s * FS), level))
    tab = np.concatenate(table)
    n = tab.size
    t = np.arange(n) / FS
    rate_dps = 0.003 + 0.02 * rng.standard_normal(n) + np.cumsum(1e-5 * rng.standard_normal(n))
    angle = tab + np.cumsum(rate_dps) / FS
    counts = np.rint(angle * K).astype(np.int64)
    md = {"nominal_scale_factor_counts_per_deg": f"{K:g}", "counter_bits": "32",
          "counter_signed": "true", "sample_rate_hz": f"{FS:g}"}
    return write_stream(path, t, counts, tab, md)


def _in_memory(path, input_kind="angle", *, window=None, each_window=False, **kw):
    """The former `stream_noise` (before issue 26), verbatim in its arithmetic."""
    stream = read_stream(path)
    k = float(stream.metadata["nominal_scale_factor_counts_per_deg"])
    t = np.asarray(stream.time_s, dtype=np.float64)
    wins = static_windows(t, stream.table_deg, stream.gyro_counts,
                          scale_factor_counts_per_deg=k, window=window)
    wins = sorted(wins, key=lambda w: (-w.duration_s, w.i_start))
    counts_all = np.asarray(stream.gyro_counts, dtype=np.float64)
    out = []
    for w in (wins if each_window else wins[:1]):
        tw = t[w.i_start: w.i_end + 1]
        tau0 = float((tw[-1] - tw[0]) / (tw.size - 1))
        counts = counts_all[w.i_start: w.i_end + 1]
        if _INPUTS[input_kind] == "rate":
            res = analyse_record(counts * (S_PER_H / k), tau0, "rate", unit="deg/h", **kw)
        else:
            res = analyse_record(counts, tau0, _INPUTS[input_kind], scale=k / S_PER_H,
                                 unit="deg/h", **kw)
        res.window, res.windows_found = w, len(wins)
        out.append(res)
    return out


def _json(results):
    return json.dumps([r.to_dict() for r in results], sort_keys=True, default=str)


@pytest.fixture(scope="module")
def streams(tmp_path_factory):
    d = tmp_path_factory.mktemp("noise-mem")
    mp = pytest.MonkeyPatch()
    mp.setattr(streams_mod, "PARQUET_ROW_GROUP", 7919)       # many row groups, odd seams
    try:
        return {"parquet": _stream(d / "s.parquet"), "csv": _stream(d / "s.csv")}
    finally:
        mp.undo()


@pytest.mark.parametrize("memmap", [False, True])
@pytest.mark.parametrize("fmt, input_kind, opts", [
    ("parquet", "angle", dict(bootstrap=3)),
    ("parquet", "rate", dict(kind="hdev", bootstrap=0)),
    ("csv", "counts", dict(modified=True, bootstrap=0, taus="decade:4")),
    ("parquet", "angle", dict(each_window=True, bootstrap=0, kind="totdev")),
    ("parquet", "angle", dict(window="310:480", bootstrap=0)),
])
def test_bounded_noise_equals_the_in_memory_path(streams, monkeypatch, memmap, fmt,
                                                 input_kind, opts):
    monkeypatch.setattr(record_mod, "_READ_PIECE", 4099)
    if memmap:
        monkeypatch.setattr(record_mod, "MEMMAP_SAMPLES", 10_000)
    path = streams[fmt]
    opts = dict(opts)
    window, each = opts.pop("window", None), opts.pop("each_window", False)
    new = stream_noise(path, input_kind, window=window, each_window=each,
                       show_progress=False, **opts)
    old = _in_memory(path, input_kind, window=window, each_window=each, **opts)
    assert _json(new) == _json(old)
    assert len(new) == (3 if each else 1)


def test_bounded_adev_against_allantools(streams):
    """ADEV at octave τ of the longest rest, against allantools.oadev on the same phase."""
    r = stream_noise(streams["parquet"], "angle", bootstrap=0, show_progress=False)[0]
    s = read_stream(streams["parquet"])
    w = r.window
    phase_s = s.gyro_counts[w.i_start: w.i_end + 1].astype(np.float64) / K * S_PER_H
    # phase in (°/h)·s so that the deviation comes out in °/h, as gonio's
    taus, dev, _, _ = allantools.oadev(phase_s, rate=1.0 / r.tau0_s, data_type="phase",
                                       taus=r.allan.tau_s)
    np.testing.assert_allclose(taus, r.allan.tau_s, rtol=1e-12)
    np.testing.assert_allclose(r.allan.adev, dev, rtol=1e-12)


def test_window_record_uniform_sampling_checked_across_piece_seams(tmp_path, monkeypatch):
    from gonio.errors import GonioError
    monkeypatch.setattr(record_mod, "_READ_PIECE", 1000)
    n = 5000
    t = np.arange(n) / FS
    t[3000:] += 0.5 / FS          # a step of 1.5 τ0 exactly at a piece seam (sample 3001)
    counts = np.cumsum(np.random.default_rng(1).integers(-50, 50, n))
    p = write_stream(tmp_path / "u.parquet", t, counts, np.zeros(n),
                     {"nominal_scale_factor_counts_per_deg": "3600", "counter_bits": "32",
                      "counter_signed": "true"})
    with pytest.raises(GonioError, match=r"not uniform.*sample 3001"):
        stream_noise(p, "angle", window="1:45", bootstrap=0, show_progress=False)
    assert math.isfinite(stream_noise(p, "angle", window="1:25", bootstrap=0,
                                      show_progress=False)[0].tau0_s)
