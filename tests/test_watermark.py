"""The virtual bench's watermark in its readings' values (gonio.formats.watermark,
docs/formats.md#watermark): every file ``gonio simulate`` writes carries it, for all four
specifications; it survives deleting every ``#`` line, deleting and reordering rows, a
renamed file and a spreadsheet's re-save ('%.15g' of every number); it moves no measured
value at all (the mark is in the times' nanosecond, for every specification) and a time by
at most one unit of its ninth decimal; and
readings not written by the bench (the repository's hand-made files, random real-looking
readings, the bench's own readings perturbed by noise) are flagged at most at the test's
stated level, checked against scipy.stats.binomtest. mark_text, column by column, writes the
bytes of its former row-by-row form (kept here as the reference) on every specification's
readings and on made-up texts with every odd cell.
"""

from __future__ import annotations

import re
import subprocess
import sys
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binomtest

from gonio.formats.provenance import readings_provenance
from gonio.formats.watermark import (ALPHA, MIN_CELLS, TIME_COLUMN, detect, detect_text,
                                     mark_text, marked_columns)
from gonio.formats import watermark as wm
from tests.own_readings import own_text, resaved, unmarked

HERE = Path(__file__).resolve().parent
PINS = HERE / "data" / "pins"
RUNS = (("ogam-draft", "ogam-draft-small.toml"), ("jjf1535-2015", "jjf1535-2015-small.toml"),
        ("iec62047-20", "iec62047-20-small.toml"), ("triad-alignment", None))


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """{spec: folder} of one simulation per specification (seed 5), and a second run of
    each to the same seed (determinism)."""
    out = {}
    for spec, proto in RUNS:
        for run in ("a", "b"):
            d = tmp_path_factory.mktemp(f"{spec}-{run}")
            p = [] if proto is None else ["--protocol", str(PINS / proto)]
            r = subprocess.run([sys.executable, "-m", "gonio", "simulate", "--spec", spec, *p,
                                "--seed", "5", "--out", str(d / "sim")], capture_output=True,
                               text=True)
            assert r.returncode == 0, r.stderr
            out[(spec, run)] = d / "sim"
    return out


def _data_lines(text: str) -> tuple[list[str], list[str]]:
    lines = [x for x in text.splitlines(keepends=True) if not x.startswith("#")]
    return lines[:1], lines[1:]


@pytest.mark.parametrize("spec", [r[0] for r in RUNS])
def test_marked_and_survives_edits(spec, simulated, tmp_path):
    sim = simulated[(spec, "a")]
    files = sorted(sim.glob("*.csv"))
    assert files
    for f in files:
        text = f.read_text(encoding="utf-8")
        a, b = simulated[(spec, "b")] / f.name, f
        assert a.read_bytes() == b.read_bytes(), f"{spec}: same seed, other bytes ({f.name})"
        full = detect(f)
        assert full["virtual"] and full["matching"] == full["cells"] >= 27, (f.name, full)
        head, rows = _data_lines(text)
        rng = np.random.default_rng(11)
        kept = [rows[i] for i in sorted(rng.choice(len(rows), size=max(MIN_CELLS, len(rows) * 3 // 4),
                                                   replace=False))]
        edited = "# serial: LAB-1\n" + "".join(head) + "".join(kept[::-1])   # rows reversed
        moved = tmp_path / f"renamed-{f.stem}.txt"
        moved.write_text(edited, encoding="utf-8")
        got = detect(moved)
        assert got["virtual"], (spec, f.name, got)
        assert readings_provenance(moved)["evidence"] == ["watermark"]
        # the laboratory's own recording of the same values (parities of its own)
        assert not detect_text(unmarked(text))["virtual"]
        assert not detect_text(own_text(text))["virtual"]
        assert detect_text(own_text(text, unmark=False))["virtual"]
        # a spreadsheet's re-save of the laboratory's copy (60.0 → 60, 2501.70 → 2501.7,
        # 17 significant digits → 15) keeps every cell's mark
        again = detect_text(resaved(own_text(text, unmark=False)))
        assert again["virtual"] and again["matching"] == again["cells"] == full["cells"], again
        assert resaved(text) != text


def _cells(text: str):
    head, rows = _data_lines(text)
    header = head[0].rstrip("\n").split(",")
    cols = list(marked_columns(header))
    return [(r.rstrip("\n").split(",")[j]) for r in rows for j in cols]


@pytest.mark.parametrize("spec", [r[0] for r in RUNS])
def test_values_move_by_at_most_one_unit_of_the_last_digit(spec, simulated):
    """Marking the laboratory-like recording of a simulated file again moves each measured
    value by at most one unit of its last written digit (of the column's decimals where the
    bench writes them padded), never any other cell; marking is idempotent."""
    for f in sorted(simulated[(spec, "a")].glob("*.csv")):
        text = f.read_text(encoding="utf-8")
        assert mark_text(text) == text
        plain = unmarked(text)
        again = mark_text(plain)
        assert detect_text(again)["virtual"]
        before, after = _cells(plain), _cells(again)
        assert len(before) == len(after)
        moved = 0
        for x, y in zip(before, after):
            if x == "" or x == y:
                continue
            unit = Decimal(1).scaleb(Decimal(y.split("e")[0]).as_tuple().exponent)
            assert abs(Decimal(x) - Decimal(y)) <= unit, (x, y)
            moved += Decimal(x) != Decimal(y)
        assert moved > 0
        # the other columns are untouched
        strip = [re.sub(r"[^,]*", "", x) for x in again.splitlines()]
        assert strip == [re.sub(r"[^,]*", "", x) for x in plain.splitlines()]


def test_real_files_are_not_flagged():
    """The repository's hand-made and laboratory-style readings files: none is flagged."""
    files = sorted((HERE / "data").glob("*.csv"))
    assert len(files) >= 4
    for f in files:
        got = detect(f)
        assert not got["virtual"], (f.name, got)


def _lab_like(rng, n: int, resolution_decimals: int) -> str:
    """A real-looking rate readings text: a bias record quantised to the output's
    resolution, noise of a real gyro, and set points."""
    head = "# serial: LAB-7\ntest,run,step,role,time_s,rate_dps,output\n"
    out = 2501.5 + rng.normal(0.0, 0.2, n)
    return head + "".join(f"bias,0,0,record,{600 + i},0,{o:.{resolution_decimals}f}\n"
                          for i, o in enumerate(out))


def test_false_positive_rate_on_real_looking_readings():
    """400 real-looking files (random outputs at four resolutions, random constant columns):
    none flagged, and the test's p-values are those of Binomial(n, 1/2) — the share below
    0.05 is within a 99.9 % binomial interval of 5 % — checked by scipy.stats.binomtest.
    (The times are the marked cells, one per distinct row context: coarse outputs repeat, and
    a file of fewer than MIN_CELLS contexts is not tested.)"""
    rng = np.random.default_rng(2026)
    small = 0
    trials = 0
    for t in range(400):
        decimals = int(rng.integers(0, 4))
        text = _lab_like(rng, int(rng.integers(30, 300)), decimals)
        got = detect_text(text)
        assert not got["virtual"], got
        if got["cells"] < MIN_CELLS:       # too few distinct rows to decide on
            assert got["p_value"] is None, got
            continue
        trials += 1
        # each test (the times; the outputs' mark of gonio 230195c0 and earlier) by scipy,
        # the file's p the smallest × the number of tests (Bonferroni)
        refs = [binomtest(t["matching"], t["cells"], 0.5, alternative="two-sided").pvalue
                for t in got["tests"] if t["cells"] >= MIN_CELLS]
        for t in got["tests"]:
            if t["cells"] >= MIN_CELLS:
                assert t["p_value"] == pytest.approx(binomtest(
                    t["matching"], t["cells"], 0.5, alternative="two-sided").pvalue, rel=1e-9)
        assert got["p_value"] == pytest.approx(min(1.0, len(got["tests"]) * min(refs)),
                                               rel=1e-9)
        small += got["p_value"] <= 0.05
    ci = binomtest(small, trials, 0.05).proportion_ci(0.999)
    assert ci.low <= 0.05 <= ci.high or small / trials < 0.05, small
    # a constant output (every value even) is no easier to flag
    const = "t,output\n" + "".join(f"{i},2500.00\n" for i in range(500))
    assert not detect_text(const)["virtual"]


def test_perturbed_bench_readings_are_not_flagged(simulated):
    """The bench's readings with a gyro's noise added to every measured value (normal,
    sd 5 steps of the output's resolution, re-quantised) and times of its own clock (at the
    millisecond): not flagged. (The bench's own nanosecond times beside them keep the mark
    wherever a row's values are unchanged: such readings are still the bench's.)"""
    rng = np.random.default_rng(8)
    text = unmarked((simulated[("jjf1535-2015", "a")] / "readings.csv")
                    .read_text(encoding="utf-8"))
    head, rows = _data_lines(text)
    header = head[0].rstrip("\n").split(",")
    j = header.index("output")
    noisy = []
    for r in rows:
        c = r.rstrip("\n").split(",")
        if c[j]:
            c[j] = f"{float(c[j]) + rng.normal(0.0, 0.05):.2f}"
        noisy.append(",".join(c) + "\n")
    got = detect_text("".join(head + noisy))
    assert not got["virtual"] and got["cells"] > 1000, got


def test_level_and_smallest_file():
    """The level is the two-sided binomial test's: 21 matching cells of 21 reach it (and 0
    of 21), 20 of 20 do not."""
    assert binomtest(21, 21, 0.5, alternative="two-sided").pvalue <= ALPHA
    assert binomtest(0, 21, 0.5, alternative="two-sided").pvalue <= ALPHA
    assert binomtest(20, 20, 0.5, alternative="two-sided").pvalue > ALPHA
    assert MIN_CELLS == 21


@pytest.mark.parametrize("spec", [r[0] for r in RUNS])
def test_mark_moves_no_measured_value(spec, simulated):
    """Every specification's mark is in ``time_s``'s nanosecond digit only: marking the
    laboratory-like recording of a simulated file (times at the millisecond) leaves every
    count, angle, output, standard deviation and set point as it was, and moves each time by
    at most 1 ns (a rate or triad time only later), so the mark can change no certified
    number."""
    for f in sorted(simulated[(spec, "a")].glob("*.csv")):
        text = f.read_text(encoding="utf-8")
        plain = unmarked(text)
        again = mark_text(plain)
        assert detect_text(again)["virtual"] and not detect_text(plain)["virtual"]
        head, rows_a = _data_lines(plain)
        _, rows_b = _data_lines(again)
        header = head[0].rstrip("\n").split(",")
        assert list(marked_columns(header).values()) == [TIME_COLUMN]
        j = header.index(TIME_COLUMN)
        moved = 0
        for a, b in zip(rows_a, rows_b):
            ca, cb = a.rstrip("\n").split(","), b.rstrip("\n").split(",")
            assert ca[:j] + ca[j + 1:] == cb[:j] + cb[j + 1:], (a, b)
            d = Decimal(cb[j]) - Decimal(ca[j])
            assert abs(d) <= Decimal("1e-9"), (a, b)
            if spec != "ogam-draft":
                assert d >= 0, (a, b)
            moved += d != 0
        assert moved > 0, f.name


def test_short_values_are_padded_and_exact_columns_left_alone():
    """A value written with fewer digits than its column moves by one unit of the column's
    last decimal (2.0 among 13-decimal values: by 10⁻¹³, not 0.1); a column with no decimal
    at all (an exact 0.0 or integer output) is not marked."""
    rng = np.random.default_rng(4)
    rows = [f"{i},{rng.normal(10, 1):.13f},0.0,{int(rng.integers(0, 9))}" for i in range(60)]
    rows[7] = "7,2.0,0.0,3"
    text = "step,out_x,sd_x,out_y\n" + "\n".join(rows) + "\n"
    got = mark_text(text)
    a, b = _data_lines(text)[1], _data_lines(got)[1]
    for x, y in zip(a, b):
        cx, cy = x.rstrip("\n").split(","), y.rstrip("\n").split(",")
        assert abs(Decimal(cx[1]) - Decimal(cy[1])) <= Decimal("1e-13"), (x, y)
        assert len(cy[1].partition(".")[2]) == 13
        assert cx[2:] == cy[2:]                  # sd_x 0.0 and the integer out_y unmarked
    assert abs(Decimal(b[7].split(",")[1]) - 2) <= Decimal("1e-13")
    assert detect_text(got)["virtual"] and detect_text(got)["cells"] == 60


def test_optical_real_looking_readings_are_not_flagged():
    """400 real-looking optical files (times on a millisecond clock, counts of a real
    counter): none flagged, and the p-values are Binomial(n, 1/2)'s (scipy.stats.binomtest)."""
    rng = np.random.default_rng(2027)
    small = 0
    for t in range(400):
        n = int(rng.integers(30, 300))
        times = np.cumsum(rng.integers(500, 20000, n)) / 1000.0
        body = "".join(f"angle_deviation,1,{i + 1},60.0,up,{float(times[i])!r},{i * 30.0},"
                       f"{int(rng.integers(0, 10**8))},\n" for i in range(n))
        got = detect_text("test,series,round,rate_dps,orientation,time_s,table_deg,"
                          "gyro_counts,gyro_deg\n" + body)
        assert not got["virtual"] and got["cells"] == n, got
        ref = binomtest(got["matching"], got["cells"], 0.5, alternative="two-sided").pvalue
        assert got["p_value"] == pytest.approx(ref, rel=1e-9)
        small += got["p_value"] <= 0.05
    ci = binomtest(small, 400, 0.05).proportion_ci(0.999)
    assert ci.low <= 0.05 <= ci.high or small / 400 < 0.05, small


def test_detect_reads_block_by_block(tmp_path):
    """A file longer than MAX_CELLS cells is tested block by block: a second block of
    fewer than MIN_CELLS cells, then bytes that are no CSV at all, change nothing; the
    first block decides. (Its memory and time: benchmarks/watermark_memory.py.)"""
    from gonio.formats.watermark import MAX_CELLS
    rng = np.random.default_rng(5)
    body = "".join(f"bias,0,{i},record,{i},0,{rng.normal(2500, 1):.2f}\n"   # distinct rows
                   for i in range(MAX_CELLS + 10))
    p = tmp_path / "r.csv"
    p.write_bytes(("test,run,step,role,time_s,rate_dps,output\n" + body).encode()
                  + b"\xff\x00" * 1000 + b"\n1,2,3\n")
    got = detect(p)
    assert got["cells"] == MAX_CELLS and not got["virtual"] and got["blocks"] == 2


def _unmarked_rate_rows(rng, start: int, n: int) -> list[str]:
    """Real-looking rate rows (times on a 1 ns grid, not marked), distinct contexts."""
    return [f"bias,0,{i},record,{i + rng.integers(0, 10**9) / 1e9:.9f},0,"
            f"{rng.normal(2500, 1):.2f}" for i in range(start, start + n)]


@pytest.mark.parametrize("n_marked", [3000, 20000])
def test_marked_rows_after_many_real_ones_are_found(n_marked):
    """Simulated rows appended after 30 000 real-looking ones (more than one block), or put
    among them, are found: the block that holds them is tested on its own, not diluted by
    the file; the real rows alone, and ten other real-looking files of two blocks, are not
    flagged."""
    from gonio.formats.watermark import mark_text
    header = "test,run,step,role,time_s,rate_dps,output"
    rng = np.random.default_rng(n_marked)
    real = _unmarked_rate_rows(rng, 0, 30000)
    fake = _unmarked_rate_rows(rng, 30000, n_marked)
    marked = mark_text("\n".join([header, *fake]) + "\n").splitlines()[1:]
    assert marked != fake and len(marked) == n_marked
    assert not detect_text("\n".join([header, *real]) + "\n")["virtual"]
    for rows in (real + marked, real[:25000] + marked + real[25000:]):
        got = detect_text("\n".join([header, *rows]) + "\n")
        assert got["virtual"] and got["blocks"] >= 2, got
    flagged = sum(detect_text("\n".join([header, *_unmarked_rate_rows(
        np.random.default_rng(100 + s), 0, 25000)]) + "\n")["virtual"] for s in range(10))
    assert flagged == 0


def test_stream_times_follow_the_cell_definition():
    """:func:`mark_stream_times` (vectorised, the stream writer's) gives every time the
    parity of the bit :func:`cell_bit` gives its row's other cells in their canonical form,
    moving it by at most 1.5 ns and keeping the times increasing; integer and float columns,
    −0.0, a huge value and a table at rest (repeated angles) alike."""
    from gonio.formats.watermark import TIME_DECIMALS, canonical, cell_bit, mark_stream_times
    rng = np.random.default_rng(12)
    n = 3000
    t = 1000.0 + np.arange(n) / 1000.0
    counts = np.cumsum(rng.integers(-80, 80, n))
    table = np.repeat(rng.normal(0.0, 100.0, n // 100), 100)
    table[:5], table[5:10] = -0.0, 1e20
    got = mark_stream_times(t, [counts, table])
    assert np.all(np.abs(got - t) <= 1.5e-9) and np.all(np.diff(got) > 0)
    for i in range(n):
        bit = cell_bit(TIME_COLUMN, f"{canonical(int(counts[i]))}\x1f{canonical(float(table[i]))}")[0]
        assert round(got[i] * 10**TIME_DECIMALS) % 2 == bit, i


def _reference_mark_text(text: str) -> str:
    """mark_text as it was before it went column by column (gonio's text of 2026-12-02), row
    by row, on the module's unchanged definition of the mark (cell_bit, canonical, _value,
    _q, _fixed, column_decimals): the reference of the byte-identity tests below."""
    lines = text.splitlines(keepends=True)
    rows = wm._iter_rows(lines)
    first = next(rows, None)
    if first is None:
        return text
    header = [c.strip().lstrip("\ufeff") for c in first[1]]
    cols = wm.marked_columns(header)
    if not cols:
        return text
    optical = any(n in wm.OPTICAL_COLUMNS for n in header)
    rows = [(i, c) for i, c in rows if len(c) == len(header) and '"' not in lines[i]]
    values = {j: [wm._value(c[j]) for _, c in rows] for j in cols}
    decimals = {j: wm.column_decimals(name, values[j]) for j, name in cols.items()}
    marked = set(cols)
    for r, (i, cells) in enumerate(rows):
        ctx = "\x1f".join(wm.canonical(c) for j, c in enumerate(cells) if j not in marked)
        for j, name in cols.items():
            d = decimals[j]
            v = values[j][r]
            if d <= 0 or v is None:
                continue
            q = wm._q(v, d)
            bit, up = wm.cell_bit(name, ctx)
            if q % 2 != bit:
                q += 1 if up or q == 0 or not optical else -1
            if name != wm.TIME_COLUMN or Decimal(q).scaleb(-d) != Decimal(cells[j].strip()):
                cells[j] = wm._fixed(q, d)
        end = lines[i][len(lines[i].rstrip("\r\n")):]
        lines[i] = ",".join(cells) + end
    return "".join(lines)


@pytest.mark.parametrize("spec", [r[0] for r in RUNS])
def test_same_bytes_as_the_row_by_row_marking(spec, simulated):
    """mark_text (column by column: times in integer arrays, contexts made at once) writes
    the bytes of its former row-by-row form (:func:`_reference_mark_text`) on every readings
    file of the specification as written, unmarked (times at the millisecond), re-saved and
    with CRLF line ends (a file's first 4000 lines: the reference is slow)."""
    files = sorted(simulated[(spec, "a")].glob("*.csv"))
    assert files
    for f in files:
        text = "".join(f.read_text(encoding="utf-8").splitlines(keepends=True)[:4000])
        plain = unmarked(text)
        for variant in (text, plain, resaved(plain), plain.replace("\n", "\r\n")):
            assert mark_text(variant) == _reference_mark_text(variant)
        assert mark_text(plain) != plain


def _odd_time(rng) -> str:
    """A time cell of every kind the row form took."""
    kind = int(rng.integers(0, 16))
    x = float(rng.uniform(0, 2000))
    return [f"{x:.3f}", f"{x:.9f}", f"{x:.12f}", f"{x!r}", f"{x:.6e}", f"{-x:.4f}", "-0", "0",
            "0.0", f" {x:.2f} ", "", "nan", "inf", "1e400", f"+{x:.1f}", "١٢.٥",
            f"{int(x)}", ".5", "5.", "-0.000000001", "1e-12", f"{x * 1e7:.9f}",
            "123456789.123456789", "1234567890.5", "12345678901234567890", "x1", "--1",
            "1.2.3", "+", "\x00"][kind + int(rng.integers(0, 15))]


def test_same_bytes_on_odd_cells():
    """Made-up texts with every odd cell, line and file the row form met: the same bytes."""
    rng = np.random.default_rng(41)
    for trial in range(60):
        optical = trial % 3 == 0
        head = ("test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg"
                if optical else "test,run,step,role,time_s,rate_dps,output")
        width = head.count(",") + 1
        out = ["# bench: virtual\n", "\ufeff" + head + "\n" if trial % 5 == 0 else head + "\n"]
        for i in range(int(rng.integers(1, 80))):
            cells = [str(int(rng.integers(0, 3))) for _ in range(width)]
            cells[0] = ["bias", "", " 60.0", "6E1", "-0.0", "+x"][int(rng.integers(0, 6))]
            cells[head.split(",").index("time_s")] = _odd_time(rng)
            cells[-1] = f"{rng.normal(2500, 1):.{int(rng.integers(0, 4))}f}"
            line = ",".join(cells)
            roll = rng.random()
            if roll < 0.04:
                line = line + ",extra"
            elif roll < 0.08:
                line = '"quoted",' + line.split(",", 1)[1]
            elif roll < 0.1:
                line = "# a comment, here"
            elif roll < 0.12:
                line = "   "
            out.append(line + ["\n", "\r\n", "\r"][int(rng.integers(0, 3))])
        text = "".join(out)
        assert mark_text(text) == _reference_mark_text(text), trial
        assert mark_text(text.rstrip("\r\n")) == _reference_mark_text(text.rstrip("\r\n"))
    for text in ("", "# only a comment\n", "a,b\n1,2\n", "time_s\n", "time_s\n1.5\n",
                 "time_s\n1.5\n2\n", "time_s,x\n", '"time_s",x\n1,2\n3,4\n'):
        assert mark_text(text) == _reference_mark_text(text), repr(text)


def test_same_bytes_in_a_file_without_times():
    """A rate or triad file without times (its measured columns marked at their decimals),
    with blank, short and exponent cells: the same bytes."""
    rng = np.random.default_rng(43)
    rows = [f"{i},{rng.normal(10, 1):.{int(rng.integers(0, 14))}f},{rng.normal(2, 1):.3e},"
            f"{['', '0.0', 'x', '2'][i % 4]}" for i in range(300)]
    text = "step,out_x,sd_x,output\n" + "\n".join(rows) + "\n"
    assert mark_text(text) == _reference_mark_text(text)


def test_short_times_are_their_exact_values():
    """The column path's times in ns are the texts' exact values (Decimal), which are their
    '%.15g' values (the row form's); any other text is left to the cell path."""
    rng = np.random.default_rng(44)
    texts = []
    for _ in range(20000):
        whole = str(int(rng.integers(0, 10 ** int(rng.integers(1, 10)))))
        frac = "".join(rng.choice(list("0123456789"), int(rng.integers(0, 10))))
        t = f"{['', '-', '+'][int(rng.integers(0, 3))]}{whole}{'.' if frac or rng.random() < .2 else ''}{frac}"
        texts.append(t)
    texts += ["", "-", ".", "1.2.3", " 1", "1e3", "١", "1234567890", "0.0000000001",
              "123456789.1234567", "12345678.1234567", "-0", "\x00", "5\x00"]
    short, q = wm._short_times_q(texts)
    for t, s, v in zip(texts, short.tolist(), q.tolist()):
        if not s:
            continue
        exact = Decimal(t).scaleb(9)
        assert exact == int(exact) == v, t
        assert Decimal("%.15g" % float(t)).scaleb(9) == exact, t
    assert short[:20000].mean() > 0.5
    assert [t for t, s in zip(texts[20000:], short[20000:]) if s] == ["12345678.1234567", "-0"]
