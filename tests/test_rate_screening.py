"""Screening of rate readings (issue 24): damaged files a laboratory really produces — a typo
in the output, the rate, the temperature or the time of one reading, a planned point
missing — written from ``gonio simulate --spec …`` output (:func:`gonio.pipeline.dispatch.simulate`,
the function the command runs) into tmp_path, are set aside or named by line in
``results.json`` and on the certificate, for JJF 1535 and IEC 62047-20; the clean file
gives no finding.
"""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

from gonio.errors import GonioError

from gonio.pipeline.coverage import reduced_protocol
from gonio.pipeline.dispatch import calibrate as calibrate_file
from gonio.pipeline.dispatch import simulate as simulate_files
from gonio.specs import get


def _rows(path):
    text = path.read_text(encoding="utf-8").splitlines(keepends=True)
    head = [i for i, s in enumerate(text) if not s.startswith("#")][0]
    header = next(csv.reader([text[head]]))
    return text, head, header


def _edit(src, dst, pick, change):
    """Copy ``src`` to ``dst`` changing the first data row ``pick(row)`` selects by
    ``change(row)``; returns that row's line number (1-based, as the findings count)."""
    text, head, header = _rows(src)
    for i in range(head + 1, len(text)):
        row = dict(zip(header, next(csv.reader([text[i]]))))
        if pick(row):
            change(row)
            buf = io.StringIO()
            csv.writer(buf, lineterminator="\n").writerow([row[h] for h in header])
            text[i] = buf.getvalue()
            dst.write_text("".join(text), encoding="utf-8")
            return i + 1
    raise AssertionError("no row picked")


def _drop(src, dst, pick) -> int:
    text, head, header = _rows(src)
    keep = text[:head + 1] + [s for s in text[head + 1:]
                              if not pick(dict(zip(header, next(csv.reader([s])))))]
    dst.write_text("".join(keep), encoding="utf-8")
    return len(text) - len(keep)


@pytest.fixture(scope="module", params=("jjf1535-2015", "iec62047-20"))
def simulated(request, tmp_path_factory):
    spec = request.param
    tmp = tmp_path_factory.mktemp(spec)
    proto = reduced_protocol(spec, tmp / "p.toml", {"arw" if spec.startswith("jjf") else "noise":
                                                    {"samples": 3000}})
    files = simulate_files(spec, tmp / "sim", protocol=str(proto), seed=77)
    return spec, proto, files["readings"], tmp


def _findings(spec, readings, proto):
    r = get(spec).calibrate(str(readings), str(proto))
    js = r.to_json()
    return r, js["findings"]


@pytest.fixture(scope="module")
def clean(simulated):
    """(result, findings) of the clean simulated file, calibrated once per specification for
    the tests that compare a damaged copy with it (read only)."""
    spec, proto, readings, _ = simulated
    return _findings(spec, readings, proto)


def test_clean_file_has_no_finding(simulated, clean):
    _, found = clean
    # a clean simulated file with every test (IEC: the 5.3.3.6 visits give the noise items'
    # temperature line, so no noise-temperature finding either) has no finding at all
    assert found == []


def _sf_point(row, spec):
    return row["test"] == "scale_factor" and row["run"] == "0" and row["role"] == "rate" \
        and abs(float(row["rate_dps"]) - (10.0 if spec.startswith("jjf") else 60.0)) < 1e-9


@pytest.mark.parametrize("column", ("output", "rate_dps", "temperature_c", "time_s"))
def test_a_typo_in_any_column_is_set_aside_by_line(simulated, clean, column):
    spec, proto, readings, tmp = simulated

    seen = []

    def pick(row):                                                # the 3rd row of the point
        if _sf_point(row, spec):
            seen.append(row)
        return len(seen) == 3 and seen[-1] is row

    def change(row):
        v = float(row[column])
        row[column] = repr({"output": v + 9.0, "rate_dps": v * 10, "temperature_c": v + 50,
                            "time_s": v + 1000.0}[column])

    bad = tmp / f"typo-{column}.csv"
    line = _edit(readings, bad, pick, change)
    if column == "time_s":
        # a time that jumps ahead and back breaks the samples' order: the reader refuses the
        # file naming the next line (the jump's return) and the column, before any screening
        with pytest.raises(GonioError) as exc:
            _findings(spec, bad, proto)
        assert exc.value.line in (line, line + 1) and exc.value.column == "time_s"
        return
    r_clean, _ = clean
    r, found = _findings(spec, bad, proto)
    hit = [f for f in found if f["line"] == line]
    assert hit and hit[0]["action"] == "set_aside" and hit[0]["column"] == column, found
    assert all(f["line"] == line for f in found if f["action"] == "set_aside"), found
    # set aside: the scale factor is the clean file's up to the one sample less
    assert r.items["scale_factor"].value == pytest.approx(r_clean.items["scale_factor"].value,
                                                          rel=1e-4)
    assert "set aside" in r.to_json()["extra"]["screening"]


def test_a_set_point_typo_in_a_segment_s_first_row_is_no_missing_point(simulated):
    """The first row of a point written with another rate (100 -> 10 by a lost digit): that
    row is set aside, and the point, which its other rows measured, is not called missing
    (the completeness check read each segment's first row as its setting)."""
    spec, proto, readings, tmp = simulated

    def change(row):
        row["rate_dps"] = repr(float(row["rate_dps"]) * 10)

    bad = tmp / "typo-first-row.csv"
    line = _edit(readings, bad, lambda row: _sf_point(row, spec), change)
    r, found = _findings(spec, bad, proto)
    assert any(f["line"] == line and f["action"] == "set_aside" for f in found), found
    assert not [f for f in found if f["code"] == "programme-point-missing"], found


def test_missing_programme_point_is_named_and_on_the_certificate(simulated):
    spec, proto, readings, tmp = simulated
    bad = tmp / "missing.csv"
    assert _drop(readings, bad, lambda row: _sf_point(row, spec)) > 0
    rate = "10" if spec.startswith("jjf") else "60"
    out = tmp / "cal-missing"
    result, paths = calibrate_file(bad, out, protocol=str(proto))
    js = json.loads(paths["results"].read_text(encoding="utf-8"))
    miss = [f for f in js["findings"] if f["code"] == "programme-point-missing"]
    assert any(f"rate_dps = {rate}" in f["message"] and "scale_factor run 0" in f["message"]
               for f in miss), js["findings"]
    assert all(f["action"] == "flagged" for f in miss)
    assert "planned point(s) missing" in js["extra"]["screening"]
    html = next(p for k, p in paths.items() if str(p).endswith(".html"))
    page = html.read_text(encoding="utf-8")
    assert "Screening of the readings" in page and f"rate_dps = {rate}" in page


def test_a_point_missing_from_a_later_run_is_drawn_against_that_run_s_rates(simulated):
    """A point dropped from the last calibration run (not the first) leaves that run's
    residuals one shorter than the first run's rates: the certificate's input–output figure
    draws each run's residuals against its own rates (was an internal error, exit 1, or the
    residuals paired with the wrong rates)."""
    spec, proto, readings, tmp = simulated
    if not spec.startswith("jjf"):
        pytest.skip("IEC 62047-20 5.1.3.1 fits one line through every run's points")
    text, head, header = _rows(readings)
    runs = sorted({dict(zip(header, next(csv.reader([s]))))["run"] for s in text[head + 1:]
                   if dict(zip(header, next(csv.reader([s]))))["test"] == "scale_factor"})
    last = runs[-1]
    rate = 10.0 if spec.startswith("jjf") else 60.0
    bad = tmp / "missing-last.csv"
    assert _drop(readings, bad, lambda row: row["test"] == "scale_factor" and row["run"] == last
                 and row["role"] == "rate" and abs(float(row["rate_dps"]) - rate) < 1e-9) > 0
    result, paths = calibrate_file(bad, tmp / "cal-missing-last", protocol=str(proto))
    js = json.loads(paths["results"].read_text(encoding="utf-8"))
    assert any(f["code"] == "programme-point-missing" and f"run {last}" in f["message"]
               for f in js["findings"]), js["findings"]
    assert any(str(p).endswith(".pdf") for p in paths.values()), paths
    from gonio.report.rate_figures import _io_points
    line = _io_points(result.item("scale_factor"))
    for rates, residuals in line[4]:
        assert len(rates) == len(residuals)
    assert len(runs) > 1
    assert len(line[4][-1][0]) == len(line[4][0][0]) - 1
    assert rate not in set(np.round(line[4][-1][0], 9))


def test_one_missing_sample_is_a_named_gap_not_half_a_record_set_aside(simulated):
    # a logger that drops one sample leaves every later row on the grid, one step further:
    # a fit t₀ + i·Δt by row index set aside every row after the gap (review of stop 28)
    spec, proto, readings, tmp = simulated
    text, head, header = _rows(readings)
    rows = [dict(zip(header, next(csv.reader([s])))) for s in text[head + 1:]]
    seg = {}
    for i, row in enumerate(rows):
        seg.setdefault((row["test"], row["run"], row["step"]), []).append(i)
    longest = max(seg.values(), key=len)
    gone = longest[len(longest) // 2]
    bad = tmp / "gap.csv"
    bad.write_text("".join(text[:head + 1 + gone] + text[head + 2 + gone:]), encoding="utf-8")
    _, found = _findings(spec, bad, proto)
    assert not [f for f in found if f["action"] == "set_aside"], found
    gaps = [f for f in found if f["code"] == "time-gap"]
    # the row after the dropped one now sits on the dropped one's line
    assert len(gaps) == 1 and gaps[0]["line"] == head + 2 + gone, found
    assert gaps[0]["action"] == "flagged" and gaps[0]["message"].startswith("1 sample(s)")


def test_a_run_entered_with_the_wrong_sign_is_refused_by_line(simulated, tmp_path):
    # every rate of one scale-factor run sign-flipped: averaged in, K came out a third of
    # the true one (K = 2.00 ± 17 for 6.00) with no word (review of stop 28)
    spec, proto, readings, _ = simulated
    text, head, header = _rows(readings)
    first = None
    for i in range(head + 1, len(text)):
        row = dict(zip(header, next(csv.reader([text[i]]))))
        if row["test"] == "scale_factor" and row["run"] == "1" and row["role"] == "rate":
            first = first or i + 1
            row["rate_dps"] = repr(-float(row["rate_dps"]))
            buf = io.StringIO()
            csv.writer(buf, lineterminator="\n").writerow([row[h] for h in header])
            text[i] = buf.getvalue()
    bad = tmp_path / "flipped.csv"
    bad.write_text("".join(text), encoding="utf-8")
    with pytest.raises(GonioError, match="sign differs") as exc:
        _findings(spec, bad, proto)
    assert exc.value.line == first and exc.value.column == "rate_dps"


# --------------------------------------------------------------- issue 24, review of r-jjf
# A record full of spikes (±1000 in the output of a bias/static record gave B_s = 48 ± 9 °/h
# for 19 with no finding): each spike is set aside by line while they are few, the record
# refused when they are many, also when each spike alone stays under the row limit.

def _longest(text, head, header):
    seg: dict = {}
    for i in range(head + 1, len(text)):
        row = dict(zip(header, next(csv.reader([text[i]]))))
        if row["test"] != "vibration":
            seg.setdefault((row["test"], row["run"], row["step"]), []).append(i)
    return max(seg.values(), key=len)


def _spiked(readings, dst, every, amp):
    """``readings`` with ±``amp`` added to the output of every ``every``-th row of its
    longest record (alternating sign); returns the spiked lines (1-based)."""
    text, head, header = _rows(readings)
    rows = _longest(text, head, header)
    hit = rows[5::every]
    for n, i in enumerate(hit):
        row = dict(zip(header, next(csv.reader([text[i]]))))
        row["output"] = repr(float(row["output"]) + (amp if n % 2 else -amp))
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow([row[h] for h in header])
        text[i] = buf.getvalue()
    dst.write_text("".join(text), encoding="utf-8")
    return [i + 1 for i in hit], len(rows)


def _third_point_row(spec):
    """(pick, seen): ``pick`` selects the third row of the scale-factor point; ``seen`` the
    rows of that point it has passed."""
    seen: list = []

    def pick(row):
        if _sf_point(row, spec):
            seen.append(row)
        return len(seen) == 3 and seen[-1] is row
    return pick, seen


def test_a_record_full_of_spikes_is_refused_naming_the_first(simulated, tmp_path):
    spec, proto, readings, _ = simulated
    lines, n = _spiked(readings, tmp_path / "dense.csv", 10, 1000.0)     # 10 % of the rows
    assert n >= 200
    with pytest.raises(GonioError, match="damaged") as exc:
        _findings(spec, tmp_path / "dense.csv", proto)
    assert exc.value.line == lines[0] and exc.value.column == "output"


def test_dense_spikes_under_the_row_limit_are_refused_by_the_tail_rule(simulated, tmp_path):
    # each spike 6.5 robust σ (under the 8σ row limit, over the 5σ tail): 10 % of the rows
    from gonio.formats.rate_readings import read_rate_readings
    from gonio.specs._rate_family.screening import hampel_residuals
    spec, proto, readings, _ = simulated
    text, head, header = _rows(readings)
    df = read_rate_readings(readings).data
    rows = _longest(text, head, header)
    first = dict(zip(header, next(csv.reader([text[rows[0]]]))))
    y = df[(df["test"] == first["test"]) & (df["run"].astype(str) == first["run"])
           & (df["step"].astype(str) == first["step"])]["output"].to_numpy(float)
    d, lim = hampel_residuals(y)
    sigma = float(np.median(lim)) / 8.0                 # the robust σ the limit is made of
    _spiked(readings, tmp_path / "tail.csv", 10, 6.5 * sigma)
    with pytest.raises(GonioError, match="beyond 5 robust σ"):
        _findings(spec, tmp_path / "tail.csv", proto)


def test_sparse_spikes_are_set_aside_by_line_and_stated(simulated, clean, tmp_path):
    spec, proto, readings, _ = simulated
    bad = tmp_path / "sparse.csv"
    lines, n = _spiked(readings, bad, 97, 1000.0)                         # ≈ 1 %
    assert len(lines) >= 2
    result, paths = calibrate_file(bad, tmp_path / "cal", protocol=str(proto))
    js = json.loads(paths["results"].read_text(encoding="utf-8"))
    out = [f for f in js["findings"] if f["code"] == "output-outlier"]
    assert sorted(f["line"] for f in out) == lines and all(
        f["action"] == "set_aside" and f["column"] == "output" for f in out), js["findings"]
    assert f"{len(lines)} reading(s) set aside" in js["extra"]["screening"]
    clean = clean[0]
    for key, it in result.items.items():          # nothing of the spikes reaches an item
        if it.measured and clean.items[key].measured and it.uncertainty is not None:
            assert abs(it.value - clean.items[key].value) <= 0.5 * it.uncertainty.U, key
    html = next(p for p in paths.values() if str(p).endswith(".html"))
    page = html.read_text(encoding="utf-8")
    assert "Screening of the readings" in page and str(lines[0]) in page


@pytest.mark.parametrize("column", ("test", "run", "step", "role"))
def test_a_typo_in_a_label_column_is_set_aside_by_line(simulated, tmp_path, column):
    # a reading moved by a typo into a segment of its own was a rate point of one sample
    spec, proto, readings, _ = simulated
    seen = []

    def pick(row):
        if _sf_point(row, spec):
            seen.append(row)
        return len(seen) == 3 and seen[-1] is row

    def change(row):
        row[column] = {"test": "bias", "run": "7",
                       "step": str(int(row["step"]) + 50), "role": "rest"}[column]

    bad = tmp_path / f"label-{column}.csv"
    line = _edit(readings, bad, pick, change)
    _, found = _findings(spec, bad, proto)
    aside = [f for f in found if f["action"] == "set_aside"]
    assert [(f["line"], f["column"]) for f in aside] == [(line, column)], found


def test_a_setting_where_the_segment_has_none_is_set_aside(simulated, tmp_path):
    spec, proto, readings, _ = simulated
    pick, _ = _third_point_row(spec)          # its supply_set_v is blank in both formats

    line = _edit(readings, tmp_path / "set.csv", pick,
                 lambda row: row.__setitem__("supply_set_v", "5.5"))
    _, found = _findings(spec, tmp_path / "set.csv", proto)
    assert [(f["line"], f["column"]) for f in found if f["action"] == "set_aside"] == \
        [(line, "supply_set_v")], found


def test_a_late_sample_is_set_aside_and_a_duplicated_one_refused(simulated, tmp_path):
    spec, proto, readings, _ = simulated
    pick, seen = _third_point_row(spec)

    def late(row):                              # 0.4 of a sampling step after its time
        step = float(seen[-1]["time_s"]) - float(seen[-2]["time_s"])
        row["time_s"] = repr(float(row["time_s"]) + 0.4 * step)

    line = _edit(readings, tmp_path / "late.csv", pick, late)
    _, found = _findings(spec, tmp_path / "late.csv", proto)
    late = [f for f in found if f["action"] == "set_aside"]
    assert [(f["line"], f["column"], f["code"]) for f in late] == \
        [(line, "time_s", "time-departs")], found
    text, head, header = _rows(readings)
    dup = text[:line] + [text[line - 1]] + text[line:]
    (tmp_path / "dup.csv").write_text("".join(dup), encoding="utf-8")
    with pytest.raises(GonioError, match="duplicated") as exc:
        _findings(spec, tmp_path / "dup.csv", proto)
    assert exc.value.line == line + 1 and exc.value.column == "time_s"


def _bias_record(y, temperature=None):
    """A bias record of one segment in the rate readings' columns (the row rules' input)."""
    import pandas as pd

    n = len(y)
    return pd.DataFrame({"test": "bias", "run": 1, "step": 1, "line": np.arange(2, n + 2),
                         "time_s": np.arange(n) * 1.0, "rate_dps": 0.0,
                         "temperature_c": temperature if temperature is not None else 25.0,
                         "output": y})


@pytest.mark.parametrize("sigma_lsb", (0.5, 0.6, 0.7))
def test_coarsely_quantised_clean_record_is_not_refused(sigma_lsb):
    """Review finding: at 0.5–0.7 LSB of noise most residuals are exactly 0, the median |d|
    collapsed to 0 and the 3-quanta floor made every 2-quanta residual a '5σ' tail: a clean
    record was refused as damaged (5 of 5 seeds). Now no finding at all."""
    from gonio.specs._rate_family.screening import screen_rows

    for seed in range(5):
        rng = np.random.default_rng(seed)
        y = np.round(rng.normal(0.0, sigma_lsb, 3600)) * 1e-3 + 2.5
        assert screen_rows(_bias_record(y)) == [], (sigma_lsb, seed)


def test_coarsely_quantised_record_with_spikes_is_still_caught():
    from gonio.specs._rate_family.screening import screen_rows

    rng = np.random.default_rng(3)
    y = np.round(rng.normal(0.0, 0.6, 3600)) * 1e-3 + 2.5
    bad = rng.choice(3600, 40, replace=False)
    y[bad] += rng.choice([-1.0, 1.0], 40)                 # ±1 V spikes, 1.1 % of the rows
    f = screen_rows(_bias_record(y))
    assert {x.line - 2 for x in f if x.action == "set_aside"} == set(bad.tolist())


def test_a_slow_temperature_sensor_sets_no_output_aside():
    """Review finding: temperature logged on every 10th row set the 30 rows that HAVE it aside
    (10 % of the output). A measured column's blank/extra value is now flagged only; a tie
    (half the rows) is no finding."""
    from gonio.specs._rate_family.screening import apply, screen_rows

    rng = np.random.default_rng(1)
    y = rng.normal(2.5, 1e-3, 300)
    temp = np.full(300, np.nan)
    temp[::10] = 25.0
    df = _bias_record(y, temp)
    f = screen_rows(df)
    assert f and all(x.action == "flagged" and x.column == "temperature_c" for x in f)
    assert len(apply(df, f)) == 300
    temp = np.full(300, np.nan)
    temp[::2] = 25.0                                        # half and half: no finding
    assert screen_rows(_bias_record(y, temp)) == []
