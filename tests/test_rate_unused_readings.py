"""The rows a rate specification's screening sets aside are listed in results.json's
``unused_readings`` (JJF 1535 and IEC 62047-20): a damaged file written from ``gonio
simulate`` output — one reading's output slipped by a digit, one scale-factor step logged at
a mistyped rate on every row — is calibrated with ``python -m gonio calibrate``, and the list
names exactly the lines damaged (read back from the file), each with its test, run, step, the
column judged and the finding's message, and the certificate counts those rows; the clean
file's list is empty. (A duplicated row is refused by the reader,
tests/test_rate_screening.py, so none is ever set aside.)
"""

from __future__ import annotations

import csv
import html
import io
import json
import re
from pathlib import Path

import pytest

from tests.test_rate_record_interval import _calibrate, _split
from tests.test_rate_screening import _edit, simulated  # noqa: F401  (both specifications)


def _point_rate(spec) -> float:
    """The scale-factor rate whose first step is logged at a mistyped rate."""
    return 10.0 if spec.startswith("jjf") else 60.0


def _mistyped_step(src, dst, spec) -> tuple[tuple, list[int]]:
    """``src`` with every row of the first scale-factor step at ``_point_rate`` logged at 1.1
    times it, written to ``dst``; returns the step's (test, run, step) and its lines."""
    rate = _point_rate(spec)
    text, head, header, rows = _split(src)
    first = next(r for r in rows if r["test"] == "scale_factor" and r["role"] == "rate"
                 and abs(float(r["rate_dps"]) - rate) < 1e-9)
    key = (first["test"], first["run"], first["step"])
    lines = []
    for i, r in enumerate(rows):
        if (r["test"], r["run"], r["step"]) == key:
            r["rate_dps"] = repr(rate * 1.1)
            buf = io.StringIO()
            csv.writer(buf, lineterminator="\n").writerow([r[h] for h in header])
            text[head + 1 + i] = buf.getvalue()
            lines.append(head + 2 + i)
    dst.write_text("".join(text), encoding="utf-8")
    return key, lines


def _outlier(src, dst, spec, avoid) -> int:
    """``src`` with the output of the third row of the first scale-factor rate step other than
    ``avoid`` (a (test, run, step)) raised by 9 (a slipped digit), written to ``dst``; returns
    its line."""
    seen = []

    def pick(row):
        if row["test"] == "scale_factor" and row["role"] == "rate" and \
                (row["test"], row["run"], row["step"]) != avoid and \
                abs(float(row["rate_dps"]) - _point_rate(spec)) > 1e-9:
            if seen and (seen[0]["run"], seen[0]["step"]) != (row["run"], row["step"]):
                return False
            seen.append(row)
        return len(seen) == 3 and seen[-1] is row

    return _edit(src, dst, pick, lambda row: row.__setitem__(
        "output", repr(float(row["output"]) + 9.0)))


def _results(src, out, proto):
    p = _calibrate(src, out, proto)
    assert p.returncode == 0, p.stderr[-2000:]
    return (json.loads((out / "results.json").read_text(encoding="utf-8")),
            (out / "summary.txt").read_text(encoding="utf-8"))


def test_the_clean_file_lists_no_unused_reading(simulated):
    spec, proto, readings, tmp = simulated
    js, summary = _results(readings, tmp / "cal-unused-clean", proto)
    assert js["unused_readings"] == [] and js["findings"] == []
    assert "readings not used" not in summary


def test_every_row_set_aside_is_listed_with_its_line(simulated):
    import jsonschema

    spec, proto, readings, tmp = simulated
    step_key, step_lines = _mistyped_step(readings, tmp / "unused-step.csv", spec)
    bad = tmp / "unused-both.csv"
    spike = _outlier(tmp / "unused-step.csv", bad, spec, step_key)
    assert spike not in step_lines and len(step_lines) >= 3
    js, summary = _results(bad, tmp / "cal-unused-both", proto)
    jsonschema.validate(js, json.loads((Path(__file__).resolve().parents[1] / "docs" /
                                        "results.schema.json").read_text(encoding="utf-8")))
    un = js["unused_readings"]
    # exactly the lines damaged, one entry each, in the file's order
    assert [u["line"] for u in un] == sorted(step_lines + [spike]), un
    # each entry names the row as the file holds it (read back from the damaged file)
    text = bad.read_text(encoding="utf-8").splitlines()
    header = next(csv.reader([text[_split(bad)[1]]]))
    for u in un:
        row = dict(zip(header, next(csv.reader([text[u["line"] - 1]]))))
        assert (u["test"], str(u["run"]), str(u["step"])) == \
            (row["test"], row["run"], row["step"]), u
        assert u["file"] is not None and Path(u["file"]).name == bad.name, u
        assert u["column"] == ("output" if u["line"] == spike else "rate_dps"), u
    # the reason is the finding's message: the outlier's own, the step's for each of its rows
    by_code = {f["code"]: f for f in js["findings"] if f["action"] == "set_aside"}
    assert set(by_code) == {"output-outlier", "off-programme"}, js["findings"]
    assert by_code["output-outlier"]["line"] == spike
    assert by_code["off-programme"]["line"] == min(step_lines)
    for u in un:
        code = "output-outlier" if u["line"] == spike else "off-programme"
        assert u["reason"] == by_code[code]["message"], u
    assert f"readings not used: {len(step_lines) + 1}" in summary
    # the certificate counts the rows set aside, the step's each (not one per finding)
    page = html.unescape(re.sub(r"<[^>]+>", " ", (tmp / "cal-unused-both" /
                                                  "certificate.html").read_text(encoding="utf-8")))
    assert f"{len(step_lines) + 1} reading(s) set aside" in " ".join(page.split())


@pytest.mark.parametrize("damage", ("outlier", "step"))
def test_each_damage_alone_lists_only_its_rows(simulated, damage):
    spec, proto, readings, tmp = simulated
    bad = tmp / f"unused-{damage}.csv"
    if damage == "step":
        _, want = _mistyped_step(readings, bad, spec)
    else:
        want = [_outlier(readings, bad, spec, None)]
    js, _ = _results(bad, tmp / f"cal-unused-{damage}", proto)
    assert [u["line"] for u in js["unused_readings"]] == want, js["unused_readings"]
