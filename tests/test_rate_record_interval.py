"""Records at another sample interval than the protocol's, and a scale-factor step logged at a
rate the programme does not have, written from ``gonio simulate`` output and calibrated with
``python -m gonio calibrate``: a bias or static record kept at every other sample is refused
(exit 2, one line naming the file, line, column, the test and run and both intervals); a whole
step at a mistyped rate is set aside as off-programme, not fitted at that rate.
"""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.test_rate_screening import simulated  # noqa: F401  (the simulated files, both specs)


def _split(path):
    text = path.read_text(encoding="utf-8").splitlines(keepends=True)
    head = [i for i, s in enumerate(text) if not s.startswith("#")][0]
    header = next(csv.reader([text[head]]))
    rows = [dict(zip(header, next(csv.reader([s])))) for s in text[head + 1:]]
    return text, head, header, rows


def _keep(src, dst, keep):
    """``src`` without the data rows ``keep(i, row)`` rejects (i: the row's index)."""
    text, head, _, rows = _split(src)
    body = [s for i, (s, r) in enumerate(zip(text[head + 1:], rows)) if keep(i, r)]
    dst.write_text("".join(text[:head + 1] + body), encoding="utf-8")


def _calibrate(readings, out, proto):
    return subprocess.run([sys.executable, "-m", "gonio", "calibrate", str(readings), "--out",
                           str(out), "--protocol", str(proto)],
                          capture_output=True, text=True, timeout=600,
                          cwd=Path(__file__).resolve().parents[1])


def _half_rate(simulated, test, run, name):
    spec, proto, readings, tmp = simulated
    _, _, _, rows = _split(readings)
    picked = [i for i, r in enumerate(rows) if r["test"] == test and r["run"] == run]
    assert len(picked) > 20
    drop = set(picked[1::2])
    bad = tmp / name
    _keep(readings, bad, lambda i, r: i not in drop)
    return _calibrate(bad, tmp / ("cal-" + name), proto), bad


@pytest.mark.parametrize("test, run, step, want", [("static", "0", "0.2 s", "0.1 s"),
                                                   ("bias", "1", "2 s", "1 s")])
def test_a_record_at_half_the_sample_rate_is_refused(simulated, test, run, step, want):
    # was: certified (ARW +42 %, a bias stability of 20 s blocks under "10 s"), no finding
    p, bad = _half_rate(simulated, test, run, f"{test}-half.csv")
    assert p.returncode == 2, p.stderr[-2000:]
    err = p.stderr.strip()
    assert "Traceback" not in p.stderr and len(err.splitlines()) == 1, err
    assert str(bad) in err and "column time_s" in err
    assert f"{test} run {run}" in err and f"median time step is {step}" in err
    assert f"sample interval {want}" in err


def test_a_step_at_a_rate_not_in_the_programme_is_set_aside(simulated):
    # was: every row of one step at −1.1 °/s instead of −1 fitted at −1.1
    spec, proto, readings, tmp = simulated
    rate = 10.0 if spec.startswith("jjf") else 60.0
    _, _, _, rows = _split(readings)
    first = next(r for r in rows if r["test"] == "scale_factor" and r["role"] == "rate"
                 and abs(float(r["rate_dps"]) - rate) < 1e-9)
    key = (first["test"], first["run"], first["step"])
    text, head, header, _ = _split(readings)
    for i, r in enumerate(rows):
        if (r["test"], r["run"], r["step"]) == key:
            r["rate_dps"] = repr(rate * 1.1)
            text[head + 1 + i] = ",".join(r[h] for h in header) + "\n"
    typo, gone = tmp / "typo.csv", tmp / "gone.csv"
    typo.write_text("".join(text), encoding="utf-8")
    _keep(readings, gone, lambda i, r: (r["test"], r["run"], r["step"]) != key)
    values = []
    for src in (typo, gone):
        p = _calibrate(src, tmp / ("cal-" + src.stem), proto)
        assert p.returncode == 0, p.stderr[-2000:]
        values.append(json.loads((tmp / ("cal-" + src.stem) / "results.json").read_text(
            encoding="utf-8")))
    js = values[0]
    off = [f for f in js["findings"] if f["code"] == "off-programme"]
    assert len(off) == 1 and off[0]["action"] == "set_aside", js["findings"]
    assert f"scale_factor run {key[1]} step {key[2]}" in off[0]["message"]
    assert f"rate {rate * 1.1:g} °/s" in off[0]["message"]
    assert any(f["code"] == "programme-point-missing" and f"rate_dps = {rate:g}" in f["message"]
               for f in js["findings"])
    assert "not in the programme set aside" in js["extra"]["screening"]
    # the step is not fitted: the items are those of the file without it
    for k in ("scale_factor", "nonlinearity" if spec.startswith("jjf") else "linearity"):
        assert js["items"][k]["value"] == values[1]["items"][k]["value"], k
