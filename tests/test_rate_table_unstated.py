"""A rate readings file that states no ``rate_table_u_rel`` (the rate table's certificate u)
is budgeted as a table within JJF 1535 Table 2's 0.05 %: the certificate, summary.txt and
results.json state that assumption as a flagged finding, naming whose it is — for IEC
62047-20 the laboratory's, taken from JJF 1535 Table 2, not IEC's requirement; a file that
states the u has no such finding (docs/formats.md#rate-gyro-metadata)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from gonio.specs._rate_family.screening import RATE_TABLE_UNSTATED_CODE

PINS = Path(__file__).resolve().parent / "data" / "pins"


def gonio(*args, cwd: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "gonio", *map(str, args)], cwd=cwd,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def _stripped(src: Path, dst: Path) -> Path:
    text = src.read_text(encoding="utf-8")
    assert re.search(r"(?m)^# rate_table_u_rel:", text)
    dst.write_text(re.sub(r"(?m)^# rate_table_u_rel:.*\n", "", text), encoding="utf-8")
    return dst


@pytest.mark.parametrize("spec", ["iec62047-20", "jjf1535-2015"])
def test_an_unstated_rate_table_u_is_a_stated_assumption(spec, tmp_path):
    proto = PINS / f"{spec}-small.toml"
    gonio("simulate", "--spec", spec, "--protocol", proto, "--seed", 4, "--out",
          tmp_path / "sim", cwd=tmp_path)
    from gonio.specs import get

    screen = get(spec).screen
    sim = tmp_path / "sim" / "readings.csv"
    assert not [f for f in screen(sim, str(proto)) if f.code == RATE_TABLE_UNSTATED_CODE]
    quiet = _stripped(sim, tmp_path / "no-table-u.csv")
    gonio("calibrate", quiet, "--protocol", proto, "--out", tmp_path / "cal", cwd=tmp_path)
    res = json.loads((tmp_path / "cal" / "results.json").read_text(encoding="utf-8"))
    found = [f for f in res["findings"] if f["code"] == RATE_TABLE_UNSTATED_CODE]
    assert len(found) == 1 and found[0]["action"] == "flagged", res["findings"]
    msg = found[0]["message"]
    assert "not stated" in msg and "0.05 %" in msg and "rate_table_u_rel" in msg, msg
    if spec == "iec62047-20":
        assert "laboratory's assumption" in msg and "IEC 62047-20 states no requirement" in msg
    else:
        assert "laboratory's assumption" not in msg and "JJF 1535 Table 2" in msg
    summary = (tmp_path / "cal" / "summary.txt").read_text(encoding="utf-8")
    page = (tmp_path / "cal" / "certificate.html").read_text(encoding="utf-8")
    assert "uncertainty is not stated (no # rate_table_u_rel)" in summary
    assert "uncertainty is not stated (no # rate_table_u_rel)" in page
