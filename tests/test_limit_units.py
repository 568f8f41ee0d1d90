"""A laboratory file's specification limit may state its ``unit``; it must be the item's unit
as results.json states it, however spelt ("°/h", "deg/h", "º/h"). A limit in a unit the
item's converts to exactly (°/s for °/h, ppm for %) is refused with the limit written in the
item's unit, never converted; any other unit is refused naming the entry. The check runs at
the conformity decision (the items' units are known once calibrated), so these tests
calibrate each specification's demo readings.

The laboratory files are the ones tests/test_outputs_agree_with_lab.py issues each demo with
(its ``lab_text``), with a ``unit`` added to each limit here.
"""

from __future__ import annotations

import json
import re
from fractions import Fraction

import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.records.services import check_limits
from gonio.units import same_unit, unit_factor
from tests.test_outputs_agree_with_lab import CASES, lab_text


def calibrate(readings, lab, out, capsys):
    """``gonio calibrate READINGS --lab LAB --out OUT``: (exit code, stderr)."""
    capsys.readouterr()
    rc = main(["calibrate", str(readings), "--lab", str(lab), "--out", str(out)])
    return rc, capsys.readouterr().err.strip()


def respelt(unit: str, i: int) -> str:
    """Another spelling of ``unit`` (the degree as "deg" or "º", the second of arc as "″",
    spaces around), alternating with the unit as results.json writes it (``i`` even)."""
    if i % 2 == 0:
        return unit
    for old, new in (("arcsec", "″"), ("deg", "º"), ("°", "deg")):
        if old in unit:
            return unit.replace(old, new)
    return f" {unit} " if unit != "1" else "one"


def with_units(text: str, units: list[str]) -> str:
    """The laboratory file ``text`` with ``unit = units[i]`` added to its i-th limit."""
    parts = text.split("\n[[specification_limits]]\n")
    assert len(parts) == len(units) + 1
    return parts[0] + "".join(f"\n[[specification_limits]]\nunit = {json.dumps(u)}\n{p}"
                              for u, p in zip(units, parts[1:]))


@pytest.fixture(scope="module")
def plain(tmp_path_factory, request):
    """Per specification: (its demo readings, its laboratory file without units, the items
    of results.json calibrated with it)."""
    shared_demo = request.getfixturevalue("shared_demo")
    runs = {}

    def get(spec: str, capsys):
        if spec not in runs:
            root = tmp_path_factory.mktemp(spec)
            lab = root / "lab.toml"
            lab.write_text(lab_text(spec), encoding="utf-8")
            readings = shared_demo(spec) / "readings.csv"
            rc, err = calibrate(readings, lab, root / "out", capsys)
            assert rc == 0, err
            items = json.loads((root / "out" / "results.json").read_text(encoding="utf-8"))
            runs[spec] = (readings, lab, items["items"])
        return runs[spec]
    return get


@pytest.mark.parametrize("spec", list(CASES))
def test_the_items_unit_however_spelt_decides_as_without_it(spec, plain, tmp_path, capsys):
    readings, lab, items = plain(spec, capsys)
    limited = [k for k, _ in CASES[spec][1]]
    units = [respelt(items[k]["unit"] or "1", i) for i, k in enumerate(limited)]
    assert any(u != items[k]["unit"] for u, k in zip(units, limited))   # a variant is in
    with_unit = tmp_path / "lab.toml"
    with_unit.write_text(with_units(lab.read_text(encoding="utf-8"), units), encoding="utf-8")
    rc, err = calibrate(readings, with_unit, tmp_path / "out", capsys)
    assert rc == 0, err
    got = json.loads((tmp_path / "out" / "results.json").read_text(encoding="utf-8"))["items"]
    for k in limited:
        assert items[k]["conformity"] is not None
        assert got[k]["conformity"] == items[k]["conformity"], k
    summary = (tmp_path / "out" / "summary.txt").read_text(encoding="utf-8")
    assert "º" not in summary                 # the item's unit is printed, not the file's


#: (specification, limited item, a unit the item's does not convert to)
WRONG = [("jjf1535-2015", "bias_stability", "mV/(°/s)"), ("ogam-draft", "angle_deviation", "%"),
         ("iec62047-20", "bias", "°/√h"), ("triad-alignment", "b_z", "lsb/(°/s)")]


@pytest.mark.parametrize("spec, item, unit", WRONG)
def test_a_unit_that_is_not_the_items_is_refused_naming_the_entry(spec, item, unit, plain,
                                                                  tmp_path, capsys):
    readings, lab, items = plain(spec, capsys)
    limited = [k for k, _ in CASES[spec][1]]
    i = limited.index(item)
    assert unit_factor(unit, items[item]["unit"]) is None        # neither same nor convertible
    units = [items[k]["unit"] or "1" for k in limited]
    units[i] = unit
    bad = tmp_path / "lab.toml"
    bad.write_text(with_units(lab.read_text(encoding="utf-8"), units), encoding="utf-8")
    rc, err = calibrate(readings, bad, tmp_path / "out", capsys)
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert str(bad) in err and f"specification_limits[{i}].unit" in err, err
    assert unit in err and items[item]["unit"] in err, err
    assert not (tmp_path / "out" / "results.json").exists()


def test_a_convertible_unit_is_refused_with_the_limit_in_the_items_unit(plain, tmp_path,
                                                                       capsys):
    """bias_stability of JJF 1535 is in °/h; its limit given in °/s is refused, the message
    writing the same limit in °/h (× 3600 s/h, worked here by hand)."""
    readings, lab, items = plain("jjf1535-2015", capsys)
    limited = [k for k, _ in CASES["jjf1535-2015"][1]]
    i = limited.index("bias_stability")
    assert same_unit(items["bias_stability"]["unit"], "°/h")
    text = lab.read_text(encoding="utf-8").replace('item = "bias_stability"\nupper = 60.0',
                                                   'item = "bias_stability"\nupper = 0.02')
    units = [items[k]["unit"] or "1" for k in limited]
    units[i] = "deg/s"
    bad = tmp_path / "lab.toml"
    bad.write_text(with_units(text, units), encoding="utf-8")
    rc, err = calibrate(readings, bad, tmp_path / "out", capsys)
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert f"specification_limits[{i}].unit" in err and str(bad) in err, err
    assert "upper = 72 " in err and "3600" in err, err        # 0.02 °/s = 72 °/h
    assert not (tmp_path / "out" / "results.json").exists()


def test_the_conversions_are_the_exact_ones():
    assert unit_factor("°/s", "°/h") == 3600 and unit_factor("%", "ppm") == 10 ** 4
    assert unit_factor("″", "deg") == Fraction(1, 3600) and unit_factor("ppm", "1") == Fraction(1, 10 ** 6)
    assert unit_factor("(°/s)/g", "(°/h)/g") == 3600
    assert unit_factor("°/√h", "(°/h)/√Hz") == 60            # IEEE Std 952 Annex C
    assert unit_factor("rad", "°") is None and unit_factor("%", "°/h") is None
    assert same_unit("deg/h", "º/h") and same_unit("°/h", " ° / h ") and not same_unit("%", "ppm")


def test_the_lab_file_refuses_a_unit_that_is_no_unit(tmp_path, capsys):
    lab = tmp_path / "lab.toml"
    text = lab_text("ogam-draft")
    n = len(text.split("\n[[specification_limits]]\n")) - 1
    lab.write_text(with_units(text, ["(°/h"] + ["arcsec"] * (n - 1)), encoding="utf-8")
    readings = tmp_path / "readings.csv"
    readings.write_text("# spec: ogam-draft\n", encoding="utf-8")
    rc, err = calibrate(readings, lab, tmp_path / "out", capsys)
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "specification_limits[0].unit" in err and str(lab) in err, err


def test_the_records_limits_take_and_check_the_unit():
    got = check_limits([{"item": "bias", "mpe": 0.5, "unit": "deg/h"}], "jjf1535-2015")
    assert got[0]["unit"] == "deg/h"
    assert check_limits([{"item": "bias", "mpe": 0.5}])[0]["unit"] is None
    with pytest.raises(GonioError, match=re.escape("limits[0].unit")):
        check_limits([{"item": "bias", "mpe": 0.5, "unit": "°/h)"}])
