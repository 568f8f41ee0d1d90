"""A laboratory file's limit on an item the specification does not have is refused before any
work (leftover 4 of the last stop): one line naming the file, the entry and the item, exit 2,
for ``gonio calibrate`` and ``gonio demo`` of every specification that knows its items up front.

Before, the calibration (or the whole simulation) ran first and the error came after it; the
tests make the pipeline's calibration and every renderer fail loudly if they are reached."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from gonio.cli import main
from gonio.specs import Specification, available

ROOT = Path(__file__).resolve().parents[1]
KNOWN = sorted(k for k, s in available().items() if s.item_keys)

#: The example laboratory file up to its limits, then two limits of our own.
EXAMPLE = (ROOT / "protocols" / "lab-example.toml").read_text(encoding="utf-8")
LAB = EXAMPLE[:EXAMPLE.index("\n[[specification_limits]]")].replace("{", "{{").replace("}", "}}") + """
[[specification_limits]]
item = "{good}"
mpe = 1.0

[[specification_limits]]
item = "no_such_item"
mpe = 1.0
"""


def test_every_built_in_specification_knows_its_items():
    assert {"ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment"} <= set(KNOWN)


@pytest.fixture
def no_work(monkeypatch):
    def reached(*_a, **_k):
        raise AssertionError("work started before the lab file's limits were checked")

    import gonio.pipeline.dispatch as dispatch
    monkeypatch.setattr(dispatch, "screen_and_calibrate", reached)
    monkeypatch.setattr(Specification, "renderer", reached)


@pytest.mark.parametrize("command", ["calibrate", "demo"])
@pytest.mark.parametrize("key", KNOWN)
def test_unknown_item_refused_before_any_work(key, command, tmp_path, capsys, no_work):
    spec = available()[key]
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB.format(good=spec.item_keys[0]), encoding="utf-8")
    readings = tmp_path / "readings.csv"
    readings.write_text(f"# spec: {key}\n", encoding="utf-8")
    out = tmp_path / "out"
    args = ([command, str(readings)] if command == "calibrate" else [command])
    rc = main([*args, "--spec", key, "--lab", str(lab), "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1, err
    assert str(lab) in err and "specification_limits[1].item" in err, err
    assert "'no_such_item'" in err and spec.item_keys[0] in err, err
    assert not out.exists() or not any(out.iterdir())


def test_known_items_pass_the_check(tmp_path):
    from gonio.pipeline.dispatch import load_lab_file

    spec = available()["jjf1535-2015"]
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB.format(good="bias").replace("no_such_item", "bandwidth"),
                   encoding="utf-8")
    d = load_lab_file(lab, spec)
    assert [x["item"] for x in d["specification_limits"]] == ["bias", "bandwidth"]


# -- the gyro triad: fixed alignment keys, thermal values at the set points as patterns ----

TRIAD_LAB = re.sub(r"^\[instrument\]\n.*?\n\n", "",          # the triad's serial is its own
                   LAB[:LAB.index("\n[[specification_limits]]")].replace("{{", "{").replace("}}", "}"),
                   flags=re.S | re.M)


def triad_lab(tmp_path, limits) -> Path:
    """The example laboratory file with ``limits`` ({item: (lower, upper)}) as its own."""
    text = TRIAD_LAB + "".join(f"\n[[specification_limits]]\nitem = {k!r}\nlower = {lo!r}\n"
                               f"upper = {hi!r}\n" for k, (lo, hi) in limits.items())
    lab = tmp_path / "lab.toml"
    lab.write_text(text, encoding="utf-8")
    return lab


@pytest.fixture(scope="module")
def triad_readings(tmp_path_factory):
    d = tmp_path_factory.mktemp("triadlab")
    assert main(["simulate", "--spec", "triad-alignment", "--out", str(d / "sim")]) == 0
    return d / "sim"


@pytest.mark.parametrize("typo", ["M_xq", "K_z_theta1", "b_z_c0", "ARW_z_t1_v1", "k_z_t1_v1",
                                  "K_w_t1_v1", "thermal_model", "K_z_t0_v1", "b_z_t1"])
def test_triad_typo_refused_before_the_calibration(typo, triad_readings, tmp_path, capsys,
                                                   no_work):
    """A real triad readings file, a limit on an item no triad result can hold (a typo, a
    polynomial coefficient — information, not a certified item —, a gyro the triad has not,
    ARW's supply level, a set point numbered 0, a bias without its supply level, the
    value-less placeholder): exit 2, one line naming the file, the entry and the key,
    nothing calibrated or written."""
    lab = triad_lab(tmp_path, {"M_xx": (49.0, 51.0), typo: (0.0, 1.0)})
    out = tmp_path / "out"
    rc = main(["calibrate", str(triad_readings / "readings.csv"), "--lab", str(lab),
               "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert str(lab) in err and "specification_limits[1].item" in err and repr(typo) in err, err
    assert not out.exists() or not any(out.iterdir())


def test_triad_lab_limits_reach_results_and_certificate(triad_readings, tmp_path):
    """Limits on an alignment item and on a thermal value (pattern keys) pass the check and
    are decided against the bench's truth: M_xx within ±0.05 of the true system-matrix
    element passes, M_yy with its upper limit 0.05 below the truth fails, the z gyro's K at
    25 °C (set point 5 of the programme) and 5 V within ±0.1 of the true scale factor passes.
    And every key the result holds passes the check (the patterns cannot drift from the
    items named)."""
    truth = json.loads((triad_readings / "truth.json").read_text(encoding="utf-8"))
    m = truth["system_matrix"]
    k_z = truth["scale_per_dps"][2]
    limits = {"M_xx": (m[0][0] - 0.05, m[0][0] + 0.05), "M_yy": (m[1][1] - 1.0, m[1][1] - 0.05),
              "K_z_t5_v2": (k_z - 0.1, k_z + 0.1)}
    lab = triad_lab(tmp_path, limits)
    out = tmp_path / "out"
    assert main(["calibrate", str(triad_readings / "readings.csv"), "--lab", str(lab),
                 "--out", str(out)]) == 0
    items = json.loads((out / "results.json").read_text(encoding="utf-8"))["items"]
    outcome = {k: items[k]["conformity"]["outcome"] for k in limits}
    assert outcome == {"M_xx": "pass", "M_yy": "fail", "K_z_t5_v2": "pass"}
    for k, (lo, hi) in limits.items():
        c = items[k]["conformity"]
        assert (c["lower"], c["upper"], c["limits_from"]) == (lo, hi, "lab file")
    html = (out / "certificate.html").read_text(encoding="utf-8")
    assert "Example Angle Metrology Laboratory" in html and "K_z_t5_v2" in html
    # every key a real result holds passes the check: the patterns follow thermal_items
    spec = available()["triad-alignment"]
    held = [k for k, it in items.items() if it["value"] is not None]
    assert any(k.startswith("ARW_z_") for k in held) and "M_zz" in held
    assert [k for k in held if not spec.knows_item(k)] == []

