"""The optical DCC states K's tilt correction where the certificate and summary.txt do: a
protocol with [tilt_estimate] gives the scale factor's dcc:quantity a description with the
measured ψ and α (their U95), the 7.1 mean uncorrected and the K_te line; the document stays
valid against the DCC 3.3.0 schema; without [tilt_estimate] K has no such description (only,
where K's k comes from its budget's combined distribution, the sentence that says so)."""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import pytest
from lxml import etree

from gonio.cli import main

SMALL = Path(__file__).parent / "data" / "small-protocol.toml"
TILT_ESTIMATE = ('[tilt_estimate]\npositions = 8\ndwell_s = 30.0\nsettle_s = 5.0\n'
                 'orientation = "up"\nrate_dps = 60.0\n')
NS = {"dcc": "https://ptb.de/dcc"}


def _run(tmp: Path, tilt: bool) -> Path:
    proto = tmp / "protocol.toml"
    proto.write_text(SMALL.read_text("utf-8") + ("\n" + TILT_ESTIMATE if tilt else ""), "utf-8")
    assert main(["simulate", "--protocol", str(proto), "--seed", "3", "--out",
                 str(tmp / "sim")]) == 0
    assert main(["calibrate", str(tmp / "sim" / "readings.csv"), "--protocol", str(proto),
                 "--dcc", "--out", str(tmp / "cal")]) == 0
    return tmp / "cal"


def _k_description(cal: Path) -> list[str]:
    doc = etree.parse(str(cal / "certificate.dcc.xml"))
    return [t for t in doc.xpath("//dcc:result[@id='result-scale_factor']/dcc:data/"
                                 "dcc:quantity/dcc:description/dcc:content/text()",
                                 namespaces=NS)]


def test_the_dcc_states_the_tilt_correction(tmp_path, dcc_schema):
    cal = _run(tmp_path, tilt=True)
    xml = (cal / "certificate.dcc.xml").read_text("utf-8")
    errors = list(dcc_schema.iter_errors(xml))
    assert not errors, str(errors[0])[:500]
    (text,) = _k_description(cal)
    # the same ψ, α and U95 as summary.txt prints them (its own formatting, in degrees)
    summary = (cal / "summary.txt").read_text("utf-8")
    m = re.search(r"corrected by the measured tilt psi = (\S+) deg \(U95 (\S+) deg\) at azimuth "
                  r"(\S+) deg \(U95 (\S+) deg\)", summary)
    assert m, summary
    psi, u_psi, az, u_az = m.groups()
    assert f"ψ = {psi}° (U = {u_psi}°)" in text and f"azimuth {az}° (U = {u_az}°)" in text, text
    assert "K_te" in text and "7.1 mean uncorrected" in text
    # the certificate's K cell says the same sentence
    page = html.unescape(re.sub(r"<[^>]+>", "", (cal / "certificate.html").read_text("utf-8")))
    page = page.replace("\xa0", " ")                   # the page binds "ψ = 0.05" together
    assert text.removeprefix("K ").split("; U(K)")[0] in page
    # the method's tilt row says the tilt was measured (8 positions here) and K corrected
    assert "measured in situ at 8 rest positions" in page


def test_without_tilt_estimate_k_has_no_tilt_description(tmp_path):
    cal = _run(tmp_path, tilt=False)
    descs = _k_description(cal)
    assert not any("measured tilt" in d or "K_te" in d for d in descs), descs
    # the one description K may carry says where its k comes from, as results.json does
    src = json.loads((cal / "results.json").read_text("utf-8"))[
        "items"]["scale_factor"]["uncertainty"]["k_source"]
    assert len(descs) == (src == "jcgm101-convolution")
    assert all("JCGM 101" in d for d in descs)
    assert "measured in situ" not in (cal / "certificate.html").read_text("utf-8")


def test_every_printed_psi_is_stated_by_one_rule(shared_demo):
    """The optical demo measures its tilt in situ: every ψ and α the outputs print — the K
    note, the K-as-mounted paragraph, the E correction's note and budget line, the
    calibration's notes in results.json and summary.txt, the DCC — is the one statement rule's
    (the value at its U95's decimal place), so a certificate never shows ψ two ways."""
    from gonio.result.statement import state

    out = shared_demo("ogam-draft")
    res = json.loads((out / "results.json").read_text("utf-8"))
    tc = res["items"]["scale_factor"]["details"]["tilt_correction"]
    psi = state(tc["tilt_deg"], tc["U95_tilt_deg"]).value_text
    az = state(tc["azimuth_deg"], tc["U95_azimuth_deg"]).value_text
    texts = {"summary.txt": (out / "summary.txt").read_text("utf-8"),
             "results.json": (out / "results.json").read_text("utf-8"),
             "certificate.dcc.xml": (out / "certificate.dcc.xml").read_text("utf-8"),
             "certificate.html": html.unescape(re.sub(
                 r"<[^>]+>", "", (out / "certificate.html").read_text("utf-8"))).replace(
                     "\xa0", " ")}
    seen = 0
    for name, t in texts.items():
        for m in re.finditer(r"(?:psi|ψ) = ([0-9.]+) ?(?:°|deg)", t):
            assert m.group(1) == psi, (name, t[max(m.start() - 80, 0):m.end() + 40], psi)
            seen += 1
        for m in re.finditer(r"azimuth ([0-9.]+) ?(?:°|deg)", t):
            assert m.group(1) == az, (name, t[max(m.start() - 80, 0):m.end() + 40], az)
    assert seen >= 6
