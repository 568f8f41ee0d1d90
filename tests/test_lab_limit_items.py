"""A laboratory file's limit on an item the specification does not have is refused before any
work (leftover 4 of the last stop): one line naming the file, the entry and the item, exit 2,
for ``gonio calibrate`` and ``gonio demo`` of every specification that knows its items up front.

Before, the calibration (or the whole simulation) ran first and the error came after it; the
tests make the pipeline's calibration and every renderer fail loudly if they are reached."""

from __future__ import annotations

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


def test_the_rate_and_optical_specifications_know_their_items():
    assert {"ogam-draft", "jjf1535-2015", "iec62047-20"} <= set(KNOWN)


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
