"""The room temperature the certificate states from the readings' metadata is the room's only
where the specification says that key is the room's (docs/formats.md#identity-and-conditions,
``room_temperature_keys``): IEC 62047-20's ``# room_temperature_c`` is its chamber's base
temperature T_BASE, a set point, and is never stated as the environment's temperature; the
other specifications' is the room's.

From the outside, for every specification: ``gonio simulate``, its readings given a
``# room_temperature_c`` line and no ``# temperature_c`` (the optical draft's, which know no
``room_temperature_c``: a ``# temperature_c`` line), ``gonio calibrate --lab --dcc`` with a
laboratory file that states no temperature; the certificate's environment row (HTML), the
DCC's influence conditions and summary.txt are read. The stored result rendered again (the
specification's renderer, as the records do) gives the same bytes, and a flagged temperature
contradiction in summary.txt takes its text by the same rule.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

import pytest
from lxml import etree

from gonio.cli import main
from gonio.formats.lab import load_lab
from gonio.result.findings import Finding
from gonio.result.model import Result
from gonio.specs import get
from tests.test_provenance import lab_file, simulated

PINS = Path(__file__).resolve().parent / "data" / "pins"
#: (specification, a small protocol of tests/data/pins or None, the metadata key written,
#: whether it states the room's temperature: known from the standards, not from gonio).
#: IEC 62047-20 runs every test in the chamber at its base temperature T_BASE, the midpoint
#: of the operating range, and its readings' ``room_temperature_c`` is T_BASE. The optical
#: draft's readings know no ``room_temperature_c`` (refused as a misspelt key): their
#: ``temperature_c`` is written.
CASES = (("ogam-draft", "ogam-draft-small.toml", "temperature_c", True),
         ("jjf1535-2015", "jjf1535-2015-small.toml", "room_temperature_c", True),
         ("iec62047-20", "iec62047-20-small.toml", "room_temperature_c", False),
         ("triad-alignment", None, "room_temperature_c", True))
#: The value given where the simulated readings state none (the triad's).
ADDED_C = "23.7"
DCC_NS = {"dcc": "https://ptb.de/dcc", "si": "https://ptb.de/si"}


@pytest.fixture(scope="module", params=CASES, ids=[c[0] for c in CASES])
def calibrated(request, tmp_path_factory, shared_simulation):
    """(spec, room?, the readings' room_temperature_c text, lab path, calibrate's folder)."""
    spec, protocol, key, is_room = request.param
    work = tmp_path_factory.mktemp(spec)
    proto = [] if protocol is None else ["--protocol", str(PINS / protocol)]
    simulated(shared_simulation, spec, protocol, 3, work / "sim")     # gonio simulate's set
    text = (work / "sim" / "readings.csv").read_text(encoding="utf-8")
    m = re.search(r"(?m)^# (?:room_)?temperature_c: *(\S+)$", text)
    value = m.group(1) if m else ADDED_C
    text = re.sub(r"(?m)^# (?:room_)?temperature_c:[^\n]*\n", "", text)
    readings = work / "sim" / "room.csv"      # beside the files the readings name
    readings.write_text(f"# {key}: {value}\n" + text, encoding="utf-8")
    lab = lab_file(work)                      # no [environment]
    lab.write_text(re.sub(r"^\[instrument\]\n.*?\n\n", "", lab.read_text(encoding="utf-8"),
                          flags=re.S | re.M), encoding="utf-8")
    out = work / "cal"
    assert main(["calibrate", str(readings), "--spec", spec, *proto, "--lab", str(lab),
                 "--dcc", "--out", str(out)]) == 0
    return spec, is_room, value, lab, out


def environment_temperature(page: str) -> str:
    """The text of the certificate's environment temperature row (HTML): the first row named
    Temperature, under the environment's heading (the optical certificate's conditions
    table, after it, has its own)."""
    page = page[page.index("Environment during calibration"):]
    rows = re.findall(r"<td>Temperature</td><td>(.*?)</td>", page)
    assert rows, "no temperature row"
    return html.unescape(rows[0])


def dcc_temperatures(xml: bytes) -> dict[str, str]:
    """The DCC's influence conditions whose name says temperature: {name: si:value}."""
    root = etree.fromstring(xml)
    out = {}
    for ic in root.iterfind(".//dcc:influenceCondition", DCC_NS):
        name = ic.findtext("dcc:name/dcc:content", namespaces=DCC_NS) or ""
        if "temperature" in name and "chamber" not in name:
            out[name] = ic.findtext(".//si:value", namespaces=DCC_NS)
    return out


def test_environment_temperature_by_the_specification(calibrated):
    spec, is_room, value, lab, out = calibrated
    row = environment_temperature((out / "certificate.html").read_text(encoding="utf-8"))
    conds = dcc_temperatures((out / "certificate.dcc.xml").read_bytes())
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    if is_room:
        assert row == f"{value} °C (taken from the readings' metadata)", row
        assert list(conds.values()) == [value], conds
    else:                                      # T_BASE is not the room's
        assert row == "not stated", row
        assert conds == {}, conds
        assert not re.search(rf"temperature: {re.escape(value)} °C", summary), summary


def test_rendered_again_the_same_and_summary_by_the_same_rule(calibrated, tmp_path):
    """The stored result rendered again by its specification's renderer gives summary.txt
    and the DCC byte for byte; a flagged temperature contradiction (a laboratory file stating
    none) is stated with the readings' room temperature only where it is the room's."""
    spec, is_room, value, lab, out = calibrated
    result = Result.from_json(json.loads((out / "results.json").read_text(encoding="utf-8")))
    renderer = get(spec).renderer()
    again = tmp_path / "again"
    again.mkdir()
    renderer.write(result, again, lab=load_lab(lab), dcc=True)
    for name in ("summary.txt", "certificate.dcc.xml"):
        assert (again / name).read_bytes() == (out / name).read_bytes(), name
    result.findings.append(Finding("identity-mismatch", "temperature: the readings say so",
                                   "flagged", subject="temperature"))
    line = next(x for x in renderer.summary(result, None).splitlines()
                if x.startswith("temperature: "))
    stated = f"{value} °C" if is_room else "not stated"
    assert line.startswith(f"temperature: {stated} [CONTRADICTED"), line
