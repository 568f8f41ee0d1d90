"""``[identity]`` tolerances are bounded: a laboratory file cannot hide a contradiction
between the readings' and its own conditions behind a tolerance as wide as the scale (35 °C
readings certified as 20.1 °C with no finding); a wider one is refused, naming the key."""
from __future__ import annotations

import pytest

from gonio.errors import GonioError
from gonio.formats.lab import (MAX_HUMIDITY_TOLERANCE_PCT, MAX_TEMPERATURE_TOLERANCE_C,
                               load_lab)
from gonio.resources import protocols_dir


def _lab(tmp_path, key, value):
    text = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    p = tmp_path / "lab.toml"
    p.write_text(text + f"\n[identity]\n{key} = {value}\n", encoding="utf-8")
    return p


@pytest.mark.parametrize("key, top", [("temperature_tolerance_c", MAX_TEMPERATURE_TOLERANCE_C),
                                      ("humidity_tolerance_pct", MAX_HUMIDITY_TOLERANCE_PCT)])
def test_a_tolerance_wider_than_its_bound_is_refused(tmp_path, key, top):
    assert load_lab(_lab(tmp_path, key, top))["identity"][key] == top
    for bad in (top * 1.001, 1000, -0.1):
        with pytest.raises(GonioError, match=rf"key identity\.{key}: expected 0–"):
            load_lab(_lab(tmp_path, key, bad))
