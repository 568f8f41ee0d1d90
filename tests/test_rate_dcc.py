"""The DCC of the rate-gyro certificates (JJF 1535-2015, IEC 62047-20): valid against the
DCC 3.3.0 schema set, every number equal to results.json's through the certificate's
display rule, every D-SI unit accepted by PTB's D-SI parser (``dsiunits``, test-only), the
not-measured items present with their reason, the settings as influence conditions, and
written by ``gonio calibrate --dcc`` in the staged output set.

The schema set and its offline loading are those of tests/test_dcc.py.
"""

from __future__ import annotations

import json
import math
import re

import pytest
from lxml import etree

from gonio.formats.rate_readings import RateReadings, read_rate_readings, write_rate_readings
from gonio.pipeline.coverage import reduced_protocol
from gonio.specs._rate_family.simulate import study_bench
from gonio.formats.lab import load_lab
from gonio.report.header import certificate_id
from gonio.report.dcc import DCC_NS, SI_NS
from gonio.report.i18n import display, last_digit_unit, parse_display
from gonio.report.stated import lookup
from gonio.report.rate_dcc import rate_dcc_bytes
from gonio.resources import protocols_dir
from gonio.specs import get


NS = {"dcc": DCC_NS, "si": SI_NS}
G_N = 9.80665                      # m/s², standard gravity (CGPM 1901), independent of gonio


@pytest.fixture(scope="module")
def schema(dcc_schema):
    return dcc_schema


def _simulate(spec_key, tmp, seed):
    mod = __import__(get(spec_key).calibrate.__module__, fromlist=["calibrate"])
    sim = __import__(mod.__name__ + ".simulate", fromlist=["simulate"])
    proto = reduced_protocol(spec_key, tmp / f"{spec_key}.toml",
                             {"g_sensitivity": {"samples": 20}}
                             if spec_key == "iec62047-20" else {})
    res = sim.simulate(study_bench(), str(proto), seed=seed, noise=True)
    path = write_rate_readings(res.data, res.metadata, tmp / f"{spec_key}.csv")
    return mod, proto, path, res


@pytest.fixture(scope="module", params=("jjf1535-2015", "iec62047-20"))
def run(request, tmp_path_factory):
    spec_key = request.param
    tmp = tmp_path_factory.mktemp(spec_key)
    mod, proto, path, _ = _simulate(spec_key, tmp, 21)
    result = mod.calibrate(path, str(proto))
    lab = load_lab(protocols_dir() / "lab-example.toml")
    return {"spec": spec_key, "result": result, "lab": lab,
            "results": json.loads(json.dumps(result.to_json())),
            "docs": {"lab": rate_dcc_bytes(result, lab=lab, cert_id=certificate_id(result, lab)),
                     "virtual": rate_dcc_bytes(result, cert_id=certificate_id(result, None))},
            "tmp": tmp, "proto": proto, "readings": path}


def test_valid_against_dcc_330_schema(run, schema):
    for name, doc in run["docs"].items():
        errors = list(schema.iter_errors(doc.decode("utf-8")))
        assert not errors, (run["spec"], name, str(errors[0])[:500])
    root = etree.fromstring(run["docs"]["lab"])          # the schema can fail
    root.find(".//dcc:result//si:real/si:value", NS).text = "0,15"
    assert not schema.is_valid(etree.tostring(root).decode())
    root = etree.fromstring(run["docs"]["lab"])
    root.find(".//dcc:result//si:coverageProbability", NS).text = "1.5"
    assert not schema.is_valid(etree.tostring(root).decode())


def _as_display(text: str) -> str:
    """An si:decimal "4.36e-5" back in the certificate's form "4.36×10⁻⁵"."""
    m = re.fullmatch(r"(-?[\d.]+)e(-?\d+)", text)
    if m:
        return f"{m.group(1)}×10{m.group(2).translate(str.maketrans('-0123456789', '⁻⁰¹²³⁴⁵⁶⁷⁸⁹'))}"
    return text


def _shown(doc: bytes):
    """(src, rule, factor, si:real element) of every stated item value (a χ² interval's ν
    beside it, ``uncertainty.nu_eff``: tests/test_chi2_nu_dcc.py)."""
    root = etree.fromstring(doc)
    out = []
    for c in root.iter(etree.Comment):
        m = re.match(r" src=(items\.\S+) rule=(\S+)(?: factor=(\S+))? ", c.text)
        if m and not m.group(1).endswith(".uncertainty.nu_eff"):
            out.append((m.group(1), m.group(2), float(m.group(3) or 1.0), c.getnext()))
    return out


def test_every_item_value_and_uncertainty_equal_results_json(run):
    res = run["results"]
    shown = _shown(run["docs"]["lab"])
    measured = [k for k, it in res["items"].items() if it["measured"]]
    assert sorted(s.split(".")[1] for s, _, _, _ in shown) == sorted(measured)
    assert len(measured) >= (15 if run["spec"] == "jjf1535-2015" else 20)
    for src, rule, factor, real in shown:
        key = src.split(".")[1]
        v = lookup(res, src) * factor
        text = real.find("si:value", NS).text
        assert _as_display(text) == display(rule, v), (src, text)
        x = parse_display(_as_display(text))
        step = 10.0 ** -int(rule[3:]) if rule.startswith("dec") else \
            last_digit_unit(_as_display(text))       # dec-1: rounded to tens
        assert abs(x - v) <= 0.5 * step + 1e-12 * abs(v), src
        unc = res["items"][key]["uncertainty"]
        it = res["items"][key]
        # a non-negative item whose U exceeds its value: one interval, [0, value + U]
        bound = it["nonnegative"] and unc["k"] is not None and unc["U"] > it["value"]
        if unc["k"] is None or bound:   # stated by its coverage interval (σ's χ², a range)
            iv = unc["interval"] if not bound else [0.0, it["value"] + unc["U"]]
            ci = real.find("si:measurementUncertaintyUnivariate/si:coverageIntervalMU", NS)
            if (it.get("details") or {}).get("bound_condition"):
                # no u_c certified (U = a + k·u): the interval's ends alone, in the next
                # quantity, with their probability in its name
                assert ci is None and real.find(".//si:valueStandardMU", NS) is None, key
                nxt = real.getparent().getnext()
                lo, hi = (float(x) for x in nxt.findtext(
                    "si:realListXMLList/si:valueXMLList", None, NS).split())
                assert lo <= iv[0] * factor and hi >= iv[1] * factor
                assert hi == pytest.approx(iv[1] * factor, rel=0.05)
                name = nxt.findtext("dcc:name/dcc:content", None, NS)
                # value ± (a + k·u), or a dispersion's one-sided [0, s + a + R]
                kind = {"U = a + R: [0, (s + R)/(1 − g)]": "one-sided bound-condition limit",
                        "interval of max|x_i| (uncertainty.extreme.max_abs_interval)":
                        "the 95 % interval of the largest magnitude"}.get(
                            unc["k_source"], "bound-condition interval")
                assert kind in name and name.endswith(
                    f"p = {100 * unc['coverage_probability']:g} %"), name
                continue
            lo, hi = (float(ci.find(f"si:interval{e}", NS).text) for e in ("Min", "Max"))
            assert lo <= iv[0] * factor and hi >= iv[1] * factor
            if unc.get("interval_numerical_u"):
                # ends from a Monte Carlo, stated where its draws settle them (JCGM 101
                # 7.9): at most one significant digit of the reach above the value, so
                # outward by less than one unit of that digit (tests/test_mc_interval_digits)
                from gonio.result.statement import decimals_for_sig
                gap = iv[1] - max(it["value"], iv[0])
                assert hi - iv[1] * factor < 10.0 ** -decimals_for_sig(gap, 1) * factor
            else:
                assert hi == pytest.approx(iv[1] * factor, rel=0.05)
            assert not bound or lo == 0.0
            # the interval's own probability, as results.json states it (a rule's outcome
            # range on whole grid steps holds at least 95 %; a χ² interval exactly 95 %)
            p_dcc = float(ci.find("si:coverageProbability", NS).text)
            # (the p the certificate states: 0.9967 is "p ≈ 99.7 %", 0.997 in the DCC)
            from gonio.result.statement import p_text
            assert p_text(p_dcc) == p_text(unc["coverage_probability"]) and 0.95 <= p_dcc <= 1.0
            assert abs(p_dcc - unc["coverage_probability"]) <= 5e-3
            assert real.find("si:measurementUncertaintyUnivariate/si:expandedMU", NS) is None
            continue
        mu = real.find("si:measurementUncertaintyUnivariate/si:expandedMU", NS)
        U = float(mu.find("si:valueExpandedMU", NS).text)
        assert U == pytest.approx(unc["U"] * factor, rel=0.05)     # 2 significant digits
        U_rule = rule if rule.startswith("sci") else "U"
        assert _as_display(mu.find("si:valueExpandedMU", NS).text) == display(U_rule,
                                                                              unc["U"] * factor)
        assert mu.find("si:coverageFactor", NS).text == display("k", unc["k"])
        assert float(mu.find("si:coverageProbability", NS).text) == unc["coverage_probability"] == 0.95
    # per-g items are per m s⁻²: the value times g_n is the results.json value
    per_g = [(s, f, r, ru) for s, ru, f, r in shown if f != 1.0]
    assert per_g and all(res["items"][s.split(".")[1]]["unit"].endswith("/g")
                         for s, _, _, _ in per_g)
    for src, f, real, rule in per_g:       # stated at U's decimal place (per m s⁻²)
        step = 10.0 ** -int(rule[3:]) if rule.startswith("dec") else 1e-3 * lookup(res, src)
        assert float(real.find("si:value", NS).text) * G_N == pytest.approx(
            lookup(res, src), abs=0.5 * step * G_N * 1.000001)
        assert f == pytest.approx(1 / G_N, rel=1e-15)


def test_clause_names_and_ref_types(run):
    res = run["results"]
    root = etree.fromstring(run["docs"]["lab"])
    for key, it in res["items"].items():
        r = root.find(f".//dcc:result[@id='result-{key}']", NS)
        assert r is not None, key
        q = r.find("dcc:data/dcc:quantity", NS)
        assert f"{run['spec']} {it['clause']}" in q.find("dcc:name/dcc:content", NS).text
        if it["measured"]:
            tok = "gonio_{}_clause_{}".format(run["spec"], it["clause"].replace(" ", "")
                                              .replace(")", ""))
            assert tok in q.get("refType").split(), (key, q.get("refType"))


def test_dsi_units_parse(run):
    dsi = pytest.importorskip("dsi_unit", reason="pip install dsiunits (test-only)")
    root = etree.fromstring(run["docs"]["lab"])
    units = {u.text for u in root.iter(f"{{{SI_NS}}}unit", f"{{{SI_NS}}}unitXMLList")}
    want = {r"\milli\volt\degree\tothe{-1}\second", r"\degree\second\tothe{-1}", r"\hertz",
            r"\second", r"\degreecelsius", r"\volt", r"\degree\hour\tothe{-1}",
            r"\degree\hour\tothe{-0.5}"}
    assert want <= units, want - units
    for u in {w for text in units for w in text.split()}:    # a unitXMLList: one per end
        parsed = dsi.DsiUnit(u)
        assert parsed.valid and not parsed.warnings, u
    assert not dsi.DsiUnit(r"\degree\hour\tothe{-1}\gravity").valid      # the parser can fail


def test_conditions_and_statements(run):
    res = run["results"]
    root = etree.fromstring(run["docs"]["virtual"])
    conds = {ic.find("dcc:name/dcc:content", NS).text: ic
             for ic in root.iterfind(".//dcc:influenceCondition", NS)}
    assert {"nominal supply voltage", "scale-factor input rates",
            "chamber temperature points", "angular vibration frequencies"} <= set(conds)
    # the room temperature only from the keys the specification reads as the room's: IEC's
    # "# room_temperature_c" is its base temperature T_BASE, never stated as the room's
    assert ("room temperature" in conds) == (run["spec"] != "iec62047-20"), sorted(conds)
    temps = next(it["details"]["temperatures_c"] for k, it in res["items"].items()
                 if k.startswith("sf_temperature"))
    got = conds["chamber temperature points"].find(".//si:valueXMLList", NS).text.split()
    assert [float(x) for x in got] == [float(t) for t in temps]
    sf = res["items"]["scale_factor"]["details"]
    rates = sf.get("rates_dps", sf.get("x_dps"))
    got = conds["scale-factor input rates"].find(".//si:valueXMLList", NS).text.split()
    assert [float(x) for x in got] == [float(r) for r in rates]
    ids = [s.get("id") for s in root.iterfind(".//dcc:statement", NS)]
    assert "virtual-bench" in ids and "uncertainty" in ids
    assert sum(i.startswith("reading-taken-") for i in ids) == len(res["readings_taken"])
    assert rate_dcc_bytes(run["result"], cert_id="X") == rate_dcc_bytes(run["result"], cert_id="X")


def test_not_measured_items_carry_their_reason(run, schema):
    """Readings without the angular-vibration records: the band item (JJF 7.2.15, IEC 5.5)
    is in the DCC as dcc:noQuantity with the reason results.json gives."""
    mod = __import__(get(run["spec"]).calibrate.__module__, fromlist=["calibrate"])
    rd = read_rate_readings(run["readings"])
    test = "vibration"
    assert (rd.data["test"] == test).any()
    cut = RateReadings(rd.data[rd.data["test"] != test].reset_index(drop=True), rd.metadata)
    result = mod.calibrate(cut, str(run["proto"]))
    key = "bandwidth" if run["spec"] == "jjf1535-2015" else "frequency_band"
    it = result.items[key]
    assert not it.measured and it.reason
    doc = rate_dcc_bytes(result, cert_id="X-2")
    assert not list(schema.iter_errors(doc.decode()))
    q = etree.fromstring(doc).find(f".//dcc:result[@id='result-{key}']/dcc:data/dcc:quantity", NS)
    assert q.find("si:real", NS) is None
    assert q.find("dcc:noQuantity/dcc:content", NS).text == f"not measured: {it.reason}"


def test_calibrate_cli_writes_the_dcc_in_the_set(run, schema, capsys):
    from gonio.cli import main
    out = run["tmp"] / "cal"
    example = protocols_dir() / "lab-example.toml"
    # the example's limits name the optical draft's items: refused, naming this spec's items
    assert main(["calibrate", str(run["readings"]), "--protocol", str(run["proto"]),
                 "--lab", str(example), "--out", str(run["tmp"] / "refused")]) == 2
    err = capsys.readouterr().err
    assert f"{run['spec']} has no item 'angle_deviation' (its items: " in err and "bias" in err
    assert not (run["tmp"] / "refused" / "results.json").exists()
    text = example.read_text(encoding="utf-8").split("\n[[specification_limits]]\n")[0] + "\n"
    # the example names the optical bench's instrument and room: these readings' are others
    text = re.sub(r"^\[(instrument|environment)\]\n.*?\n\n", "", text, flags=re.S | re.M)
    lab = run["tmp"] / "lab-rate.toml"
    lab.write_text(text + '[[specification_limits]]\nitem = "bias"\nmpe = 1.0e6\n'
                   'source = "test limit"\n', encoding="utf-8")
    assert main(["calibrate", str(run["readings"]), "--protocol", str(run["proto"]), "--dcc",
                 "--lab", str(lab), "--out", str(out)]) == 0
    capsys.readouterr()
    # conformity decided in the pipeline, written to results.json (non-binary, the lab's rule)
    conf = json.loads((out / "results.json").read_text())["items"]["bias"]["conformity"]
    assert (conf["rule"], conf["outcome"], conf["limits_from"]) == ("non-binary", "pass",
                                                                    "lab file")
    man = json.loads((out / "gonio-manifest.json").read_text())
    assert {"certificate.dcc.xml", "certificate.html", "certificate.pdf",
            "results.json"} <= set(man["files"])
    doc = (out / "certificate.dcc.xml").read_bytes()
    assert not list(schema.iter_errors(doc.decode()))
    root = etree.fromstring(doc)
    assert root.find(".//dcc:coreData/dcc:uniqueIdentifier", NS).text == \
        load_lab(lab)["certificate"]["number"]
    # the file equals the DCC of results.json's calibration
    res = json.loads((out / "results.json").read_text())
    val = {s: (float(r.find("si:value", NS).text), ru, f) for s, ru, f, r in _shown(doc)}
    for src, (v, rule, f) in val.items():       # the stated value: results.json's, rounded
        assert _as_display(repr(v) if "e" in repr(v) else str(v)) and \
            display(rule, lookup(res, src) * f) == _as_display(
                [r for s, _, _, r in _shown(doc) if s == src][0].find("si:value", NS).text), src
    val = {s: v for s, (v, _, _) in val.items()}
    assert not math.isnan(sum(val.values()))
