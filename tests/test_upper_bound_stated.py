"""A non-negative quantity is never stated by an interval reaching below zero, and has one
statement in every output. The optical draft's zero stability B_s of a short 7.3 programme
(four readings: ν_eff ≈ 1, U several times B_s) is a dispersion: it is stated by its
one-sided χ² interval [0, s·√(ν/χ²_0.05,ν)] alone (no "± U", no k), results.json carries
``nonnegative`` and ``upper_bound`` (the interval's upper end, rounded up), and the
certificate (HTML and PDF), summary.txt, the CLI's output and the DCC all print the same
bound, computed here independently with scipy's χ² quantile."""

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

from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.protocol import parse_protocol
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
    from scipy.stats import chi2
    o = cal["en"]["dir"]
    it = json.loads((o / "results.json").read_text())["items"]["zero_stability"]
    unc = it["uncertainty"]
    v, U = it["value"], unc["U"]
    assert it["nonnegative"] is True and unc["k"] is None and unc["k_source"] == "chi-square"
    # the χ² limit of the stated ν (its integer part), independently of gonio
    nu = max(1, math.floor(unc["nu_eff"]))
    hi = v * math.sqrt(nu / chi2.ppf(0.05, nu))
    assert unc["interval"] == [0.0, pytest.approx(hi, rel=1e-12)]
    assert v + U == pytest.approx(hi, rel=1e-12)      # U: the guard band to the limit
    b = it["upper_bound"]
    # the bound: the limit rounded up at the place giving (limit − value) two digits
    place = Decimal(repr(hi - v)).adjusted() - 1
    step = 10.0 ** place
    assert hi <= b + 1e-15 and b - hi < step * 1.0001
    text = (f"{b:.{max(-place, 0)}f}")
    for where, t in (("summary.txt", (o / "summary.txt").read_text(encoding="utf-8")),
                     ("CLI", cal["en"]["cli"]),
                     ("HTML", (o / "certificate.html").read_text(encoding="utf-8"))):
        t = re.sub(r"<[^>]+>", "", t.replace("&nbsp;", " "))      # the HTML's number spans
        t = re.sub(r"\s+", " ", t)
        assert f"≤ {text}" in t, where
        assert "interval [0.000" not in t and "k = 12" not in t, where   # no second statement
    if shutil.which("pdftotext"):
        pdf = subprocess.run(["pdftotext", str(o / "certificate.pdf"), "-"],
                             capture_output=True, text=True, check=True).stdout
        assert f"≤ {text}" in re.sub(r"\s+", " ", pdf)
    root = etree.parse(str(o / "certificate.dcc.xml")).getroot()
    res = root.find(".//dcc:result[@id='result-zero_stability']", NS)
    assert res.find(".//dcc:quantity[@refType='gonio_upperBound']", NS) is None
    ci = res.find(".//si:coverageIntervalMU", NS)
    assert ci.find("si:intervalMax", NS).text == text
    assert float(ci.find("si:intervalMin", NS).text) == 0.0
    assert res.find(".//si:expandedMU", NS) is None
    # the Chinese certificate states it too
    zh = (cal["zh"]["dir"] / "certificate.html").read_text(encoding="utf-8")
    assert "≤\u00a0" in zh and not math.isnan(b)


def test_no_bound_where_U_is_below_the_value(cal):
    items = json.loads((cal["en"]["dir"] / "results.json").read_text())["items"]
    for key, it in items.items():
        u = it.get("uncertainty") or {}
        if key not in ("zero_stability", "repeatability") and not (   # R: a dispersion too
                it.get("nonnegative") and u.get("U") and u["U"] > it["value"]):
            assert "upper_bound" not in it or it["upper_bound"] is None, key
        if it.get("upper_bound") is not None and u.get("k") is not None:  # a range: [0, v + U]
            assert it["upper_bound"] >= it["value"] + u["U"] - 1e-12, key
