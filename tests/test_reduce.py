"""Stream → readings against the virtual bench's own readings (the independent reference:
the session takes its readings at planned grid indices, the reduction finds them from the
samples alone), with glitches, a missing round, an extra stop, noise, no table column."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.errors import GonioError
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.override import read_override
from gonio.reduce import RestFinder, find_rests
from gonio.specs.ogam_draft.reduce import reduce_stream
from gonio.formats.streams import Stream

PROTO = parse_protocol({
    "protocol": {"name": "mini"},
    "session": {"warm_up_s": 0.0, "static_s": 5.0, "settle_s": 1.0},
    "zero_stability": {"readings": 3, "interval_s": 4.0},
    "scale_factor": {"rest_s": 3.0, "read_delay_s": 1.505,
                     "rounds": [{"stop_deg": 60.0}, {"stop_deg": 120.0}, {"stop_deg": 360.0}]},
    "angle_deviation": {"rest_s": 3.0, "read_delay_s": 1.005, "series": 2,
                        "rounds": [{"stop_deg": 30.0}, {"stop_deg": 90.0}, {"stop_deg": 180.0}]},
    "rate_consistency": {"rates_dps": [10.0, 60.0], "rest_s": 3.0, "read_delay_s": 1.005},
    "pointing_consistency": {"orientations": ["up", "north"], "rest_s": 3.0,
                             "read_delay_s": 1.005},
})
KEY = ["test", "series", "round", "orientation"]


def _session(bench="fog", quantisation=True, noise=True, seed=3):
    b = load_bench(bench)
    b = dataclasses.replace(b, sample_rate_hz=100.0)
    if not noise:
        b = b.random_off()
    b = dataclasses.replace(b, instrument=dataclasses.replace(b.instrument,
                                                              quantisation=quantisation))
    parts = []
    res = run_session(PROTO, b, seed=seed,
                      stream=lambda t, c, th: parts.append((t.copy(), c.copy(), th.copy())))
    t, c, th = (np.concatenate([p[i] for p in parts]) for i in range(3))
    md = {"nominal_scale_factor_counts_per_deg": repr(b.instrument.nominal_scale_factor_counts_per_deg)}
    if not quantisation:
        md["counts_quantised"] = "false"
    st = Stream(t, c.astype(np.int64) if quantisation else c, th, metadata=md)
    return res.readings, st


@pytest.fixture(scope="module")
def fog():
    return _session("fog")


def _compare(ref: pd.DataFrame, got: pd.DataFrame, atol: float, t_atol: float = 0.0101):
    m = ref.merge(got, on=KEY, how="outer", suffixes=("_ref", "_got"), indicator=True)
    assert (m["_merge"] == "both").all(), m[m["_merge"] != "both"]
    np.testing.assert_allclose(m["gyro_counts_got"], m["gyro_counts_ref"], rtol=0, atol=atol)
    np.testing.assert_allclose(m["time_s_got"], m["time_s_ref"], rtol=0, atol=t_atol)
    np.testing.assert_array_equal(m["table_deg_got"].fillna(-1), m["table_deg_ref"].fillna(-1))
    return m


def test_clean_stream_reproduces_session_counts(fog):
    ref, st = fog
    red = reduce_stream(st, PROTO)
    assert [u for u in red.unmatched if u["kind"] == "round"] == []
    assert len(red.readings) == len(ref) == 3 + 3 + 2 * 3 + 3 + 3
    m = _compare(ref, red.readings, atol=1.0)
    assert (m["gyro_counts_got"] == m["gyro_counts_ref"]).mean() > 0.9
    # same order as the session's readings file
    assert red.readings[KEY].values.tolist() == ref[KEY].values.tolist()


@pytest.mark.parametrize("bench", ["rlg", "fog"])
def test_quantisation_off_is_exact(bench):
    ref, st = _session(bench, quantisation=False)
    red = reduce_stream(st, PROTO)
    m = _compare(ref, red.readings, atol=2e-6)
    np.testing.assert_array_equal(m["time_s_got"], m["time_s_ref"])


def test_glitches_in_table_are_ignored(fog):
    ref, st = fog
    rng = np.random.default_rng(11)
    tab = st.table_deg.copy()
    idx = rng.choice(np.arange(5, tab.size - 5, 3), 200, replace=False)
    tab[idx] += rng.choice([-1.0, 1.0], 200) * rng.uniform(0.01, 50.0, 200)
    red = reduce_stream(dataclasses.replace(st, table_deg=tab), PROTO)
    assert [u for u in red.unmatched if u["kind"] == "round"] == []
    _compare(ref, red.readings, atol=1.0)


def test_missing_round_is_reported_and_others_kept(fog):
    ref, st = fog
    # cut round 2 of angle_deviation series 1: from its zeroing to the next zeroing
    probe = reduce_stream(st, PROTO).readings.set_index(KEY)
    t0 = probe.loc[("angle_deviation", 1, 2, "up"), "t_zero_s"]
    t1 = probe.loc[("angle_deviation", 1, 3, "up"), "t_zero_s"]
    keep = (st.time_s <= t0) | (st.time_s > t1)
    cut = Stream(st.time_s[keep], st.gyro_counts[keep], st.table_deg[keep], metadata=st.metadata)
    red = reduce_stream(cut, PROTO)
    lost = [(u["test"], u["series"], u["round"]) for u in red.unmatched if u["kind"] == "round"]
    assert lost == [("angle_deviation", 1, 2)]
    assert "no rest at 90°" in [u for u in red.unmatched if u["kind"] == "round"][0]["reason"]
    _compare(ref[~((ref.test == "angle_deviation") & (ref.series == 1) & (ref["round"] == 2))],
             red.readings, atol=1.0)


def test_extra_stop_is_skipped(fog):
    ref, st = fog
    # the table pauses 2 s at ~100° on the return of scale_factor round 2 (120° → 0°)
    probe = reduce_stream(st, PROTO).readings.set_index(KEY)
    after = probe.loc[("scale_factor", 1, 2, "up"), "t_read_s"]
    i = int(np.flatnonzero((st.time_s > after) & (st.table_deg < 100.0))[0])
    n = 200
    dt = 0.01
    rate = (st.gyro_counts[i] - st.gyro_counts[i - 100]) / 1.0   # not used; keep shape
    ins_c = st.gyro_counts[i - 1] + np.round(np.arange(1, n + 1) * 0.3).astype(np.int64)
    t = np.concatenate((st.time_s[:i], st.time_s[i - 1] + dt * np.arange(1, n + 1),
                        st.time_s[i:] + n * dt))
    c = np.concatenate((st.gyro_counts[:i], ins_c, st.gyro_counts[i:] + (ins_c[-1] - st.gyro_counts[i - 1])))
    tab = np.concatenate((st.table_deg[:i], np.full(n, st.table_deg[i - 1]), st.table_deg[i:]))
    red = reduce_stream(Stream(t, c, tab, metadata=st.metadata), PROTO)
    assert [u for u in red.unmatched if u["kind"] == "round"] == []
    extra = [u for u in red.unmatched if u["kind"] == "rest" and 95 < u["level_deg"] < 105]
    assert len(extra) == 1 and abs(extra[0]["t_end_s"] - extra[0]["t_start_s"] - 2.0) < 0.05
    _compare(ref, red.readings, atol=1.0)


def test_without_table_column_from_gyro_rate(fog):
    ref, st = fog
    red = reduce_stream(dataclasses.replace(st, table_deg=None), PROTO)
    assert [u for u in red.unmatched if u["kind"] == "round"] == []
    # gyro-rate edges: the reading may fall a few samples late on slow moves (at rest: counts
    # move by noise only)
    _compare(ref, red.readings, atol=3.0, t_atol=0.05)


def test_noisier_instrument_still_matches():
    """ARW ×20: the counts change, the reduction still reproduces the bench's."""
    b = load_bench("rlg")
    inst = dataclasses.replace(b.instrument, arw_dpsh=b.instrument.arw_dpsh * 20 + 0.01)
    b = dataclasses.replace(b, sample_rate_hz=100.0, instrument=inst)
    parts = []
    res = run_session(PROTO, b, seed=9, stream=lambda t, c, th: parts.append((t, c, th)))
    t, c, th = (np.concatenate([p[i] for p in parts]) for i in range(3))
    red = reduce_stream(Stream(t, c.astype(np.int64), th), PROTO)
    _compare(res.readings, red.readings, atol=1.0)


def test_override_replaces_a_round(fog, tmp_path):
    ref, st = fog
    base = reduce_stream(st, PROTO).readings.set_index(KEY)
    row = base.loc[("scale_factor", 1, 2, "up")]
    p = tmp_path / "o.csv"
    p.write_text(f"test,series,round,t_zero_s,t_read_s\nscale_factor,1,2,{float(row.t_zero_s)!r},"
                 f"{float(row.t_read_s) + 0.5!r}\n")
    red = reduce_stream(st, PROTO, override=read_override(p))
    got = red.readings.set_index(KEY).loc[("scale_factor", 1, 2, "up")]
    assert got.t_read_s == pytest.approx(row.t_read_s + 0.5)
    # at rest the compensated count moves by noise only (< 3 counts in 0.5 s for this FOG)
    assert abs(got.gyro_counts - row.gyro_counts) <= 3
    assert any("override" in s for s in red.log)
    bad = tmp_path / "b.csv"
    bad.write_text("test,series,round,t_zero_s,t_read_s\nscale_factor,x,2,1,2\n")
    with pytest.raises(GonioError, match=r"b.csv:2: column series"):
        read_override(bad)
    with pytest.raises(GonioError, match="exactly one round"):
        reduce_stream(st, PROTO, override=[{"test": "scale_factor", "series": 1, "round": 9,
                                            "t_zero_s": 1.0, "t_read_s": 2.0}])


def test_rest_finder_chunk_independent():
    rng = np.random.default_rng(2)
    t = np.arange(20000) * 0.01
    x = np.cumsum(np.where(rng.random(20000) < 0.002, 1, 0)) * 0.0
    seg = (t // 7).astype(int)
    x = np.where(seg % 2 == 0, seg * 10.0, seg * 10.0 + (t % 7) * 1.0)
    x[rng.integers(1, 19999, 50)] += 5.0
    whole = find_rests(t, x, refine=False)
    for size in (1, 2, 3, 777):
        f = RestFinder(rate_threshold_dps=0.01, window=1, despike=True, min_rest_s=0.5)
        for a in range(0, t.size, size):
            f.feed(t[a:a + size], x[a:a + size])
        got = f.finish()
        assert [(r.i_start, r.i_end) for r in got] == [(r.i_start, r.i_end) for r in whole]
        assert [r.level_deg for r in got] == pytest.approx([r.level_deg for r in whole],
                                                           abs=1e-9)
    # closed form: rests are the even 7 s segments
    assert len(whole) == 15 and all(abs(r.duration_s - 7.0) < 0.05 for r in whole[1:-1])


def test_subsample_edges_closed_form():
    """Departure at 3.0 s, arrival at 3 + 2·√(30/60) s (triangular move): refined to < 1e-6 s."""
    from gonio.physics.kinematics import Timeline
    tl = Timeline(0.0)
    tl.dwell(3.0)
    arrive = tl.move(30.0, 60.0, 60.0)
    tl.dwell(4.0)
    t = np.arange(0, 8, 0.01)
    r = find_rests(t, tl.angle_deg(t))
    assert r[0].t_depart_s == pytest.approx(3.0, abs=1e-6)
    assert r[1].t_arrive_s == pytest.approx(3.0 + 2 * math.sqrt(0.5), abs=1e-6)
    assert arrive == pytest.approx(3.0 + 2 * math.sqrt(0.5))


def test_gyro_mode_needs_scale_factor(fog):
    _, st = fog
    with pytest.raises(GonioError, match="nominal_scale_factor_counts_per_deg"):
        reduce_stream(Stream(st.time_s, st.gyro_counts, None, metadata={}), PROTO)


@pytest.mark.parametrize("fmt, protocol", [
    ("parquet", "tilt-estimate"),                       # the command, built-in protocol
    ("csv", "SHORT"),                                   # the CSV stream, a shorter programme
])
def test_simulated_tilt_estimate_stream_reduces(tmp_path, fmt, protocol):
    """issue 26: `gonio simulate --protocol tilt-estimate --stream` then `gonio reduce` of that
    stream failed ('no round of the protocol could be matched in the stream (12 rests found)').
    The reduction must give the bench's own readings (its planned grid samples: the independent
    reference), and `gonio tilt-estimate` the same tilt from both."""
    import io
    import json
    from contextlib import redirect_stdout
    from pathlib import Path

    from gonio.cli import main

    if protocol == "SHORT":
        text = (Path(__file__).resolve().parents[1] / "protocols" / "tilt-estimate.toml"
                ).read_text(encoding="utf-8")
        text = (text.replace("positions = 12", "positions = 6")
                .replace("dwell_s = 120.0", "dwell_s = 20.0")
                .replace("warm_up_s = 3600.0", "warm_up_s = 0.0"))
        protocol = str(tmp_path / "short.toml")
        Path(protocol).write_text(text, encoding="utf-8")
    s, r = tmp_path / "s", tmp_path / "r.csv"
    assert main(["simulate", "--protocol", protocol, "--stream", "--stream-format", fmt,
                 "--out", str(s)]) == 0
    assert main(["reduce", str(s / f"stream.{fmt}"), "--protocol", protocol,
                 "--out", str(r)]) == 0

    def body(p):
        return [ln for ln in p.read_text(encoding="utf-8").splitlines()
                if ln and not ln.startswith("#")]
    sim, red = body(s / "readings.csv"), body(r)
    assert red[0] == sim[0] and len(red) == len(sim) > 1
    cols = sim[0].split(",")
    for a, b in zip(red[1:], sim[1:]):
        ra, rb = dict(zip(cols, a.split(","))), dict(zip(cols, b.split(",")))
        assert ra["test"] == "tilt_estimate"
        for c in ("series", "round", "orientation", "table_deg"):
            assert ra[c] == rb[c], (c, a, b)
        # the virtual bench's mark sits in the times' 1 ns digit (gonio.formats.watermark)
        assert abs(float(ra["time_s"]) - float(rb["time_s"])) <= 1e-6, (a, b)
        # zeroing/reading found from the samples, the bench's planned on its grid: ≤ 1 count
        assert abs(float(ra["gyro_counts"]) - float(rb["gyro_counts"])) <= 1.0, (a, b)
    outs = []
    for p in (r, s / "readings.csv"):
        buf = io.StringIO()
        with redirect_stdout(buf):
            assert main(["tilt-estimate", str(p), "--json"]) == 0
        outs.append(json.loads(buf.getvalue()))
    # one count in a few thousand moves ψ by far less than its own standard uncertainty
    assert outs[0]["tilt_deg"] == pytest.approx(outs[1]["tilt_deg"], abs=outs[1]["u_tilt_deg"])
    assert outs[0]["n_positions"] == outs[1]["n_positions"] == len(sim) - 1
