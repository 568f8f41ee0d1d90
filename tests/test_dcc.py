"""The Digital Calibration Certificate (PTB DCC 3.3.0): schema-valid, numbers equal to
results.json through the certificate's rounding rule, D-SI units parsed by a D-SI parser,
conformity equal to the closed form.

The schema set is the offline copy the repository carries, ``tests/data/dcc-3.3.0``
(or ``$GONIO_DCC_SCHEMA_DIR``), loaded with xmlschema with remote access refused. D-SI unit
strings are parsed with the ``dsiunits`` package (PTB's D-SI parser; test-only dependency).
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import replace
from pathlib import Path

import pytest
from lxml import etree
from scipy.stats import norm

from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.pipeline.dispatch import decide_conformity
from gonio.specs.ogam_draft.outputs import write_calibration
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.formats.lab import load_lab
from gonio.report.header import certificate_id
from gonio.report.dcc import DCC_NS, SI_NS
from gonio.specs.ogam_draft.dcc import dcc_bytes
from gonio.report.i18n import display, last_digit_unit, parse_display
from gonio.resources import protocols_dir
from tests.own_readings import own_metadata

NS = {"dcc": DCC_NS, "si": SI_NS}
SMALL = {
    "protocol": {"name": "small", "specification": "JJF xxxx 光学陀螺测角仪校准规范 (draft for comment)"},
    "session": {"static_s": 30.0},
    "scale_factor": {"rest_s": 15.0, "rounds": [{"stop_deg": 180.0}, {"stop_deg": 360.0}]},
    "zero_stability": {"readings": 4, "interval_s": 20.0},
    "angle_deviation": {"series": 2, "rest_s": 15.0,
                        "rounds": [{"stop_deg": 120.0 * i} for i in range(1, 4)]},
    "rate_consistency": {"rates_dps": [30.0, 60.0], "rest_s": 15.0},
    "pointing_consistency": {"orientations": ["up", "north"], "rest_s": 15.0},
}


@pytest.fixture(scope="module")
def schema(dcc_schema):
    return dcc_schema


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("dcc")
    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=20.0), seed=7)
    write_session(session, d)
    result = calibrate(d / "readings.csv", proto, static_record=session.static_record)
    write_calibration(result, d)
    lab = load_lab(protocols_dir() / "lab-example.toml")
    res = decide_conformity(result, lab).to_json()   # the pipeline decides; the DCC renders
    docs = {"lab": dcc_bytes(res, lab=lab, cert_id=certificate_id(res, lab)),
            "virtual": dcc_bytes(res, lab=None, cert_id=certificate_id(res, None))}
    return {"res": res, "lab": lab, "docs": docs,
            "results": json.loads((d / "results.json").read_text())}


def lookup(res, src):
    x = res
    for part in src.split("."):
        x = x[int(part)] if isinstance(x, list) else x[part]
    return x


def test_valid_against_dcc_330_schema(run, schema):
    for name, doc in run["docs"].items():
        errors = list(schema.iter_errors(doc.decode("utf-8")))
        assert not errors, (name, str(errors[0])[:500])


def test_broken_instances_are_rejected(run, schema):
    root = etree.fromstring(run["docs"]["lab"])
    uid = root.find(".//dcc:coreData/dcc:uniqueIdentifier", NS)
    uid.getparent().remove(uid)
    assert not schema.is_valid(etree.tostring(root).decode())
    root = etree.fromstring(run["docs"]["lab"])
    root.find(".//dcc:statement/dcc:conformity", NS).text = "probably"
    assert not schema.is_valid(etree.tostring(root).decode())
    root = etree.fromstring(run["docs"]["lab"])
    root.find(".//si:real/si:value", NS).text = "0,15"
    assert not schema.is_valid(etree.tostring(root).decode())
    root = etree.fromstring(run["docs"]["lab"])
    root.set("schemaVersion", "3.2.1")
    assert not schema.is_valid(etree.tostring(root).decode())


def _numbers(doc: bytes):
    """(src, rule, xml text) of every si:value and list entry, by the comment before it."""
    root = etree.fromstring(doc)
    out = []
    for c in root.iter(etree.Comment):
        m = re.match(r" src=(\S+) rule=(\S+) ", c.text)
        if m:
            real = c.getnext()
            out.append((m.group(1), m.group(2), real.find("si:value", NS).text))
            continue
        m = re.match(r" src-list=(.+) rule=(\S*) ", c.text)
        if m:
            values = c.getnext().find("si:valueXMLList", NS).text.split()
            srcs = m.group(1).split()
            assert len(values) == len(srcs)
            out += [(s, m.group(2), v) for s, v in zip(srcs, values) if s != "-"]
    return out


def _as_display(text: str) -> str:
    m = re.fullmatch(r"(-?[\d.]+)e(-?\d+)", text)
    if m:
        sup = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
        return f"{m.group(1)}×10{m.group(2).translate(sup)}"
    return text


def test_every_number_equals_results_json(run):
    res = run["results"]
    U = res["extra"]["uncertainty"]["U_arcsec"]
    nums = _numbers(run["docs"]["lab"])
    assert len(nums) > 25
    srcs = {s for s, _, _ in nums}
    for must in ("items.angle_deviation.details.max_abs_arcsec",
                 "items.angle_deviation.details.signed_extreme_arcsec",
                 "items.scale_factor.value", "items.zero_stability.value",
                 "items.repeatability.value", "items.rate_consistency.value",
                 "items.pointing_consistency.value",
                 "items.angle_deviation.details.table.0.E_arcsec"):
        assert must in srcs, must
    for src, rule, text in nums:
        v = lookup(res, src)
        shown = display(rule, v, U).lstrip("±+")
        assert _as_display(text) == shown, (src, rule, text, shown)
        x = parse_display(_as_display(text))
        vv = abs(v) if rule.startswith("pmdec") else v
        assert abs(x - vv) <= 0.5 * last_digit_unit(_as_display(text)) + 1e-9 * abs(vv), src
    # E's one statement: the 95 % coverage interval of max|E_i| (no U, no k), its ends
    # results.json's interval rounded outwards
    root = etree.fromstring(run["docs"]["lab"])
    e = root.find(".//dcc:result[@id='result-angle_deviation']", NS)
    assert e.find(".//si:expandedMU", NS) is None
    lo, hi = res["items"]["angle_deviation"]["uncertainty"]["interval"]
    if res["extra"]["uncertainty"].get("u_c_certified", True) is False:
        # each point's U = k·u + b: no standard uncertainty of E, so no coverageIntervalMU
        # (it requires a valueStandardMU); the ends as a list, p in the quantity's name
        assert e.find(".//si:coverageIntervalMU", NS) is None
        assert e.find(".//si:valueStandardMU", NS) is None
        lst = [q for q in e.iterfind(".//dcc:quantity", NS)
               if q.get("refType") == "basic_measurementUncertainty"]
        assert len(lst) == 1
        shown_lo, shown_hi = map(float, lst[0].find(".//si:valueXMLList", NS).text.split())
        assert "p = 95 %" in lst[0].find(".//dcc:content", NS).text
    else:
        mu = e.find(".//si:coverageIntervalMU", NS)
        shown_lo = float(mu.find("si:intervalMin", NS).text)
        shown_hi = float(mu.find("si:intervalMax", NS).text)
        assert float(mu.find("si:coverageProbability", NS).text) == 0.95
    assert shown_lo <= lo <= shown_lo + 0.01 and hi <= shown_hi <= hi + 0.01
    assert shown_lo <= res["items"]["angle_deviation"]["details"]["max_abs_arcsec"] <= shown_hi


def test_dsi_units_parse(run):
    dsi = pytest.importorskip("dsi_unit", reason="pip install dsiunits (test-only)")
    root = etree.fromstring(run["docs"]["lab"])
    units = {u.text for u in root.iter(f"{{{SI_NS}}}unit", f"{{{SI_NS}}}unitXMLList")}
    assert {r"\arcsecond", r"\degree", r"\degree\hour\tothe{-1}", r"\one\degree\tothe{-1}",
            r"\percent", r"\ppm", r"\degreecelsius"} <= units
    for u in units:
        for one in u.split():
            assert dsi.DsiUnit(one).valid, one
    assert not dsi.DsiUnit(r"\arcsec").valid          # the parser can fail


def test_administrative_data_and_conformity(run):
    res = run["results"]
    lab = run["lab"]
    root = etree.fromstring(run["docs"]["lab"])
    t = lambda path: root.find(path, NS).text  # noqa: E731
    assert t(".//dcc:coreData/dcc:uniqueIdentifier") == lab["certificate"]["number"]
    assert t(".//dcc:coreData/dcc:beginPerformanceDate") == lab["certificate"]["date_of_calibration"]
    assert t(".//dcc:items/dcc:item/dcc:model") == lab["instrument"]["model"]
    assert t(".//dcc:item//dcc:identification/dcc:value") == lab["instrument"]["serial"]
    assert t(".//dcc:calibrationLaboratory//dcc:name/dcc:content") == lab["laboratory"]["name"]
    signers = [p.find("dcc:person/dcc:name/dcc:content", NS).text
               for p in root.iterfind(".//dcc:respPerson", NS)
               if p.find("dcc:mainSigner", NS).text == "true"]
    assert signers == [lab["signatory"]["approved_by"]]
    assert "光学陀螺测角仪校准规范" in t(".//dcc:statement[@id='specification']/dcc:norm")
    # conformity: E against ±0.5″, non-binary, w = U, outcome and p from the closed form
    y, U = res["items"]["angle_deviation"]["value"], res["extra"]["uncertainty"]["U_arcsec"]
    st = root.find(".//dcc:statement[@id='conformity-angle_deviation']", NS)
    expect = ("pass" if abs(y) <= 0.5 - U else "conditionalPass" if abs(y) <= 0.5
              else "conditionalFail" if abs(y) <= 0.5 + U else "fail")
    assert st.find("dcc:conformity", NS).text == expect
    u = res["extra"]["uncertainty"]["u_c_arcsec"]        # k = U/u_c (t95 of ν_eff, not always 2)
    p_c = norm.cdf((0.5 - y) / u) - norm.cdf((-0.5 - y) / u)
    q = {q.find("dcc:name/dcc:content", NS).text: float(q.find("si:real/si:value", NS).text)
         for q in st.iterfind("dcc:data/dcc:quantity", NS)}
    key = "specific false-accept probability" if expect in ("pass", "conditionalPass") \
        else "specific false-reject probability"
    want = 1 - p_c if key.endswith("accept probability") else p_c
    if res["items"]["angle_deviation"]["uncertainty"].get("k_source") == "max-abs-interval":
        # E stated by the interval of max|E_i|: no normal model, no probability stated
        assert not any(n.startswith("specific") for n in q), q
    else:
        assert q[key] == pytest.approx(want, rel=0.05, abs=1e-15)   # 2 significant digits
    assert q["lower specification limit"] == -0.5 and q["upper specification limit"] == 0.5
    # no limits, no statement
    virtual = etree.fromstring(run["docs"]["virtual"])
    assert virtual.find(".//dcc:statement/dcc:conformity", NS) is None
    assert virtual.find(".//dcc:statement[@id='virtual-bench']", NS) is not None


def test_performance_location_is_the_category_of_the_place_entered(run, schema, tmp_path):
    """dcc:performanceLocation takes one of the schema's categories: the one the laboratory
    file states (``[certificate] location``), valid against the schema for each, with the
    place itself as the statement 'place'; a virtual-bench example says 'other'; a category
    the schema does not know is refused when the laboratory file is read."""
    from gonio.errors import GonioError
    from gonio.formats.lab import LOCATIONS

    lab = run["lab"]
    # the same result as measured readings would give it (no virtual-bench metadata)
    res = dict(run["res"], provenance={"virtual": False, "bench": None, "seed": None,
                                       "generator": None, "evidence": []},
               metadata=own_metadata(run["res"]["metadata"]))
    enum = [e.get("value") for e in etree.parse(str(Path(__file__).parent / "data" / "dcc-3.3.0"
                                                    / "dcc.xsd")).iterfind(
        ".//{http://www.w3.org/2001/XMLSchema}simpleType[@name='stringPerformanceLocationType']"
        "//{http://www.w3.org/2001/XMLSchema}enumeration")]
    assert list(LOCATIONS) == enum
    for where in LOCATIONS:
        here = dict(lab, certificate=dict(lab["certificate"], location=where))
        doc = dcc_bytes(res, lab=here, cert_id="X-1")
        assert not list(schema.iter_errors(doc.decode("utf-8"))), where
        root = etree.fromstring(doc)
        assert root.find(".//dcc:coreData/dcc:performanceLocation", NS).text == where
        place = root.find(".//dcc:statement[@id='place']/dcc:declaration", NS)
        assert "".join(place.itertext()).strip() == lab["certificate"]["place"]
    assert etree.fromstring(dcc_bytes(res, lab=lab, cert_id="X-1")).find(
        ".//dcc:coreData/dcc:performanceLocation", NS).text == "laboratory"   # the default
    assert etree.fromstring(run["docs"]["lab"]).find(
        ".//dcc:coreData/dcc:performanceLocation", NS).text == "other"
    text = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    bad = tmp_path / "lab.toml"
    bad.write_text(text.replace('place = "Angle laboratory, room 101"',
                                'place = "Angle laboratory, room 101"\nlocation = "Wuxi"'),
                   encoding="utf-8")
    with pytest.raises(GonioError, match="certificate.location"):
        load_lab(bad)


def test_same_inputs_same_bytes(run):
    r = run["res"]
    assert dcc_bytes(r, lab=run["lab"], cert_id="X-1") == dcc_bytes(r, lab=run["lab"],
                                                                  cert_id="X-1")
