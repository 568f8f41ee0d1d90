"""The IEC noise items (5.4.5.2, 5.4.5.1 b), c)) at the static record's temperature: without
the 5.3.3.6 visits they carry no term for the gyro's temperature error at T_BASE and the
calibration states, as a flagged finding, that they hold at the record's temperature (the
readings' temperature_c), with the chamber's bound; an item that carries the line is not
named. The coefficient from the visits against the bench's own parameter: tests/
test_rate_bound_u_c.py (the line) and below."""
from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pandas as pd

from gonio.specs.iec62047_20 import certificate as C
from gonio.specs.iec62047_20 import items as I


def _frame(static_c: float) -> pd.DataFrame:
    n = 50
    return pd.DataFrame({
        "test": ["bias"] * 5 + ["static"] * n, "run": [0] * (5 + n), "step": [0] * (5 + n),
        "time_s": np.arange(5 + n, dtype=float), "output": np.zeros(5 + n),
        "temperature_c": [25.0] * 5 + [static_c] * n})


def _items(measured=("arw", "inband_noise", "broadband_noise"), lined=()):
    clauses = {"arw": "5.4.5.2", "inband_noise": "5.4.5.1 b)", "broadband_noise": "5.4.5.1 c)"}
    return {k: SimpleNamespace(clause=c, measured=k in measured, uncertainty=SimpleNamespace(
        components=[{"symbol": "N"}] + ([{"symbol": "dT_noise"}] if k in lined else [])))
        for k, c in clauses.items()}


def test_the_finding_names_the_record_s_temperature_and_the_bound():
    t = I.static_record_temperature_c(_frame(22.8))      # not the bias rows' 25 °C
    assert t == 22.8
    f = I.noise_temperature_finding(_items(), t, 2.2)
    assert f.action == "flagged" and f.code == I.NOISE_TEMPERATURE_CODE
    assert (f.test, f.column) == ("static", "temperature_c")
    for part in ("5.4.5.2", "5.4.5.1 b)", "5.4.5.1 c)", "22.8 °C", "± 2.2 °C", "not at T_BASE"):
        assert part in f.message
    only = I.noise_temperature_finding(_items(("inband_noise",)), t, 2.2)
    assert "5.4.5.1 b)" in only.message and "5.4.5.2" not in only.message


def test_no_finding_without_a_measured_noise_item():
    assert I.noise_temperature_finding(_items(()), 20.0, 2.2) is None


def test_an_item_with_its_temperature_line_is_not_named():
    all_lined = _items(lined=("arw", "inband_noise", "broadband_noise"))
    assert I.noise_temperature_finding(all_lined, 20.0, 2.2) is None
    f = I.noise_temperature_finding(_items(lined=("arw",)), 20.0, 2.2)
    assert "5.4.5.1 b)" in f.message and "5.4.5.2" not in f.message


def test_the_zh_certificate_translates_the_finding():
    msg = I.noise_temperature_finding(_items(), 22.8, 2.2).message
    hits = [zh for pat, zh in C.PHRASES_ZH if re.fullmatch(pat, msg)]
    assert len(hits) == 1 and "T_BASE" in hits[0]
