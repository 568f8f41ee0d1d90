"""The probabilities a DCC's conformity statement carries are the certificate's, to the digit:
p_c and the false-reject probability at three significant digits, the false-accept at two, as
the certificate's conformity table prints them (before: the optical DCC wrote a false-reject
43.5 % as 0.44 and no p_c; the rate DCCs wrote the false-accept at three digits)."""
from __future__ import annotations

import html as html_module
import re
from decimal import Decimal
from pathlib import Path

import pytest
from lxml import etree

ROOT = Path(__file__).resolve().parents[1]
NS = {"dcc": "https://ptb.de/dcc", "si": "https://ptb.de/si"}


def _lab(tmp_path, spec: str) -> Path:
    text = (ROOT / "protocols" / "lab-example.toml").read_text(encoding="utf-8")
    if spec == "jjf1535-2015":
        text = text.split("\n[[specification_limits]]")[0] + (
            '\n[[specification_limits]]\nitem = "bias_stability"\nupper = 51.5\n'
            '\n[[specification_limits]]\nitem = "warmup_time"\nupper = 60\n'
            '\n[[specification_limits]]\nitem = "scale_factor"\nlower = 5.99\nupper = 5.9991\n')
    else:
        text = text.replace("upper = 0.3", "upper = 0.118")
    p = tmp_path / f"{spec}.toml"
    p.write_text(text, encoding="utf-8")
    return p


@pytest.mark.parametrize("spec", ["ogam-draft", "jjf1535-2015"])
def test_dcc_probabilities_are_the_certificates(tmp_path, capsys, spec):
    from gonio.cli import main

    out = tmp_path / "out"
    assert main(["demo", "--spec", spec, "--lab", str(_lab(tmp_path, spec)),
                 "--out", str(out)]) == 0
    page = (out / "certificate.html").read_text(encoding="utf-8")
    table = re.search(r'<table[^>]*id="conformity"[^>]*>(.*?)</table>', page, re.S)
    assert table, "no conformity table"
    cells = html_module.unescape(re.sub(r"<[^>]+>", " ", table.group(1)))
    shown = {Decimal(x) for x in re.findall(r"(\d+(?:\.\d+)?) %", cells)}
    root = etree.parse(str(out / "certificate.dcc.xml")).getroot()
    seen = 0
    for st in root.iterfind(".//dcc:statement", NS):
        for q in st.iterfind("dcc:data/dcc:quantity", NS):
            name = q.find("dcc:name/dcc:content", NS).text
            if "probability" not in name:
                continue
            v = Decimal(q.find("si:real/si:value", NS).text) * 100
            digits = 2 if "false-accept" in name else 3
            assert len(v.normalize().as_tuple().digits) <= digits, (name, v)
            assert v.normalize() in {x.normalize() for x in shown}, (name, v, sorted(shown))
            seen += 1
    assert seen >= 2, seen
