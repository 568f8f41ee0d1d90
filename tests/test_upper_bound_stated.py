"""Issue 25: a non-negative quantity whose U exceeds its value is stated with its upper bound
(gonio.result.statement.state) in every output. The optical draft's zero stability B_s of
a short 7.3 programme (four readings: ν_eff ≈ 1, k ≈ 12, U several times B_s) is such a
quantity: results.json carries ``nonnegative`` and ``upper_bound``, and the certificate
(HTML and PDF), summary.txt, the CLI's output and the DCC all print the same bound, which is
value + U rounded up at U's decimal place (never below the unrounded value + U)."""

from __future__ import annotations

import contextlib
import io
import json
import re
import math
import shutil
import subprocess
from dataclasses import replace
from decimal import Decimal

import pytest
from lxml import etree

from gonio.bench import load_bench, run_session, write_session
from gonio.protocol import parse_protocol
from gonio.report.dcc import DCC_NS, SI_NS

NS = {"dcc": DCC_NS, "si": SI_NS}


@pytest.fixture(scope="module")
def cal(tmp_path_factory):
    from gonio.cli.cmd_calibrate import show
    from gonio.pipeline.dispatch import calibrate
    from gonio.specs import get
    from tests.test_dcc import SMALL
    d = tmp_path_factory.mktemp("bound")
    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=20.0), seed=7)
    write_session(session, d)
    out = {}
    for lang in ("en", "zh"):
        result, _ = calibrate(d / "readings.csv", d / lang, spec_key="ogam-draft",
                              protocol=proto, dcc=True, lang=lang)
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):       # what gonio calibrate prints
            show(get("ogam-draft"), result, False, None, lang)
        out[lang] = {"dir": d / lang, "cli": buf.getvalue()}
    return out


def test_upper_bound_in_every_output(cal):
    o = cal["en"]["dir"]
    it = json.loads((o / "results.json").read_text())["items"]["zero_stability"]
    v, U = it["value"], it["uncertainty"]["U"]
    assert it["nonnegative"] is True and U > v       # the case of the rule
    b = it["upper_bound"]
    # the bound: value + U rounded up at U's decimal place (two significant digits of U)
    place = Decimal(repr(U)).adjusted() - 1
    step = 10.0 ** place
    assert v + U <= b + 1e-15 and b - (v + U) < step * 1.0001
    text = (f"{b:.{max(-place, 0)}f}")
    for where, t in (("summary.txt", (o / "summary.txt").read_text(encoding="utf-8")),
                     ("CLI", cal["en"]["cli"]),
                     ("HTML", (o / "certificate.html").read_text(encoding="utf-8"))):
        t = re.sub(r"<[^>]+>", "", t.replace("&nbsp;", " "))      # the HTML's number spans
        assert f"≤ {text}" in re.sub(r"\s+", " ", t), where
    if shutil.which("pdftotext"):
        pdf = subprocess.run(["pdftotext", str(o / "certificate.pdf"), "-"],
                             capture_output=True, text=True, check=True).stdout
        assert f"≤ {text}" in re.sub(r"\s+", " ", pdf)
    root = etree.parse(str(o / "certificate.dcc.xml")).getroot()
    q = root.find(".//dcc:result[@id='result-zero_stability']//dcc:quantity"
                  "[@refType='gonio_upperBound']", NS)
    assert q is not None and q.find("si:real/si:value", NS).text == text
    # the Chinese certificate states it in Chinese
    zh = (cal["zh"]["dir"] / "certificate.html").read_text(encoding="utf-8")
    assert "上限：≤\u00a0" in zh and not math.isnan(b)


def test_no_bound_where_U_is_below_the_value(cal):
    items = json.loads((cal["en"]["dir"] / "results.json").read_text())["items"]
    for key, it in items.items():
        if key != "zero_stability":
            assert "upper_bound" not in it or it["upper_bound"] is None, key
