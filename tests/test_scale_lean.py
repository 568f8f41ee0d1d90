"""Issue 16's speed and memory work changes no result: the noise bootstrap's piecewise
synthesis equals the whole-array formulas; Parquet is written plain + LZ4 and a file encoded
any other way reads the same; the stream checks' one-pass screens still catch every bad
value (and pass good values whose sum overflows); a validation batch runs its numerical
libraries on one thread."""

from __future__ import annotations

import math

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from gonio.analysis.noise import simulate_noise
from gonio.errors import GonioError
from gonio.formats.streams import PARQUET_OPTIONS, StreamFile, read_stream, write_stream

MD = {"counter_bits": "16", "counter_signed": "true",
      "nominal_scale_factor_counts_per_deg": "1000.0"}


def _whole_array(n, tau0, Q, N, B, K, R, seed, input_type):
    """The five-term model as whole-array expressions (the formulas before the piecewise
    rewrite), drawing in the same order: the reference the synthesis must equal bit for bit."""
    rng = np.random.default_rng(seed)
    y = np.zeros(n)
    if N:
        y += N / math.sqrt(tau0) * rng.standard_normal(n)
    if B:
        from scipy.fft import next_fast_len

        ntot = next_fast_len(4 * n, real=True)
        f = np.fft.rfftfreq(ntot, tau0)
        spec = rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)
        spec[0] = 0.0
        h = B * B / math.pi
        spec[1:] *= np.sqrt(h / f[1:] * ntot / (4.0 * tau0)) * np.sinc(f[1:] * tau0)
        y += np.fft.irfft(spec, ntot)[:n]
    if K:
        y += K * math.sqrt(tau0) * np.cumsum(rng.standard_normal(n))
    if R:
        y += R * tau0 * (np.arange(n) + 0.5)
    if Q:
        q = Q * rng.standard_normal(n + 1)
        y += np.diff(q) / tau0
    if input_type == "rate":
        return y
    x = np.empty(n + 1)
    x[0] = 0.0
    np.cumsum(y * tau0, out=x[1:])
    return x


@pytest.mark.parametrize("terms", [dict(N=0.3), dict(K=0.02), dict(Q=0.1), dict(R=0.01),
                                   dict(B=0.05),
                                   dict(Q=0.1, N=0.2, B=0.05, K=0.02, R=0.001)])
@pytest.mark.parametrize("n", [7, 300_001])           # one piece, and more than one
def test_noise_synthesis_equals_the_whole_array_formulas(terms, n):
    args = {k: terms.get(k, 0.0) for k in ("Q", "N", "B", "K", "R")}
    for kind in ("rate", "angle"):
        got = simulate_noise(n, 0.01, rng=11, input_type=kind, **args)
        ref = _whole_array(n, 0.01, seed=11, input_type=kind, **args)
        assert got.shape == ref.shape
        assert np.array_equal(got, ref), (terms, n, kind)


def _stream(n=3000):
    t = np.arange(n) * 0.01
    table = np.clip((t - 10.0) * 20.0, 0.0, 90.0)
    counts = np.round(table * 1000.0 + 3 * np.arange(n)).astype(np.int64)
    return t, counts, table


def test_parquet_is_plain_lz4_and_other_encodings_read_the_same(tmp_path):
    t, c, table = _stream()
    p = write_stream(tmp_path / "s.parquet", t, c, table, MD)
    meta = pq.ParquetFile(p).metadata
    col = meta.row_group(0).column(0)
    assert col.compression.startswith("LZ4") and PARQUET_OPTIONS["compression"] == "lz4"
    assert "RLE_DICTIONARY" not in col.encodings and not col.has_dictionary_page
    # the same table re-encoded the usual way (dictionary + snappy) reads identically
    other = tmp_path / "snappy.parquet"
    pq.write_table(pq.read_table(p), other, compression="snappy", use_dictionary=True)
    a, b = read_stream(p), read_stream(other)
    assert a.metadata == b.metadata == {k: v for k, v in MD.items()}
    for name in ("time_s", "gyro_counts", "table_deg"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert np.array_equal(a.gyro_counts, c)          # wrapped on disk, unwrapped back


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_values_whose_sum_overflows_pass_and_bad_values_in_a_later_block_fail(tmp_path, fmt):
    n = 4000
    t = np.arange(n) * 0.01
    temp = np.full(n, 1e308)                     # finite, but the block's sum overflows
    c = np.arange(n, dtype=np.int64)
    p = write_stream(tmp_path / f"ok.{fmt}", t, c, None, {"counter_bits": "64"},
                     temperature_c=temp)
    sf = StreamFile(p, block_bytes=1 << 12) if fmt == "csv" else StreamFile(p)
    assert sum(ch.time_s.size for ch in sf.chunks()) == n
    # a non-finite temperature deep in the file is still found at its row
    bad = temp.copy()
    bad[3210] = np.inf
    path = tmp_path / f"bad.{fmt}"
    if fmt == "csv":
        write_stream(path, t, c, None, {"counter_bits": "64"}, temperature_c=temp)
        lines = path.read_text().splitlines(keepends=True)
        row = lines[2 + 3210].split(",")
        row[2] = "inf\n"
        lines[2 + 3210] = ",".join(row)
        path.write_text("".join(lines))
        sf = StreamFile(path, block_bytes=1 << 12)
    else:
        tab = pa.table({"time_s": t, "gyro_counts": c, "temperature_c": bad})
        pq.write_table(tab.replace_schema_metadata({"counter_bits": "64"}), path,
                       row_group_size=1000)
        sf = StreamFile(path)
    with pytest.raises(GonioError) as exc:
        for _ in sf.chunks():
            pass
    assert exc.value.column == "temperature_c"
    if fmt == "csv":
        assert exc.value.line == 2 + 3210 + 1
    else:
        assert "data row 3211" in exc.value.message


def test_too_fast_step_is_still_caught_after_the_screen(tmp_path):
    t, c, table = _stream()
    c = c.copy()
    c[2500:] += 20_000                      # 20000 counts in 0.01 s at K = 1000: 2000 °/s
    p = write_stream(tmp_path / "fast.csv", t, c, None,
                     {"counter_bits": "64", "nominal_scale_factor_counts_per_deg": "1000.0"})
    with pytest.raises(GonioError) as exc:
        for _ in StreamFile(p, block_bytes=1 << 12).chunks():
            pass
    assert "above the plausible bound" in exc.value.message
    assert exc.value.line == 3 + 2500 + 1       # 2 metadata lines, header, then row 2500


def test_a_validation_batch_runs_blas_on_one_thread():
    from threadpoolctl import threadpool_info

    from gonio.pipeline.validate import WORKER_THREADS, worker_threads

    text = worker_threads()
    assert WORKER_THREADS == 1
    if threadpool_info():                   # numpy's and scipy's OpenBLAS, OpenMP…
        assert all(part.rsplit(":", 1)[1].strip() == "1" for part in text.split(", "))
