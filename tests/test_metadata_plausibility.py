"""Metadata stated in another unit or scale than the readings show, written into a copy of a
``gonio simulate`` file and calibrated as a laboratory would:

- rate files (JJF 1535, IEC 62047-20): a ``null_output`` of 2.5 where the outputs are logged
  in mV (null 2500 mV) is refused in one line naming the key and both values (it certified a
  bias of 1.5·10⁶ °/h); the bound is the largest rate of the scale-factor test;
- a ``nominal_scale_factor`` in another unit: flagged for JJF 1535 (no item reads it; every
  item is the clean file's), refused for IEC 62047-20 (a_TYP divides 5.1.3.2 and 5.1.3.8);
- optical draft: a nominal K ×1000 is flagged where 7.1 measures K (every item the clean
  file's), refused where the file has no 7.1 readings (it then reads every angle); a
  ``table_mpe_arcsec`` of 100″ against the protocol's 0.1″ is refused; a row whose
  ``gyro_deg`` contradicts its ``gyro_counts`` is refused by the screening hook itself, in
  the line ``gonio calibrate`` gives.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs import get
from tests.test_rate_screening import clean, simulated  # noqa: F401  (both rate specs)


def _gonio(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(argv)
    return rc, err.getvalue()


def _refused(argv: list[str]) -> str:
    rc, err = _gonio(argv)
    assert rc == 2, err[-2000:]
    lines = [x for x in err.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("gonio: error: "), err[-2000:]
    return lines[0]


def _with_meta(src: Path, dst: Path, key: str, value: str) -> None:
    """``src`` with its ``# key:`` line stating ``value`` (the key must be there)."""
    text = src.read_text(encoding="utf-8").split("\n")
    i = next(n for n, x in enumerate(text) if x.startswith(f"# {key}:"))
    text[i] = f"# {key}: {value}"
    dst.write_text("\n".join(text), encoding="utf-8")


def _rows(path: Path) -> list[dict]:
    text = [x for x in path.read_text(encoding="utf-8").splitlines() if not x.startswith("#")]
    return list(csv.DictReader(text))


def _rest_and_top(path: Path) -> tuple[float, float]:
    """The median output of the scale-factor test's rows at rest (rate 0), and its largest
    |rate|: read off the file, independently of the rule."""
    rows = [r for r in _rows(path) if r["test"] == "scale_factor"]
    rest = [float(r["output"]) for r in rows if float(r["rate_dps"]) == 0.0]
    return float(np.median(rest)), max(abs(float(r["rate_dps"])) for r in rows)


def _number_after(text: str, words: str) -> float:
    return float(re.search(re.escape(words) + r" (-?[0-9.e+]+)", text).group(1))


# ------------------------------------------------------------------------------- rate files

def test_null_output_in_another_unit_is_refused(simulated, tmp_path):
    spec, proto, readings, _ = simulated
    bad = tmp_path / "readings.csv"
    _with_meta(readings, bad, "null_output", "2.5")            # 2500 mV written in V
    msg = _refused(["calibrate", str(bad), "--out", str(tmp_path / "out"), "--protocol",
                    str(proto)])
    assert "readings.csv: key null_output: null_output 2.5 mV" in msg, msg
    rest, _ = _rest_and_top(readings)
    measured = _number_after(msg, "the scale-factor test measures,")
    assert abs(measured - rest) < 5.0, (measured, rest)       # mV: the rest's output


@pytest.mark.parametrize("share, refused", [(0.9, False), (1.1, True)])
def test_null_output_bound_is_the_largest_rate_tested(simulated, tmp_path, share, refused):
    """A null leaving a bias of 0.9 × the largest rate passes the screening, 1.1 × is refused
    (K from the file's nominal, which the measured K matches to 0.03 %)."""
    spec, proto, readings, _ = simulated
    rest, top = _rest_and_top(readings)
    k = 6.0
    assert f"# nominal_scale_factor: {k}" in readings.read_text(encoding="utf-8")
    bad = tmp_path / "readings.csv"
    _with_meta(readings, bad, "null_output", repr(rest + share * top * k))
    if refused:
        with pytest.raises(GonioError, match="key null_output") as e:
            get(spec).screen(str(bad), str(proto))
        assert e.value.key == "null_output"
    else:
        assert not [f for f in get(spec).screen(str(bad), str(proto))
                    if "null_output" in f.message]


def test_nominal_scale_factor_in_another_unit(simulated, clean, tmp_path):
    spec, proto, readings, _ = simulated
    bad = tmp_path / "readings.csv"
    _with_meta(readings, bad, "nominal_scale_factor", "0.006")   # 6 mV/(°/s) written in V
    argv = ["calibrate", str(bad), "--out", str(tmp_path / "out"), "--protocol", str(proto)]
    if spec == "iec62047-20":              # a_TYP divides 5.1.3.2 and 5.1.3.8: refused
        msg = _refused(argv)
        assert "key nominal_scale_factor: nominal_scale_factor 0.006 " in msg, msg
        assert abs(_number_after(msg, "the scale-factor test measures,") - 6.0) < 0.06, msg
        return
    rc, err = _gonio(argv)
    assert rc == 0, err[-2000:]
    got = json.loads((tmp_path / "out" / "results.json").read_text(encoding="utf-8"))
    flagged = [f for f in got["findings"] if f["code"] == "nominal-scale-factor-departs"]
    assert len(flagged) == 1 and flagged[0]["action"] == "flagged", got["findings"]
    assert "0.006" in flagged[0]["message"]
    # no JJF item reads the nominal: every item is the clean file's
    base = clean[0].to_json()["items"]
    for name, item in got["items"].items():
        assert item.get("value") == base[name].get("value"), name
        assert item.get("uncertainty") == base[name].get("uncertainty"), name


# ----------------------------------------------------------------------------- optical draft

@pytest.fixture
def optical(shared_simulation, tmp_path):
    """A copy of the simulated optical readings, to edit."""
    sim = tmp_path / "sim"
    shutil.copytree(shared_simulation("ogam-draft"), sim)
    return sim / "readings.csv"


def test_gyro_deg_contradiction_refused_by_the_screening_hook(optical, tmp_path):
    lines = optical.read_text(encoding="utf-8").split("\n")
    i = next(n for n, x in enumerate(lines) if x.startswith("angle_deviation,1,4,"))
    cells = lines[i].split(",")
    cells[8] = "12.5"                        # gyro_deg; its gyro_counts say 120°
    lines[i] = ",".join(cells)
    optical.write_text("\n".join(lines), encoding="utf-8")
    spec = get("ogam-draft")
    refused = [f for f in spec.screen(str(optical)) if f.action == "refused"]
    assert [(f.line, f.column) for f in refused] == [(i + 1, "gyro_deg")], refused
    msg = _refused(["calibrate", str(optical), "--out", str(tmp_path / "out")])
    assert msg == f"gonio: error: {optical}:{i + 1}: column gyro_deg: {refused[0].message}"


def test_nominal_k_in_another_scale(optical, shared_simulation, tmp_path):
    _with_meta(optical, optical, "nominal_scale_factor_counts_per_deg", "76434.87e3")
    out = tmp_path / "out"
    rc, err = _gonio(["calibrate", str(optical), "--out", str(out)])
    assert rc == 0, err[-2000:]
    got = json.loads((out / "results.json").read_text(encoding="utf-8"))
    flagged = [f for f in got["findings"] if f["code"] == "nominal-scale-factor-departs"]
    assert len(flagged) == 1 and flagged[0]["action"] == "flagged", got["findings"]
    rc, err = _gonio(["calibrate", str(shared_simulation("ogam-draft") / "readings.csv"),
                      "--out", str(tmp_path / "base")])
    assert rc == 0, err[-2000:]
    base = json.loads((tmp_path / "base" / "results.json").read_text(encoding="utf-8"))
    for name, item in got["items"].items():  # 7.1 reads the angles: every item the clean one's
        assert item.get("value") == base["items"][name].get("value"), name
        assert item.get("uncertainty") == base["items"][name].get("uncertainty"), name
    # without 7.1 the nominal reads every angle: refused, naming the key and both values
    no71 = tmp_path / "no71.csv"
    no71.write_text("\n".join(x for x in optical.read_text(encoding="utf-8").split("\n")
                              if not x.startswith("scale_factor,")), encoding="utf-8")
    msg = _refused(["calibrate", str(no71), "--out", str(tmp_path / "out2")])
    assert "key nominal_scale_factor_counts_per_deg: " in msg and "76434870 " in msg, msg
    k_ref = _number_after(msg, "the readings measure,")
    assert abs(k_ref / 76434.87 - 1) < 1e-5, msg


def test_table_mpe_in_another_unit_is_refused(optical, tmp_path):
    _with_meta(optical, optical, "table_mpe_arcsec", "100")
    msg = _refused(["calibrate", str(optical), "--out", str(tmp_path / "out")])
    assert "key table_mpe_arcsec: " in msg and "100″" in msg and "0.1″" in msg, msg


def test_table_mpe_within_the_factor_is_used_and_stated():
    import pandas as pd

    from gonio.specs.ogam_draft.calibration import session_settings
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.readings import Readings

    s, c = session_settings(Readings(pd.DataFrame(), {"table_mpe_arcsec": "0.9"}),
                            load_protocol("ogam-draft"))
    assert s["table_mpe_arcsec"] == 0.9 and c[0].used == 0.9
