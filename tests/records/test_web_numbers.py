"""The records' web pages state every item as the certificate does, and mark virtual readings.

For each specification ``gonio demo --spec KEY --seed 3`` is put into a records store as the
command line puts it (``gonio calibrate --record``: imported, its standard and environment
attached, its draft rendered from the stored result) and its calibration page read through
the application (Starlette's TestClient):

- every measured item of results.json has one row, and that row's value, U, k, ν_eff, interval
  ends and p are the ones the statement rule gives from results.json's numbers, each negative
  number with U+2212, and the same as the demo certificate's own number spans (k checked
  against scipy's t quantile of the stated ν: tests/statement_numbers.py, shared with
  tests/test_one_statement.py);
- the page and the draft certificate it serves (every PDF page, the HTML, the DCC) say
  virtual; readings whose metadata are stripped of the bench's lines give no mark;
- readings whose serial contradicts the registered instrument are refused by the web form,
  naming both serials, and nothing is queued; with the right serial they are queued and the
  queued calibration's page says virtual already (from the readings' own metadata).
"""

from __future__ import annotations

import html as html_module
import json
import re

import pytest
from lxml import etree

from gonio.records import services
from gonio.report.i18n import labels
from tests.own_readings import own_text
from tests.statement_numbers import (certificate_spans, cell_numbers, check_k, expected_cell,
                                     measured, nu_eff_interval_items)

from .conftest import PASSWORD, make_people

SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")
_ROW = re.compile(r'<td class="num" data-src="items\.([A-Za-z0-9_]+)">([^<]*)</td>')


def environment(d) -> dict:
    """The room temperature and humidity the readings in folder ``d`` state (their own
    metadata: the ones the identity check compares), else 20 °C and 45 %."""
    from gonio.formats.provenance import readings_metadata

    md = readings_metadata(d / "readings.csv")
    t = md.get("temperature_c", md.get("room_temperature_c", "20.0"))
    return {"temperature_c": float(t), "humidity_pct": float(md.get("humidity_pct", "45"))}


def web_client(store, name: str = "tech"):
    from fastapi.testclient import TestClient

    from gonio.web.app import create_app

    c = TestClient(create_app(store), follow_redirects=False)
    token = re.search(r'name="csrf" value="([^"]+)"', c.get("/login").text).group(1)
    r = c.post("/login", data={"username": name, "password": PASSWORD, "csrf": token})
    assert r.status_code == 303, r.text
    return c


@pytest.fixture(scope="module", params=SPECS)
def recorded(request, tmp_path_factory, shared_demo):
    """The demo of one specification (``gonio demo --seed 3``: the session's shared one,
    tests/test_one_statement.py reads it too; read only), recorded with a standard and the
    readings' environment (its draft certificate rendered from the stored result): the
    folder, results.json, the store, the calibration's id and a logged-in client."""
    from gonio.records.db import open_store
    from gonio.records.importer import record_output_folder

    root = tmp_path_factory.mktemp(request.param)
    d = shared_demo(request.param, seed=3)
    store = open_store(None, root / "data")
    tech = make_people(store)["tech"]
    services.add_standard(store, tech, name="reference rotary table", identifier="ENV-STD-1",
                          due_on="2099-01-01")
    cid = record_output_folder(store, d, actor=tech, standard_identifiers=["ENV-STD-1"],
                               **environment(d))
    yield {"spec": request.param, "dir": d, "store": store, "id": cid, "web": web_client(store),
           "res": json.loads((d / "results.json").read_text(encoding="utf-8"))}
    store.close()


def page_rows(text: str) -> dict:
    """item key → the list of its statement cells on a calibration page (unescaped)."""
    rows: dict = {}
    for key, cell in _ROW.findall(text):
        rows.setdefault(key, []).append(html_module.unescape(cell).replace("\xa0", " "))
    return rows


def test_web_states_every_item_as_the_certificate(recorded):
    """One row per measured item; its numbers are results.json's by the statement rule and
    the certificate's."""
    from gonio.report.i18n import minus_sign
    from gonio.result.statement import K_SOURCE_MAX_ABS, item_statement

    r = recorded["web"].get(f"/calibrations/{recorded['id']}")
    assert r.status_code == 200
    rows = page_rows(r.text)
    spans = certificate_spans((recorded["dir"] / "certificate.html").read_text(encoding="utf-8"))
    items = measured(recorded["res"])
    assert items
    for key, it in items.items():
        check_k(key, it)
        assert len(rows.get(key, [])) == 1, (key, rows.get(key))
        got, want = cell_numbers(rows[key][0]), expected_cell(it)
        assert got == want, (key, rows[key][0])
        st = item_statement(it)
        value = minus_sign(st.value_text)
        if (it.get("uncertainty") or {}).get("k_source") == K_SOURCE_MAX_ABS:
            # E (7.4): the statement's value is max|E_i|; the span of items.KEY.value is the
            # signed extreme beside it, the same magnitude at the same decimal place
            value = minus_sign(("-" if it["value"] < 0 else "") + st.value_text)
        for field, text in (("value", value), ("uncertainty.U", st.U_text),
                            ("uncertainty.k", st.k), ("uncertainty.nu_eff", st.nu_eff)):
            if text is not None and (key, field) in spans and not st.below_zero:
                # a signed extreme above zero may carry its sign ("+0.05")
                ok = spans[(key, field)] == {text} or (
                    field == "value" and (it.get("uncertainty") or {}).get("k_source")
                    == K_SOURCE_MAX_ABS and spans[(key, field)] == {"+" + text})
                assert ok, (key, field, spans[(key, field)])
    # a row the page has for an item results.json does not hold as measured says so
    for key, cells in rows.items():
        if key not in items:
            assert cells[0] in ("not measured", "not stated") or \
                recorded["res"]["items"][key]["measured"], (key, cells)


_TITLE_ROW = re.compile(r'<tr><td>([^<]*)</td><td>[^<]*</td><td class="num" '
                        r'data-src="items\.([A-Za-z0-9_]+)">')


def test_the_chinese_page_states_the_same_numbers(recorded, tmp_path):
    """The calibration page in Chinese (``?lang=zh``): every item's numbers are the English
    page's and the statement rule's from results.json, and the Chinese certificate's, rendered
    from the same stored result (its number spans); its names are the Chinese certificate's
    or its DCC's (the report's texts, no table of the web's own)."""
    from gonio.report.i18n import minus_sign
    from gonio.result.model import Result
    from gonio.result.statement import item_statement
    from gonio.specs import get

    web, cid, res = recorded["web"], recorded["id"], recorded["res"]
    en = page_rows(web.get(f"/calibrations/{cid}").text)
    r = web.get(f"/calibrations/{cid}?lang=zh")
    assert r.status_code == 200
    zh = page_rows(r.text)
    assert set(zh) == set(en) and zh
    assert f"<th>{labels('zh')['item']}</th>" in r.text and 'href="?lang=en"' in r.text
    out = tmp_path / "zh"                 # the Chinese certificate of the same stored result
    get(res["spec"]).renderer().write(Result.from_json(res), out, lang="zh", dcc=True)
    page = (out / "certificate.html").read_text(encoding="utf-8")
    # the names: the zh certificate's, or its DCC's zh where the certificate shows the item
    # in a matrix (the triad's M, S, L)
    dcc = out / "certificate.dcc.xml"
    named = page + (dcc.read_text(encoding="utf-8") if dcc.exists() else "")
    spans = certificate_spans(page)
    for key, it in measured(res).items():
        assert [cell_numbers(c) for c in zh[key]] == [cell_numbers(c) for c in en[key]] \
            == [expected_cell(it)], (key, zh[key], en[key])
        st = item_statement(it)
        if (key, "uncertainty.U") in spans and st.U_text is not None:
            assert spans[(key, "uncertainty.U")] == {st.U_text}, key
        if (key, "value") in spans and not st.below_zero and \
                (it.get("uncertainty") or {}).get("k_source") is None:
            assert spans[(key, "value")] == {minus_sign(st.value_text)}, key
    titles = {k: html_module.unescape(t) for t, k in _TITLE_ROW.findall(r.text)}
    assert titles and all(re.search(r"[\u4e00-\u9fff]", t) for t in titles.values()), titles
    for key, title in titles.items():           # each name is the zh certificate's own
        assert html_module.escape(title, quote=False) in named or title in named, (key, title)


def test_web_states_the_nu_of_each_chi2_interval(recorded):
    """An item stated by a χ² interval (the optical draft's B_s and R, a rate specification's
    bias stability, K_r, B_r, ARW, a noise item's limit) is stated on the calibration page, in
    English and Chinese, with the ν that interval was computed with: the certificate's ν
    (its number span), summary.txt's, the integer part of results.json's ν_eff, and the
    interval's upper end computed again from it (JCGM 100 E.4.3) is results.json's, within
    the page's printed end; an item stated otherwise prints no "ν =" of its own."""
    import math

    from scipy.stats import chi2

    from gonio.report.dcc import dsi_decimal
    from gonio.result.statement import K_SOURCE_CHI2, chi2_nu, chi2_stated_nu

    web, cid, res = recorded["web"], recorded["id"], recorded["res"]
    spans = certificate_spans((recorded["dir"] / "certificate.html").read_text(encoding="utf-8"))
    summary = (recorded["dir"] / "summary.txt").read_text(encoding="utf-8")
    en = page_rows(web.get(f"/calibrations/{cid}").text)
    zh = page_rows(web.get(f"/calibrations/{cid}?lang=zh").text)
    seen = set()
    nu_eff = nu_eff_interval_items(res)
    for key, it in res["items"].items():
        unc = it.get("uncertainty") or {}
        if not it.get("measured") or key not in en:
            continue
        if unc.get("interval") is None or unc.get("k") is not None \
                or not chi2_stated_nu(unc.get("k_source")):
            assert "ν =" not in en[key][0], (key, en[key])
            if key in nu_eff:       # another interval: the ν_eff of its coverage factor
                assert en[key][0].endswith(f"; ν_eff = {nu_eff[key]}"), (key, en[key])
                assert zh[key][0].endswith(f"；ν_eff = {nu_eff[key]}"), (key, zh[key])
                assert f"; ν_eff = {nu_eff[key]}\n" in summary, key
                seen.add(key)
            else:
                assert "ν_eff =" not in en[key][0] or "±" in en[key][0], (key, en[key])
            continue
        nu = f"{chi2_nu(unc['nu_eff']):g}"
        assert nu == str(math.floor(unc["nu_eff"])), key
        assert en[key][0].endswith(f"; ν = {nu}"), (key, en[key])
        assert zh[key][0].endswith(f"；ν = {nu}"), (key, zh[key])
        if (key, "uncertainty.nu_eff") in spans:            # the certificate's ν column
            assert spans[(key, "uncertainty.nu_eff")] == {nu}, (key, spans[
                (key, "uncertainty.nu_eff")])
        assert f"ν = {nu}" in summary or f"ν_eff = {nu})" in summary, key
        seen.add(key)
        if unc["k_source"] != K_SOURCE_CHI2:
            continue                  # a bound-condition limit: s + a + R, not s alone
        p = unc.get("coverage_probability") or 0.95
        upper = it["value"] * math.sqrt(float(nu) / chi2.ppf(1 - p, float(nu)))
        assert upper == pytest.approx(unc["interval"][1], rel=1e-6), key
        printed = cell_numbers(en[key][0])
        hi = printed.get("upper") or printed["interval"][1]
        assert float(dsi_decimal(hi.replace("\u2212", "-"))) >= upper * (1 - 1e-12), \
            (key, hi, upper)
    must = {"ogam-draft": {"zero_stability", "repeatability"},
            "jjf1535-2015": {"bias_stability"},
            "iec62047-20": {"scale_factor", "bias"},
            "triad-alignment": {"M_xy"}}.get(recorded["spec"], set())
    assert must <= seen, (recorded["spec"], sorted(seen))


def test_results_json_served_is_the_stored_result(recorded):
    r = recorded["web"].get(f"/calibrations/{recorded['id']}/files/results.json")
    assert r.status_code == 200
    assert json.loads(r.content) == recorded["res"]


def files_say_virtual(web, base: str, spec: str, tmp) -> None:
    """The certificate files the web serves under ``base`` (every PDF page, the HTML, the
    DCC) carry the virtual-bench mark."""
    from gonio.report.dcc import DCC_NS
    from tests.test_provenance import pdf_pages

    files = {name: web.get(f"{base}/{name}") for name in
             ("certificate.pdf", "certificate.html", "certificate.dcc.xml")}
    assert all(f.status_code == 200 for f in files.values()), \
        {n: f.status_code for n, f in files.items()}
    pdf = tmp / "served.pdf"
    pdf.write_bytes(files["certificate.pdf"].content)
    pages = pdf_pages(pdf)
    assert len(pages) >= 2, spec
    for i, text in enumerate(pages, 1):
        assert labels("en")["virtual_short"] in text, f"{spec}: {base} PDF page {i} unmarked"
    assert labels("en")["virtual"] in files["certificate.html"].text, spec
    dcc = etree.fromstring(files["certificate.dcc.xml"].content)
    assert dcc.find(f".//{{{DCC_NS}}}*[@id='virtual-bench']") is not None, spec


def page_mark(web, url: str) -> str:
    """The virtual-bench mark of a web page, or ""."""
    page = html_module.unescape(web.get(url).text)
    m = re.search(r'<p class="virtual" id="virtual-bench">([^<]*)</p>', page)
    return m.group(1) if m else ""


def test_web_page_and_draft_say_virtual(recorded, tmp_path):
    web, cid, spec = recorded["web"], recorded["id"], recorded["spec"]
    prov = recorded["res"]["provenance"]
    assert prov["virtual"] is True
    mark = page_mark(web, f"/calibrations/{cid}")
    assert mark.startswith(labels("en")["virtual"]), spec
    assert f"virtual bench {prov['bench']}, seed {prov['seed']}" in mark, spec
    files_say_virtual(web, f"/calibrations/{cid}/files", spec, tmp_path)
    summary = web.get(f"/calibrations/{cid}/files/summary.txt")
    assert summary.text.startswith("VIRTUAL BENCH EXAMPLE"), spec


def test_history_bars_are_the_stated_intervals(recorded):
    """The instrument's history (its figure's bars): an item the certificate states by one
    interval carries that interval, the page's ends as numbers; an item stated by ± U none."""
    from gonio.report.dcc import dsi_decimal

    store, cid = recorded["store"], recorded["id"]
    inst_id = services.calibration(store, cid).instrument_id
    hist = services.history(store, inst_id)
    for key, it in measured(recorded["res"]).items():
        want = expected_cell(it).get("interval")
        (row,) = [r for r in hist[key] if r["calibration_id"] == cid]
        if want is None:
            assert row["interval"] is None, key
        else:
            ends = [float(dsi_decimal(x.replace("\u2212", "-"))) for x in want]
            assert list(row["interval"]) == pytest.approx(ends, rel=1e-12), key
    r = recorded["web"].get(f"/instruments/{inst_id}/history.svg")
    assert r.status_code == 200 and r.text.count('class="bar"') >= len(measured(recorded["res"]))


def test_history_from_rows_is_the_history_from_the_stored_results(recorded, monkeypatch):
    """The plot's data read from the result rows alone (their kept statements) equals the
    data worked out from each stored results.json (what the plot read before rows kept
    them, :func:`gonio.records.results.stated_items`), and so does the figure."""
    from decimal import Decimal

    from gonio.records import results
    from gonio.report.history_figure import history_svg

    store, cid = recorded["store"], recorded["id"]
    inst_id = services.calibration(store, cid).instrument_id
    sha = {c: services.calibration(store, c).results_sha256 for c in
           {r["calibration_id"] for rows in services.history(store, inst_id).values()
            for r in rows}}

    def intervals(cal_id):          # each statement's interval, its ends as numbers
        return {k: tuple(float(Decimal(x).scaleb(st.exponent)) for x in st.interval)
                for k, st in results.stated_items(store, sha[cal_id]).items()
                if st.interval is not None}

    from_json = {key: [dict(r, interval=intervals(r["calibration_id"]).get(key)) for r in rows]
                 for key, rows in services.history(store, inst_id).items()}
    assert any(r["interval"] for rows in from_json.values() for r in rows) \
        or recorded["spec"] == "triad-alignment"             # it states every item by ± U
    monkeypatch.setattr(results, "stored_columns", lambda *a: pytest.fail("read a result"))
    from_rows = services.history(store, inst_id)
    assert from_rows == from_json
    assert history_svg(from_rows) == history_svg(from_json)


def _readings(d):
    return (d / "readings.csv").read_bytes()


def test_web_form_refuses_another_serial_and_marks_the_queued_run(recorded, tmp_path):
    """The readings' # serial against the registered instrument, on the web form (the path a
    person takes): refused naming both, nothing queued; the right serial is queued and its
    page marked virtual from the readings' metadata before any result exists."""
    from gonio.formats.provenance import readings_metadata
    from gonio.records.db import open_store

    spec, d = recorded["spec"], recorded["dir"]
    serial = readings_metadata(d / "readings.csv")["serial"]
    store = open_store(None, tmp_path / "data")
    tech = make_people(store)["tech"]
    cust = services.add_customer(store, tech, "C", "1 Road")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="SN-0001",
                                        spec_key=spec, model="")
    std = services.add_standard(store, tech, name="table", identifier="T-1", due_on="2099-01-01")
    web = web_client(store)
    csrf = re.search(r'name="csrf" value="([^"]+)"', web.get("/").text).group(1)
    form = {"performed_on": "2025-11-20", "standards": [str(std.id)], "csrf": csrf,
            **{k: str(v) for k, v in environment(d).items()}}
    r = web.post(f"/instruments/{inst.id}/calibrate", data=form,
                 files={"readings": ("readings.csv", _readings(d))})
    assert r.status_code == 400, spec
    said = html_module.unescape(re.search(r'<p class="error" role="alert">(.*?)</p>', r.text,
                                          re.S).group(1))
    assert f"the readings say '{serial}'" in said and "'SN-0001'" in said, (spec, said)
    with store.session() as s:
        from sqlalchemy import func, select

        from gonio.records.models import Calibration
        assert s.scalar(select(func.count()).select_from(Calibration)) == 0
    services.update_instrument(store, tech, inst.id, serial=serial)
    r = web.post(f"/instruments/{inst.id}/calibrate", data=form,
                 files={"readings": ("readings.csv", _readings(d))})
    assert r.status_code == 303, (spec, r.text[:2000])
    page = html_module.unescape(web.get(r.headers["location"]).text)
    assert 'id="virtual-bench"' in page and labels("en")["virtual"] in page, spec
    store.close()


def test_laboratory_readings_give_no_mark(recorded, tmp_path):
    """The same readings without the bench's metadata lines (a laboratory's own file): the
    queued calibration's page has no virtual mark (the check can fail)."""
    from gonio.formats.provenance import readings_metadata
    from gonio.records.db import open_store
    from gonio.records.models import Calibration

    if recorded["spec"] != "ogam-draft":
        pytest.skip("one specification suffices: the mark's rule is the same for all")
    d = recorded["dir"]
    lines = _readings(d).decode("utf-8").splitlines(keepends=True)
    stripped = own_text("".join(lines))
    md = readings_metadata(d / "readings.csv")
    store = open_store(None, tmp_path / "data")
    tech = make_people(store)["tech"]
    cust = services.add_customer(store, tech, "C", "1 Road")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial=md["serial"],
                                        spec_key="ogam-draft", model="")
    std = services.add_standard(store, tech, name="table", identifier="T-1", due_on="2099-01-01")
    sha, _ = services.store_file(store, __import__("io").BytesIO(stripped.encode("utf-8")))
    from gonio.records import submission
    cal = submission.submit_calibration(
        store, tech, instrument_id=inst.id, readings_sha256=sha, standard_ids=[std.id],
        performed_on="2025-11-20", **environment(d))
    assert isinstance(cal, Calibration)
    page = web_client(store).get(f"/calibrations/{cal.id}").text
    assert 'id="virtual-bench"' not in page and labels("en")["virtual"] not in page
    store.close()


def test_issued_certificate_page_and_files_say_virtual(recorded, tmp_path):
    """Reviewed, approved and issued (rendered from the stored result at issue): the
    certificate's page and its files say virtual (last: it issues the module's calibration)."""
    from sqlalchemy import select

    from gonio.records import worker
    from gonio.records.models import Certificate

    store, cid, spec = recorded["store"], recorded["id"], recorded["spec"]
    people = {u: services.user(store, u) for u in ("rev", "rev2")}
    services.review(store, people["rev"], cid, accept=True)
    services.approve(store, people["rev2"], cid)
    assert worker.execute(store, services.claim_next(store).id), \
        services.calibration(store, cid).error
    with store.session() as s:
        cert_id = s.scalar(select(Certificate.id).where(Certificate.calibration_id == cid))
    web = recorded["web"]
    assert page_mark(web, f"/certificates/{cert_id}").startswith(labels("en")["virtual"]), spec
    files_say_virtual(web, f"/certificates/{cert_id}", spec, tmp_path)
    # the calibration's page of the issued calibration: its numbers unchanged
    rows = page_rows(web.get(f"/calibrations/{cid}").text)
    for key, it in measured(recorded["res"]).items():
        assert [cell_numbers(c) for c in rows[key]] == [expected_cell(it)], key


@pytest.mark.parametrize("spec, protocol, seed", [r for r in __import__(
    "tests.test_provenance", fromlist=["RUNS"]).RUNS], ids=SPECS)
def test_a_contradiction_the_lab_proceeded_with_is_flagged_on_the_page(spec, protocol, seed,
                                                                       tmp_path,
                                                                       shared_simulation):
    """Simulated readings calibrated on the command line with a laboratory file naming another
    serial and proceeding, then put into the records (gonio db import --lab): the calibration
    page states the contradiction, naming both serials, and says virtual."""
    from gonio.formats.provenance import readings_metadata
    from gonio.records.db import open_store
    from gonio.records.importer import import_output_folder
    from tests.test_provenance import LAB_SERIAL, PINS, lab_file, simulate_calibrate

    lab = lab_file(tmp_path, 'on_mismatch = "proceed"')
    cal = simulate_calibrate(spec, protocol, seed, tmp_path, lab, sims=shared_simulation)
    readings = tmp_path / "sim" / "readings.csv"
    serial = readings_metadata(readings)["serial"]
    store = open_store(None, tmp_path / "data")
    services.add_standard(store, make_people(store)["tech"], name="rotary table",
                          identifier="RT-07", due_on="2099-01-01")    # the lab file's
    cid = import_output_folder(store, cal, readings=readings, lab=lab,
                               protocol=PINS / protocol if protocol else None)
    page = html_module.unescape(web_client(store).get(f"/calibrations/{cid}").text)
    flagged = re.search(r'<div class="virtual" id="identity">(.*?)</div>', page, re.S)
    assert flagged, spec
    assert serial in flagged.group(1) and LAB_SERIAL in flagged.group(1), (spec, flagged.group(1))
    assert 'id="virtual-bench"' in page, spec
    store.close()
