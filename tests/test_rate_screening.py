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


def test_clean_file_has_no_finding(simulated):
    spec, proto, readings, _ = simulated
    _, found = _findings(spec, readings, proto)
    assert found == []


def _sf_point(row, spec):
    return row["test"] == "scale_factor" and row["run"] == "0" and row["role"] == "rate" \
        and abs(float(row["rate_dps"]) - (10.0 if spec.startswith("jjf") else 60.0)) < 1e-9


@pytest.mark.parametrize("column", ("output", "rate_dps", "temperature_c", "time_s"))
def test_a_typo_in_any_column_is_set_aside_by_line(simulated, column):
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
    r_clean, _ = _findings(spec, readings, proto)
    r, found = _findings(spec, bad, proto)
    hit = [f for f in found if f["line"] == line]
    assert hit and hit[0]["action"] == "set_aside" and hit[0]["column"] == column, found
    assert all(f["line"] == line for f in found if f["action"] == "set_aside"), found
    # set aside: the scale factor is the clean file's up to the one sample less
    assert r.items["scale_factor"].value == pytest.approx(r_clean.items["scale_factor"].value,
                                                          rel=1e-4)
    assert "set aside" in r.to_json()["extra"]["screening"]


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
