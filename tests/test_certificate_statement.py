"""Issue 13: the certificate a metrologist signs — stated form, rounding, conformity, Chinese,
layout defects, print CSS — checked on rendered output (poppler, headless Chromium).

Each layout test can fail: it reads the rendered PDF pages (matplotlib's and Chromium's print of
the HTML) as text, page by page. Needs scripts/install-test-system-deps.sh (chromium,
poppler-utils, fonts-noto-cjk).
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from dataclasses import replace
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure
from scipy.stats import norm

from gonio.specs.ogam_draft.bench import load_bench, run_session, write_session
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.pipeline.dispatch import decide_conformity
from gonio.specs.ogam_draft.outputs import write_calibration
from gonio.errors import GonioError
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.report.figures import HTML_FIGSIZE, mpl_style
from gonio.specs.ogam_draft import certificate_pages as cert
from gonio.specs.ogam_draft import figures as figs
from gonio.report.i18n import LABELS as SHARED_LABELS
from gonio.report.i18n import labels as shared_labels
from gonio.specs.ogam_draft.phrases import BUDGET_SOURCES_ZH, READING_NOTES_ZH
from gonio.specs.ogam_draft.phrases import LABELS as OWN_LABELS

#: Every label the optical certificate shows: the shared ones and the draft's own.
LABELS = SHARED_LABELS | OWN_LABELS


def labels(lang):
    """The optical certificate's labels (the shared ones and the draft's own)."""
    return shared_labels(lang, OWN_LABELS)
from gonio.specs.ogam_draft.stated import stated_item, summary_text
from gonio.resources import builtin_names, protocols_dir

HINT = "run scripts/install-test-system-deps.sh (chromium, poppler-utils, fonts-noto-cjk)"
LAB = protocols_dir() / "lab-example.toml"
# the shared small protocol with a third, slow rate in 7.6
SMALL = {**tomllib.loads((Path(__file__).parent / "data" / "small-protocol.toml")
                          .read_text(encoding="utf-8")),
         "rate_consistency": {"rates_dps": [30.0, 60.0, 1.0], "rest_s": 15.0}}


def tool(name: str) -> str:
    path = shutil.which(name) or (f"/usr/bin/{name}" if Path(f"/usr/bin/{name}").exists() else None)
    if not path:
        pytest.skip(f"{name} is missing: {HINT}")
    return path


def pdf_pages(pdf: Path) -> list[str]:
    txt = subprocess.run([tool("pdftotext"), "-layout", str(pdf), "-"], capture_output=True,
                         text=True, check=True).stdout
    return [p for p in txt.split("\f") if p.strip()]


def chromium_print(html_path: Path, out_pdf: Path, tmp: Path) -> Path:
    exe = shutil.which("chromium") or shutil.which("chromium-browser") or tool("chromium")
    subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu",
                    "--disable-background-networking", "--no-first-run",
                    f"--user-data-dir={tmp / 'chromium-profile'}", "--no-pdf-header-footer",
                    f"--print-to-pdf={out_pdf}", html_path.resolve().as_uri()],
                   capture_output=True, timeout=180, check=True)
    assert out_pdf.is_file() and out_pdf.stat().st_size > 1000
    return out_pdf


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("cert13")
    proto = parse_protocol(SMALL)
    session = run_session(proto, replace(load_bench("rlg"), sample_rate_hz=50.0), seed=4)
    write_session(session, d)
    lab = cert.load_lab(LAB)
    result = decide_conformity(calibrate(d / "readings.csv", proto,
                                         static_record=session.static_record), lab)
    write_calibration(result, d, lab=lab)
    cert.write_certificate(result.to_json(), d / "en", truth=session.truth, lab=lab, dcc=True)
    cert.write_certificate(result.to_json(), d / "zh", truth=session.truth, lang="zh")
    printed = {lang: chromium_print(d / lang / "certificate.html", d / f"{lang}-print.pdf", d)
               for lang in ("en", "zh")}
    return {"dir": d, "result": result, "lab": lab, "truth": session.truth,
            "results": json.loads((d / "results.json").read_text()), "printed": printed}


def half_up(x: float, dec: int) -> str:
    return f"{Decimal(repr(x)).quantize(Decimal(1).scaleb(-dec), rounding=ROUND_HALF_UP):f}"


def u_decimals(U: float) -> int:
    """Decimal place of U at two significant digits (JCGM 100 7.2.6), computed afresh."""
    e = Decimal(repr(U)).adjusted()
    dec = 1 - e
    if Decimal(repr(U)).quantize(Decimal(1).scaleb(-dec), rounding=ROUND_HALF_UP).adjusted() > e:
        dec -= 1
    return dec


def visible_text(page: str) -> str:
    page = re.sub(r"<style>.*?</style>|<svg.*?</svg>", " ", page, flags=re.S)
    page = re.sub(r"</?span[^>]*>", "", page)
    return html.unescape(re.sub(r"<[^>]+>", " ", page))


# --------------------------------------------------------------------------- content

def test_E_interval_form_identical_in_every_output(run):
    """E = ± max|E_i| stated by the 95 % interval of max|E_i| (results.json's), rounded here
    by hand: the decimal place of the interval's nearer reach (two significant digits; its
    upper reach for an interval from 0), the ends outwards, max|E_i| and the signed extreme
    half up; the same in the certificate, summary.txt and the DCC, and no ± U."""
    from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal

    res = run["results"]
    E = [r["E_arcsec"] for r in res["items"]["angle_deviation"]["details"]["table"]]
    j = int(np.argmax(np.abs(E)))
    m = abs(E[j])
    lo, hi = res["items"]["angle_deviation"]["uncertainty"]["interval"]
    assert lo <= m <= hi
    dec = u_decimals(hi - m if lo == 0 else min(hi - m, m - lo))
    q = Decimal(1).scaleb(-dec)
    hi_t = str(Decimal(repr(hi)).quantize(q, rounding=ROUND_CEILING))
    lo_t = str(Decimal(repr(lo)).quantize(q, rounding=ROUND_FLOOR))
    iv = f"≤ {hi_t} (p = 95 %)" if lo == 0 else f"[{lo_t}, {hi_t}] (p = 95 %)"
    mt = half_up(m, dec)
    signed = half_up(E[j], dec)
    signed = signed if signed.startswith("-") else "+" + signed
    pos = f"{res['items']['angle_deviation']['details']['table'][j]['position_deg']:g}"
    # the certificate prints the minus sign U+2212; summary.txt and the DCC the hyphen-minus
    expect = f"{mt}; {iv}; signed extreme {signed.replace('-', chr(0x2212))}″ at {pos}°"
    page = visible_text((run["dir"] / "en" / "certificate.html").read_text())
    assert re.sub(r"\s+", " ", expect) in re.sub(r"\s+", " ", page)
    summary = summary_text(res)
    assert f"{mt}; {iv} (signed extreme {signed}″ at {pos}°)" in summary
    assert "±" + mt not in summary.split("Uncertainty of")[0]       # no ± U for E
    dcc = (run["dir"] / "en" / "certificate.dcc.xml").read_text()
    assert f"<si:value>{mt}</si:value>" in dcc and f"<si:value>{signed.lstrip('+')}</si:value>" in dcc
    if res["extra"]["uncertainty"].get("u_c_certified", True) is False:
        # U = k·u + b: no standard uncertainty of E, the interval's ends as a list
        assert f"<si:valueXMLList>{lo_t} {hi_t}</si:valueXMLList>" in dcc
    else:
        assert f"<si:intervalMax>{hi_t}</si:intervalMax>" in dcc


def test_summary_and_certificate_use_the_same_numbers(run):
    """Every item's stated value and U in summary.txt equal the certificate's (one rule)."""
    res = run["results"]
    page = (run["dir"] / "en" / "certificate.html").read_text()
    table = page[page.index('<table id="results">'):]
    table = table[:table.index("</table>")]
    summary = (run["dir"] / "summary.txt").read_text()
    for name in ("scale_factor", "zero_stability", "repeatability", "rate_consistency",
                 "angle_deviation"):
        st = stated_item(res, name)
        # an estimate below zero is stated by its upper bound alone (its own number)
        num = st["interval"]["stated_value"] if st.get("below_zero") else st["value"]
        assert f'data-src="{num.src}"' in table
        assert f">{html.escape(num.text)}</span>" in table
        line = next(li for li in summary.splitlines() if res["items"][name]["title"] in li)
        assert num.text in line, (name, line)
    # U to two significant digits, the same in both; u_c not "0.2″" beside "0.20″"
    U = res["extra"]["uncertainty"]["U_arcsec"]
    uc = res["extra"]["uncertainty"]["u_c_arcsec"]
    # the per-point U stated (with the table's bound, U = k·u + b, where the points carry it)
    Us = res["extra"]["uncertainty"].get("U_bound_arcsec") or U
    assert f"U = {half_up(Us, u_decimals(Us))}″" in summary
    if res["extra"]["uncertainty"].get("u_c_certified", True) is False:
        # U = k·u + b: u of the lines other than the table's is stated, no u_c of E
        u = res["extra"]["uncertainty"]["u_without_table_arcsec"]
        assert f"u = {half_up(u, u_decimals(u))}″" in summary
        assert f"u_c = {half_up(uc, u_decimals(uc))}″" not in summary
    else:
        assert f"u_c = {half_up(uc, u_decimals(uc))}″" in summary
    # R shown at E's decimal place everywhere (figure legend included)
    R = half_up(res["items"]["repeatability"]["value"], u_decimals(U))
    assert stated_item(res, "repeatability")["value"].text == R


def test_coverage_probability_beside_every_U(run):
    page = visible_text((run["dir"] / "en" / "certificate.html").read_text())
    # k: fixed by the laboratory or t95(ν_eff) (1.96 with E's per-point r of pooled ν)
    assert re.search(r"U = [\d.]+″, k = [\d.]+, coverage probability 95 %", page)
    summary = (run["dir"] / "summary.txt").read_text()
    for line in summary.splitlines():
        if re.search(r"\bU = |\d \(k = ", line):
            assert "95 %" in line, line
    # the laboratory's conformity statements are in summary.txt as on the certificate
    assert re.search(r"conformity angle_deviation: (pass|conditional pass|conditional fail|fail)"
                     r" \(limits \[-0\.5, 0\.5\], rule non-binary", summary), summary


def test_per_item_uncertainty_is_shown_when_results_carry_it(run):
    res = json.loads(json.dumps(run["results"]))
    res["items"]["scale_factor"]["uncertainty"] = {
        "components": [], "u_c": 0.0123, "U": 0.0246, "k": 2.0, "nu_eff": None,
        "coverage_probability": 0.95, "unit": "counts/deg"}
    st = stated_item(res, "scale_factor")
    assert st["U"].text == "0.025" and st["k"].text == "2" and st["p"] == "95"
    assert st["value"].text == half_up(res["items"]["scale_factor"]["value"], 3)   # U's place
    assert "0.025 (k = 2, p = 95 %)" in summary_text(res)
    bare = json.loads(json.dumps(run["results"]))
    bare["items"]["scale_factor"]["uncertainty"] = None   # an item without its uncertainty
    without = stated_item(bare, "scale_factor")
    assert without["U"] is None and "—" in summary_text(bare).splitlines()[2]


def test_method_statement_lists_the_settings(run):
    page = visible_text((run["dir"] / "en" / "certificate.html").read_text())
    for s in ("Table rates", "1, 30, 60 °/s", "Rounds and series", "3 series", "read ",
              "Earth-rate compensation", "static phase of 30 s", "Site latitude",
              "Axis orientations", "up, north", "Tilt of the sensing plane",
              "(20 ± 1) °C", "during calibration 20.1 °C", "clauses 7.1, 7.2, 7.3"):
        assert s in page, s


def test_conformity_only_with_limits_and_outcome_from_closed_form(run, tmp_path):
    res = run["results"]
    virtual = visible_text((run["dir"] / "zh" / "certificate.html").read_text())
    assert LABELS["conformity"]["zh"] not in virtual and "符合性" not in virtual
    page = visible_text((run["dir"] / "en" / "certificate.html").read_text())
    assert "Statement of conformity" in page and "non-binary" in page
    # lab example: E within ±0.5″, w = U, non-binary
    y = res["items"]["angle_deviation"]["value"]
    U = res["extra"]["uncertainty"]["U_arcsec"]
    u = U / 2.0
    p_c = norm.cdf((0.5 - y) / u) - norm.cdf((-0.5 - y) / u)
    if abs(y) <= 0.5 - U:
        outcome = "pass"
    elif abs(y) <= 0.5:
        outcome = "conditional pass"
    elif abs(y) <= 0.5 + U:
        outcome = "conditional fail"
    else:
        outcome = "fail"
    html_page = (run["dir"] / "en" / "certificate.html").read_text()
    table = html_page[html_page.index('<table id="conformity">'):]
    table = table[:table.index("</table>")]
    cells = [visible_text(c).strip() for c in re.findall(r"<td>(.*?)</td>", table)]
    row = cells[cells.index("Angle-position deviation E"):][:5]
    assert row[1] == "[\u22120.5, 0.5] ″", row      # the limits as given, with the minus sign
    assert row[3].startswith(outcome), (row, outcome)
    if res["items"]["angle_deviation"]["uncertainty"].get("k_source") == "max-abs-interval":
        # E stated by the interval of max|E_i|: no normal model, no probability stated
        assert row[4] == "—", row
    elif outcome in ("pass", "conditional pass"):
        assert float(row[4].rstrip(" %")) == pytest.approx(100 * (1 - p_c), rel=0.05, abs=0.051)
    # a lab file with limits but no rule is refused, naming the key
    text = LAB.read_text().replace('[decision_rule]\nrule = "non-binary"\nguard_band_factor = 1.0\n'
                                   'agreed = "with the customer at contract review, 2026-11-02"\n',
                                   "")
    bad = tmp_path / "lab.toml"
    bad.write_text(text)
    with pytest.raises(GonioError, match="key decision_rule"):
        cert.load_lab(bad)
    bad.write_text(LAB.read_text().replace("mpe = 0.5", "mpe = 0.5\nupper = 0.4"))
    with pytest.raises(GonioError, match=r"specification_limits\[0\].*not both"):
        cert.load_lab(bad)


def test_chinese_is_complete(run):
    res = run["results"]
    for note in res["readings_taken"]:
        assert any(note.startswith(p) for p in READING_NOTES_ZH), f"no zh form: {note[:40]}"
    for c in res["extra"]["uncertainty"]["components"]:
        assert c["symbol"] in BUDGET_SOURCES_ZH, c["symbol"]
    missing = [k for k, v in LABELS.items() if not v.get("zh")]
    assert not missing
    page = visible_text((run["dir"] / "zh" / "certificate.html").read_text())
    for english in ("(draft for comment)", " rows)", "standard table positioning", "zero drift",
                    "position (°)", "rate (°/s)", "reference condition", "round",
                    "7.3: the protocol", "Annex A.4.4: u(r)",
                    "signed extreme", "approximately"):
        assert english not in page, english
    assert re.search(r"\d+ 行）", page)                  # full-width (the bracket rule)


def test_units_never_wrap(run):
    page = (run["dir"] / "zh" / "certificate.html").read_text()
    assert '<span class="nb">脉冲数/(°)</span>' in page
    text = "".join(pdf_pages(run["dir"] / "zh" / "certificate.pdf"))
    assert "脉冲数/(°)" in text


# --------------------------------------------------------------------------- layout

def test_every_printed_page_has_identifier_and_page_x_of_y(run):
    cid_en = run["lab"]["certificate"]["number"]
    cid_zh = cert.certificate_id(run["results"], None)
    for lang, cid, fmt in (("en", cid_en, "Page {x} of {y}"), ("zh", cid_zh, "第 {x} 页 共 {y} 页")):
        for pdf in (run["dir"] / lang / "certificate.pdf", run["printed"][lang]):
            pages = pdf_pages(pdf)
            assert len(pages) >= 3, pdf
            for i, page in enumerate(pages, 1):
                assert cid in page, (pdf.name, lang, i)
                flat = re.sub(r"\s+", "", page)      # Chromium's text drops CJK spacing
                assert re.sub(r"\s+", "", fmt.format(x=i, y=len(pages))) in flat, \
                    (pdf.name, lang, i)
                assert "Page 1 of 1" not in page and "第 1 页 共 1 页" not in page or len(pages) == 1


def test_html_on_screen_has_no_page_numbers(run):
    page = (run["dir"] / "en" / "certificate.html").read_text()
    body = page[page.index("<body>"):]
    assert "Page 1 of" not in body and 'id="page-of"' not in body
    assert "@page" in page and "counter(pages)" in page


def test_identifiers_never_break(run):
    for pdf in (run["dir"] / "en" / "certificate.pdf", run["printed"]["en"]):
        raw = subprocess.run([tool("pdftotext"), str(pdf), "-"], capture_output=True, text=True,
                             check=True).stdout
        for ident in ("NIM-2026-A-0123", "GON-2026-0017", "RLG-0001", "angle-lab@example.org"):
            assert ident in raw, (pdf.name, ident)


def _headings(run, lang):
    L = labels(lang)
    blocks = cert.certificate_blocks(run["results"], L, lab=run["lab"] if lang == "en" else None,
                                     truth=None, lang=lang)["blocks"]
    return {b.data.strip() for b in blocks if b.kind in ("h", "sub")}


def test_no_page_ends_with_a_heading(run):
    for lang in ("en", "zh"):
        heads = _headings(run, lang)
        for pdf in (run["dir"] / lang / "certificate.pdf", run["printed"][lang]):
            pages = pdf_pages(pdf)
            for i, page in enumerate(pages[:-1], 1):
                lines = [li.strip() for li in page.splitlines() if li.strip()]
                body = [li for li in lines if not re.search(
                    r"Certificate No\.|证书编号|Page \d+ of|第 \d+ 页|shall not be reproduced|"
                    r"不得部分复制|Example Angle Metrology|gonio", li)]
                assert body, (pdf.name, i)
                assert body[-1] not in heads, (pdf.name, lang, i, body[-1])


def test_rate_and_pointing_tables_labelled_reference_first(run):
    blocks = cert.certificate_blocks(run["results"], labels("en"), lab=None, truth=None)["blocks"]
    tables = {b.extra["id"]: b.data for b in blocks if b.kind == "table"
              and isinstance(b.extra, dict) and b.extra["id"].startswith("table-")}
    assert set(tables) == {"table-rate_consistency", "table-pointing_consistency"}
    for head, rows in tables.values():
        assert all(str(h).strip() for h in head), head
        assert rows[0][1] == "reference condition"
        assert all(r[1] == "compared" for r in rows[1:])


# --------------------------------------------------------------------------- figures

def _draw(run, draw, L=None):
    fig = Figure(figsize=HTML_FIGSIZE)
    with mpl_style():
        draw(fig, fig.add_gridspec(1, 1)[0], run["results"], L or labels("en"), run["truth"])
        fig.canvas.draw()
    return fig


def test_figures_have_no_offset_labels_and_legends_outside_the_data(run):
    for key, _, draw in figs.FIGURES:
        fig = _draw(run, draw)
        for ax in fig.axes:
            assert ax.yaxis.get_offset_text().get_text() == "", key
            assert ax.xaxis.get_offset_text().get_text() == "", key
            leg = ax.get_legend()
            if leg is not None:
                lb = leg.get_window_extent()
                ab = ax.get_window_extent()
                assert lb.y0 >= ab.y1 - 1.0, (key, lb, ab)     # above the axes, not over data


def test_figure_numbers_rounded_as_the_tables(run):
    res = run["results"]
    fig = _draw(run, figs.draw_repeatability)
    labels_ = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    R = stated_item(res, "repeatability")["value"].text
    assert any(lab.endswith(f" {R}″") for lab in labels_), labels_
    fig = _draw(run, figs.draw_rate)
    labels_ = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels_[0] == "60 °/s (reference)" and "1 °/s" in labels_ and "30 °/s" in labels_


def test_zero_stability_drift_comes_from_results(run):
    res = run["results"]
    row = res["items"]["zero_stability"]["details"]["table"][0]
    rd = [r for r in res["items"]["zero_stability"]["details"]["readings"]
          if r["series"] == row["series"]]
    t = np.array([r["time_s"] for r in rd]) - rd[0]["time_s"]
    m = np.array([r["angle_deg"] for r in rd])
    slope = ((t - t.mean()) * (m - m.mean())).sum() / ((t - t.mean()) ** 2).sum()  # closed form
    assert row["drift_deg_per_h"] == pytest.approx(slope * 3600.0, rel=1e-9)
    fig = _draw(run, figs.draw_zero_stability)
    line = [ln for ln in fig.axes[0].get_lines() if ln.get_linestyle() == "-"][0]
    y = np.asarray(line.get_ydata())
    expect = (row["drift_intercept_deg"] + row["drift_deg_per_h"] * t / 3600.0) * 3600.0
    assert y == pytest.approx(expect, rel=1e-9, abs=1e-9)
    assert "polyfit" not in Path(figs.__file__).read_text()


def test_importing_the_report_does_not_switch_the_backend():
    code = ("import matplotlib; b = matplotlib.get_backend(); "
            "import gonio.specs.ogam_draft.certificate_pages, gonio.report.figures, "
            "gonio.specs.ogam_draft.figures, gonio.specs.ogam_draft.dcc; "
            "assert matplotlib.get_backend() == b, (b, matplotlib.get_backend()); print(b)")
    env = dict(os.environ, MPLBACKEND="svg", PYTHONPATH=str(Path(cert.__file__).parents[3]))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "svg"


def test_english_certificate_without_cjk_font_has_no_tofu(run, monkeypatch):
    def no_font():
        raise GonioError("no CJK font")
    from gonio.report import render
    monkeypatch.setattr(render, "cjk_font", no_font)
    res = json.loads(json.dumps(run["results"]))
    res["extra"]["method"]["specification"] = "JJF xxxx 光学陀螺测角仪校准规范 (draft for comment)"
    assert render.font_families("en") == ("DejaVu Sans",)
    assert render.cjk_notice("en") and "fonts-noto-cjk" in render.cjk_notice("en")
    content = cert.certificate_blocks(res, labels("en"), lab=None, truth=None,
                                      lang="en", cjk=False)
    spec = [v for b in content["blocks"] if b.kind == "kv" for k, v in b.data
            if k == "Specification followed"][0]
    assert "Optical Gyroscope Angle Measuring Instrument" in spec
    assert not re.search(r"[\u3400-\u9fff]", spec)


# --------------------------------------------------------------------------- CLI items

def test_cli_output_into_a_closed_pipe_exits_quietly():
    """stdout is a pipe whose reader is gone (``gonio ... --json | head``): exit 0, no trace."""
    code = ("import os, sys; r, w = os.pipe(); os.close(r); os.dup2(w, 1); "
            "from gonio.cli import main; rc = main(['budget', '--json']); "
            "sys.stderr.write(f'rc={rc}\\n'); sys.exit(rc)")
    env = dict(os.environ, PYTHONPATH=str(Path(cert.__file__).parents[3]))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stderr == "rc=0\n", p.stderr


def test_every_output_has_one_file_mode(run):
    modes = {f.relative_to(run["dir"]).as_posix(): f.stat().st_mode & 0o777
             for f in run["dir"].rglob("*") if f.is_file()
             and "chromium-profile" not in f.parts and not f.name.endswith("-print.pdf")}
    assert {"results.json", "summary.txt", "en/certificate.dcc.xml",
            "tables/uncertainty_budget.csv"} <= set(modes)
    assert len(set(modes.values())) == 1, modes


def test_stream_file_has_the_mode_of_every_other_output(tmp_path):
    from gonio.atomic import write_text
    from gonio.formats.streams import StreamWriter

    w = StreamWriter(tmp_path / "stream.csv", {"sample_rate_hz": "10"}, table=True)
    w.write(np.array([0.0, 0.1]), np.array([0, 1]), np.array([0.0, 0.0]))
    w.close()
    write_text(tmp_path / "other.txt", "x")
    assert (tmp_path / "stream.csv").stat().st_mode & 0o777 == \
        (tmp_path / "other.txt").stat().st_mode & 0o777


def test_demo_cli_help_and_wrote_list(run, tmp_path, monkeypatch, capsys):
    from gonio.cli import build_parser, cmd_demo

    sub = [a for a in build_parser()._actions if a.dest == "command"][0]
    seed = [a for a in sub.choices["demo"]._actions if a.dest == "seed"][0]
    assert seed.help and "seed" in seed.help
    out = tmp_path / "d"
    paths = [out / "results.json", out / "tables" / "uncertainty_budget.csv"]
    import gonio.cli.cmd_calibrate as cmd_calibrate
    import gonio.pipeline.dispatch as dispatch

    monkeypatch.setattr(dispatch, "demo", lambda *a, **k: (run["result"], dict(enumerate(paths))))
    monkeypatch.setattr(cmd_calibrate, "show", lambda *a, **k: None)
    args = build_parser().parse_args(["demo", "--out", str(out)])
    assert cmd_demo.run(args) == 0
    wrote = capsys.readouterr().out.splitlines()[-1]
    assert wrote == f"wrote results.json, tables/uncertainty_budget.csv in {out}"
    assert "lab-example" not in builtin_names()


def test_eda_error_bars_say_they_are_u():
    from gonio.specs.ogam_draft.equal_division import equal_division_analysis, simulate_eda_matrix

    sim = simulate_eda_matrix({1: 1.0}, {2: 0.2}, 8, 8, 1, 0.05, 0)
    from gonio.specs.ogam_draft.pages import equal_division_figure

    fig = equal_division_figure(equal_division_analysis(sim.D_arcsec, sim.start_deg,
                                                        sim.step_deg))
    for ax in fig.axes:
        texts = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any("± u (k = 1)" in t for t in texts), texts


def test_budget_kind_beyond_draft_lines_and_no_E(run):
    def physical(results):
        d = json.loads(json.dumps(results))
        d["extra"]["uncertainty"]["budget_kind"] = "physical"
        d["extra"]["uncertainty"]["components"][1]["beyond_draft"] = True
        return d
    blocks = cert.certificate_blocks(physical(run["results"]), labels("en"), lab=None,
                                     truth=None)["blocks"]
    text = " ".join("".join(str(x) for x in b.data) for b in blocks if b.kind == "p")
    assert "lines marked \"beyond the draft\" are not in Annex A" in text
    budget = [b.data for b in blocks if b.kind == "table" and b.data[0][0] == "Component"][0]
    marked = [r[1] for r in budget[1] if "(beyond the draft)" in r[1]]
    already = sum(bool(c.get("beyond_draft")) for i, c in
                  enumerate(run["results"]["extra"]["uncertainty"]["components"]) if i != 1)
    assert len(marked) == 1 + already
    res = physical(run["results"])
    assert "(physical budget)" in summary_text(res)
    res["extra"]["uncertainty"].update({"U_arcsec": None, "u_c_arcsec": None})
    res["items"]["angle_deviation"].update({"measured": False, "value": None,
                                            "reason": "no rows"})
    s = summary_text(res)
    assert "no uncertainty stated" in s and "±" not in s


def test_equal_division_errors_rounded_to_their_own_u(run):
    eda = {"n_starts": 4, "m_points": 2, "repeats": 1, "noise": "white",
           "table": {"position_deg": [0.0, 180.0], "error_arcsec": [0.00744, -0.31649],
                     "u_arcsec": [0.022, 0.0049]},
           "goniometer": {"angle_deg": [180.0, 360.0], "error_arcsec": [1.23456, 0.0],
                          "u_arcsec": [0.13, 0.0]},
           "closure": {"full_turn_arcsec": 0.01234, "u_full_turn_arcsec": 0.0456}}
    res = {**run["results"], "extra": {**run["results"]["extra"], "equal_division": eda}}
    blocks = cert.certificate_blocks(res, labels("en"), lab=None, truth=None)["blocks"]
    i = [k for k, b in enumerate(blocks) if b.kind == "h" and "equal-division" in b.data][0]
    rows = [b for b in blocks[i:] if b.kind == "table"][0].data[1]
    assert [str(c) for c in rows[0]] == ["0", "0.007", "0.022", "180", "1.23", "0.13"]
    assert [str(c) for c in rows[1]][1:3] == ["-0.3165", "0.0049"]
    closure = [b for b in blocks[i:] if b.kind == "p"][-1].data
    assert "".join(str(x) for x in closure).endswith("= 0.012″ ± 0.046″")


def test_status_line_only_on_a_terminal():
    import io

    from gonio.progress import status

    class Tty(io.StringIO):
        def isatty(self):
            return True
    tty, pipe = Tty(), io.StringIO()
    status("demo: calibrating", tty)
    status("demo: calibrating", pipe)
    status("", tty)
    assert "demo: calibrating" in tty.getvalue() and tty.getvalue().startswith("\r")
    assert pipe.getvalue() == ""


def test_zh_says_where_k_comes_from_in_chinese(run):
    """Issue 13's zh gap: the line on the origin of k went through i18n."""
    ks = run["results"]["extra"]["uncertainty"].get("k_source")
    page = visible_text((run["dir"] / "zh" / "certificate.html").read_text(encoding="utf-8"))
    assert "t-factor" not in page and "welch-satterthwaite" not in page
    if ks:
        zh = labels("zh")
        assert (zh["k_fixed"] if ks == "fixed by laboratory" else zh["k_welch"]) in page


# --------------------------------------------------------------------------- zh brackets

#: ASCII brackets a Chinese page must not carry (docs/certificate.md#brackets-on-a-chinese-page):
#: brackets holding Chinese, brackets right after a Chinese character, a clause or definition
#: reference in brackets, and a unit in brackets after a Chinese name ("位置 (°)"; "(°)/h",
#: the unit symbol, is mathematics and stays).
ZH_ASCII_BRACKETS = (
    re.compile(r"\([^()]*[\u4e00-\u9fff][^()]*\)"),
    re.compile(r"[\u4e00-\u9fff]\("),
    re.compile(r"\((?:[A-Z]\.)?\d+(?:\.\d+)*(?:(?:, |、)(?:[A-Z]\.)?\d+(?:\.\d+)*)*\)"),
    re.compile(r"[\u4e00-\u9fff] \((?:°|″|min|s|%)\)(?!/)"),
)


def zh_bracket_problems(text: str) -> list[str]:
    """The pieces of ``text`` that break the bracket rule of a Chinese page."""
    return [m.group(0) for rx in ZH_ASCII_BRACKETS for m in rx.finditer(text)]


def test_the_bracket_check_can_fail_and_passes_mathematics():
    bad = ["readings.csv (SHA-256 ab…, 249 行)", "标度因数 K (7.1)", "位置 (°)", "微机电(MEMS)",
           "7.3 (3.3)", "角位置偏差 (7.4, 7.5)"]
    assert all(zh_bracket_problems(b) for b in bad), [b for b in bad if not zh_bracket_problems(b)]
    good = ["u(P)", "B_s = s(M)/T，并同时给出 (max M − min M)/T", "要求 (20 ± 1) °C（表2）",
            "(°)/h", "脉冲数/(°)", "速率（(°)/s）", "k = t₉₅(ν_eff)", "E_i (″)", "7.3（3.3）",
            "K_i（脉冲数/(°)）", "readings.csv（SHA-256 ab…，249 行）"]
    assert [g for g in good if zh_bracket_problems(g)] == []


def test_zh_certificate_uses_full_width_brackets_in_chinese_text(run):
    page = visible_text((run["dir"] / "zh" / "certificate.html").read_text(encoding="utf-8"))
    assert zh_bracket_problems(page) == []
    shown = [v["zh"] for v in LABELS.values()]           # the figures' text is drawn as paths
    assert [s for s in shown if zh_bracket_problems(s)] == []
