"""The optical draft's E (7.4, E = ± max|E_i|) states one number with one meaning in every
output: results.json ``items.angle_deviation.value`` is max|E_i|, the value the certificate
(HTML and PDF), summary.txt, tables/items.csv and the DCC certify; the signed extreme is
``details.signed_extreme_arcsec``. Checked on a hand-made readings file whose extreme is
negative (the case where the two meanings differ), against the E_i computed here from the
deviations the file was written with."""

from __future__ import annotations

import csv
import json
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main

ROOT = Path(__file__).resolve().parents[1]

PROTO = """[protocol]
name = "e-sign"
[scale_factor]
rounds = [{stop_deg = 120.0}, {stop_deg = 240.0}, {stop_deg = 360.0}]
[angle_deviation]
series = 5
max_time_to_reading_s = 30.0
rounds = [{stop_deg = 90.0}, {stop_deg = 180.0}, {stop_deg = 270.0}, {stop_deg = 360.0}]
"""

#: Deviations E_ij (″), series × round: the means E_i are −0.20, +0.26, −0.30, −0.26, so
#: the signed extreme is −0.30″ at 270° and max|E_i| = 0.30″.
E = -np.array([[0.30, -0.20, 0.10, 0.40],
               [0.10, -0.40, 0.30, 0.20],
               [0.20, -0.30, 0.50, 0.30],
               [0.40, -0.10, 0.20, 0.10],
               [0.00, -0.30, 0.40, 0.30]])
POS = [90.0, 180.0, 270.0, 360.0]


def write_case(d: Path) -> tuple[Path, Path]:
    (d / "p.toml").write_text(PROTO)
    lines = ["# latitude_deg: 40.0\n",
             "test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg\n"]
    for i, th in enumerate((120.0, 240.0, 360.0), 1):
        lines.append(f"scale_factor,1,{i},60,up,{5 + i},{th},{int(th * 36000)},\n")
    for j in range(E.shape[0]):
        for i, th in enumerate(POS):
            lines.append(f"angle_deviation,{j + 1},{i + 1},60,up,{10.0 + i},{th},,"
                         f"{float(th + E[j, i] / 3600)!r}\n")
    (d / "readings.csv").write_text("".join(lines))
    return d / "readings.csv", d / "p.toml"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("e_sign")
    f, p = write_case(d)
    assert main(["calibrate", str(f), "--protocol", str(p), "--out", str(d / "out"),
                 "--lab", str(ROOT / "protocols" / "lab-example.toml"), "--dcc"]) == 0
    return d / "out"


def _text(html: str) -> str:
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html)).replace("&#x27;", "'")


def test_results_json_value_is_the_certified_magnitude(run):
    e_i = E.mean(axis=0)
    at = int(np.argmax(np.abs(e_i)))
    assert e_i[at] < 0                                   # the case the meanings differ in
    it = json.loads((run / "results.json").read_text())["items"]["angle_deviation"]
    assert it["value"] == pytest.approx(abs(e_i[at]), abs=1e-6)
    assert it["details"]["max_abs_arcsec"] == pytest.approx(it["value"], abs=0)
    assert it["details"]["signed_extreme_arcsec"] == pytest.approx(e_i[at], abs=1e-6)
    assert it["details"]["position_deg"] == POS[at]
    # the statement is of that value: its interval holds it, U is its reach above it
    lo, hi = it["uncertainty"]["interval"]
    assert lo <= it["value"] <= hi
    assert it["uncertainty"]["U"] == pytest.approx(hi - it["value"], rel=1e-12)


def test_every_output_states_the_same_value(run):
    res = json.loads((run / "results.json").read_text())
    it = res["items"]["angle_deviation"]
    v, s = it["value"], it["details"]["signed_extreme_arcsec"]
    v_txt, s_txt = f"{v:.2f}", f"{s:+.2f}".replace("+", "")      # 0.30 and -0.30
    # summary.txt: "0.30; ≤ … (p = 95 %) (signed extreme -0.30″ at 270°)"
    line = next(ln for ln in (run / "summary.txt").read_text().splitlines()
                if "angle-position deviation E" in ln)
    assert re.search(rf"7\.4\s+{re.escape(v_txt)}; ≤ ", line), line
    assert f"signed extreme {s_txt}″ at 270°" in line, line
    # tables/items.csv
    rows = {r["item"]: r for r in csv.DictReader((run / "tables" / "items.csv").open())}
    assert float(rows["angle_deviation"]["value"]) == pytest.approx(v, abs=1e-12)
    # the certificate: the value cell reads the value, the signed extreme its own detail
    html = (run / "certificate.html").read_text()
    cell = re.search(r'<span[^>]*data-src="items\.angle_deviation\.(value|details\.'
                     r'max_abs_arcsec)"[^>]*>([^<]*)</span>', html)
    assert cell and cell.group(2).strip().lstrip("±") == v_txt, cell and cell.group(0)
    signed = re.search(r'<span[^>]*data-src="items\.angle_deviation\.details\.'
                       r'signed_extreme_arcsec"[^>]*>([^<]*)</span>', html)
    assert signed and signed.group(1).replace("−", "-").strip() == s_txt
    flat = re.sub(r"\s", "", _text(html)).replace("−", "-")
    assert f"signedextreme{s_txt}″at270°" in flat
    assert re.search(rf"7\.4{re.escape(v_txt)};≤", flat)
    # the DCC: E's quantity holds the value, the signed extreme its own quantity
    root = ET.parse(run / "certificate.dcc.xml").getroot()
    ns = {"dcc": "https://ptb.de/dcc", "si": "https://ptb.de/si"}
    q = {}
    for quant in root.iterfind(".//dcc:result[@id='result-angle_deviation']//dcc:quantity", ns):
        name = quant.find("dcc:name/dcc:content", ns)
        val = quant.find(".//si:value", ns)
        if name is not None and val is not None:
            q.setdefault(name.text, float(val.text))
    assert q["E = ± max|E_i| (draft 7.4)"] == pytest.approx(v, abs=0.005)
    assert q["signed extreme of E_i"] == pytest.approx(s, abs=0.005)
    assert q["E = ± max|E_i| (draft 7.4)"] > 0 > q["signed extreme of E_i"]


@pytest.mark.skipif(shutil.which("pdftotext") is None, reason="needs pdftotext")
def test_pdf_states_the_same_value(run):
    it = json.loads((run / "results.json").read_text())["items"]["angle_deviation"]
    txt = subprocess.run(["pdftotext", str(run / "certificate.pdf"), "-"], capture_output=True,
                         text=True, check=True).stdout
    txt = re.sub(r"\s", "", txt).replace("−", "-")
    s_txt = f"{it['details']['signed_extreme_arcsec']:.2f}"
    assert re.search(rf"{it['value']:.2f};≤", txt)
    assert f"signedextreme{s_txt}″at270°" in txt
