"""7.1 of two readings, from the outside: ``gonio simulate --protocol`` (7.1 at 180° and 360°)
then ``gonio calibrate``. No screening rule can judge two readings (the median rule: each
departs from their median by their MAD), so the certificate must say so rather than show K
and K_l as judged: a flagged ``readings-not-judged`` finding naming both lines, in
results.json, summary.txt, the certificate (en, zh) and the DCC, with what a typo does per ″
at the smaller stop. A 3° typo planted in the 180° reading passes every rule (exit 0) and
the statement stays; the K it moved is checked against the stated per-″ effect, computed here
from the counts (a second computation: K = mean of C_i/θ_i).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from gonio.cli import main

from tests._helpers import plant_71_counts

SMALL = Path(__file__).resolve().parent / "data" / "small-protocol.toml"
STATED = re.compile(r"readings at lines (\d+), (\d+) judged by no rule \(2 readings; the median "
                    r"rule needs 3\): a typo of any size in one of them would not have been "
                    r"seen; each ″ of it moves K by up to (\S+) ppm and K_l by up to (\S+) % "
                    r"\(line (\d+), (\S+)°\)")


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    out = tmp_path_factory.mktemp("two71")
    proto = out / "two.toml"
    text = SMALL.read_text(encoding="utf-8")
    old = "rounds = [{stop_deg = 120.0}, {stop_deg = 240.0}, {stop_deg = 360.0}]"
    assert text.count(old) == 1
    proto.write_text(text.replace(old, "rounds = [{stop_deg = 180.0}, {stop_deg = 360.0}]"),
                     encoding="utf-8")
    assert main(["simulate", "--protocol", str(proto), "--seed", "3", "--out",
                 str(out / "sim")]) == 0
    clean = out / "sim" / "readings.csv"
    # 3° at 180°: far beyond any threshold a rule would use, and seen by none
    line, typo = plant_71_counts(clean, out / "typo" / "readings.csv", 3 * 76435,
                                 stop_deg=180.0)
    return out, proto, clean, typo, line


def _run(src, proto, out, capsys, *extra):
    rc = main(["calibrate", str(src), "--protocol", str(proto), "--out", str(out), "--dcc",
               *extra])
    capsys.readouterr()
    assert rc == 0
    return json.loads((out / "results.json").read_text(encoding="utf-8"))


def test_two_readings_are_stated_as_judged_by_no_rule_everywhere(two, capsys):
    out, proto, clean, typo, line = two
    res = {}
    for name, src in (("clean", clean), ("typo", typo)):
        o = out / f"o_{name}"
        res[name] = r = _run(src, proto, o, capsys)
        fl = [f for f in r["findings"] if f["code"] == "readings-not-judged"
              and f["clause"] == "7.1"]
        assert len(fl) == 1 and fl[0]["action"] == "flagged" and fl[0]["clause"] == "7.1"
        m = STATED.search(fl[0]["message"])
        assert m, fl[0]["message"]
        assert (int(m.group(1)), int(m.group(2))) == (line, line + 1)
        assert int(m.group(5)) == line and float(m.group(6)) == 180.0
        # per ″ at 180° of 2 rounds: K by 1/(180 · 3600)/2, K_l by 1/(180 · 3600)
        # (printed to 2 significant digits)
        assert m.group(3) == f"{1e6 / (180 * 3600) / 2:.2g}"
        assert m.group(4) == f"{100.0 / (180 * 3600):.2g}"
        assert [f for f in r["findings"] if f["action"] != "flagged"] == []
        words = m.group(0)
        for f in ("summary.txt", "certificate.html", "certificate.dcc.xml"):
            assert words in (o / f).read_text(encoding="utf-8"), (name, f)
    # the 3° typo moved K by what the statement says a ″ does (K = (C_1/θ_1 + C_2/θ_2)/2)
    k0 = res["clean"]["items"]["scale_factor"]["value"]
    k1 = res["typo"]["items"]["scale_factor"]["value"]
    assert k1 - k0 == pytest.approx(3 * 76435 / 180.0 / 2, rel=1e-6)
    per = float(STATED.search(res["clean"]["findings"][0]["message"]).group(3))
    assert (k1 / k0 - 1.0) * 1e6 == pytest.approx(per * 3 * 3600, rel=0.02)


def test_the_chinese_certificate_states_it(two, capsys):
    out, proto, clean, *_ = two
    _run(clean, proto, out / "zh", capsys, "--lang", "zh")
    page = (out / "zh" / "certificate.html").read_text(encoding="utf-8")
    assert "未经任何规则判别（2 个读数；中位数规则至少需要 3 个）" in page
    assert "judged by no rule" not in page
