"""A dispersion read with a bounded error that scales it (IEC 62047-20 5.4.5's noise items, read
at the static record's temperature, stated at T_BASE): its one statement is the one-sided
bound condition [0, (s + R)/(1 − g)] (gonio.result.gum.dispersion_bound_statement), which
covers 95 % exactly at the bound and more inside it, where the χ² limit of the GUM budget (the
error as a rectangular line) covers less; and the coverage studies' ``cold`` case that puts the
gyro at that bound (gonio.bench.equipment.cold_equipment)."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from gonio.bench.equipment import cold_equipment, worst_equipment
from gonio.bench.rate_gyro import load_rate_bench
from gonio.errors import GonioError
from gonio.formats.toml import read_toml
from gonio.resources import resolve
from gonio.result.gum import dispersion_bound_statement, dispersion_uncertainty, gum
from gonio.specs import get
from uncertainty import from_u, type_b


def _budget(s: float, nu: int, g: float):
    """A noise rms s with ν degrees of freedom (its χ² line, u = s/√(2ν)) and the relative
    error g·s of its reading as a rectangular line, as the IEC noise items' budgets hold them."""
    return gum(lambda n, t: n + t, [from_u("N", s, s / math.sqrt(2 * nu), dof=nu),
                                   type_b("dT_noise", 0.0, g * s, "rectangular")])


def _coverage(k_upper: float, nu: int, factor: float) -> float:
    """P(σ ≤ k_upper·s) where s is a standard deviation of ν degrees of freedom of data whose
    own dispersion is factor·σ: s = factor·σ·√(χ²_ν/ν)  →  P(χ²_ν ≥ ν/(k_upper·factor)²)."""
    return float(stats.chi2.sf(nu / (k_upper * factor) ** 2, nu))


@pytest.mark.parametrize("nu,g", [(200, 0.05), (40, 0.10), (5000, 0.01)])
def test_the_bound_condition_covers_exactly_at_the_bound(nu, g):
    """The statement is scale-equivariant (upper = K·s): its coverage at the cold bound (the
    reading σ·(1 − g)) is 95 % to 1e-9 by the χ² law; inside the bounds (no error) more; the
    χ² limit of the whole budget (the line rectangular, ν_eff of u_c) less. A first-order
    s + g·s + R (the cross terms dropped) would cover less than 95 % at (40, 0.10)."""
    u = _budget(1.0, nu, g)
    st, d = dispersion_bound_statement(1.0, u, {"dT_noise": g})
    k_upper = st.interval[1]
    assert st.k is None and st.interval[0] == 0.0 and d["nu_rest"] == pytest.approx(nu)
    assert _coverage(k_upper, nu, 1.0 - g) == pytest.approx(0.95, abs=1e-9)
    assert _coverage(k_upper, nu, 1.0) > 0.95
    plain = dispersion_uncertainty(1.0, u)                # the GUM line, rectangular
    assert _coverage(plain.interval[1], nu, 1.0 - g) < 0.93
    if (nu, g) == (40, 0.10):
        assert _coverage(1.0 + g + d["reach_rest"], nu, 1.0 - g) < 0.94
    # the scale: twice the reading, twice the statement
    st2, _ = dispersion_bound_statement(2.0, _budget(2.0, nu, g), {"dT_noise": g})
    assert st2.interval[1] == pytest.approx(2.0 * k_upper, rel=1e-12)


def test_the_bound_condition_covers_on_drawn_records():
    """The same by simulation, not by the χ² law: 20 000 records of 201 normal samples whose
    dispersion is σ·(1 − g), each stated by the function itself (scale-equivariant: once,
    then scaled; checked against three direct calls): the Clopper–Pearson interval of the
    coverage holds 95 %, and the whole budget's χ² limit misses it."""
    rng = np.random.default_rng(20261203)
    nu, g, sigma = 200, 0.05, 1.0
    x = rng.standard_normal((20000, nu + 1)) * sigma * (1.0 - g)
    s = x.std(axis=1, ddof=1)
    k_upper = dispersion_bound_statement(1.0, _budget(1.0, nu, g), {"dT_noise": g})[0].interval[1]
    for si in s[:3]:
        st, _ = dispersion_bound_statement(float(si), _budget(float(si), nu, g), {"dT_noise": g})
        assert st.interval[1] == pytest.approx(k_upper * si, rel=1e-12)
    hits = int(np.sum(sigma <= k_upper * s))
    ci = stats.binomtest(hits, len(s)).proportion_ci(0.95)
    assert ci.low <= 0.95 <= ci.high, (hits, ci)
    k_plain = dispersion_uncertainty(1.0, _budget(1.0, nu, g)).interval[1]
    miss = stats.binomtest(int(np.sum(sigma <= k_plain * s)), len(s)).proportion_ci(0.95)
    assert miss.high < 0.95


def test_the_bound_condition_refuses_what_it_cannot_state():
    u = _budget(1.0, 100, 0.05)
    with pytest.raises(GonioError, match="not below 1"):
        dispersion_bound_statement(1.0, u, {"dT_noise": 1.0})
    with pytest.raises(GonioError, match="no line 'dT'"):
        dispersion_bound_statement(1.0, u, {"dT": 0.05})
    # no bounded error: the χ² statement of the budget, no parts
    st, d = dispersion_bound_statement(1.0, u, {"dT_noise": 0.0})
    assert d == {} and st.k_source == "chi-square"


def test_cold_equipment_puts_the_gyro_cold_at_every_set_point():
    """From the bench file as written: the chamber's deviation at −its bound and the gyro's
    place at −half the uniformity at every set point, the fluctuation at the bench's own,
    everything else as the worst case puts it (the same seed)."""
    raw = read_toml(resolve("mems-adxrs610", kind="bench"))["equipment"]
    eq = load_rate_bench("mems-adxrs610").equipment
    c = cold_equipment(eq, 7, cross_axis=(0.01, -0.008))
    w = worst_equipment(eq, 7, temperature_split_c=0.0, cross_axis=(0.01, -0.008))
    b = raw["chamber_deviation_bound_c"]
    for t in (-40.0, -8.75, 20.0, 22.5, 53.75, 85.0):
        assert c.chamber.deviation_at(t) == -b
        assert c.chamber.position_at(t) == -c.chamber.uniformity_c / 2
    assert c.chamber.fluctuation_c == raw["chamber"]["fluctuation_c"]
    assert (c.rate_table, c.fixture, c.acquisition) == (w.rate_table, w.fixture, w.acquisition)


def test_a_cold_trial_reads_the_noise_low_and_its_statement_holds_it():
    """One trial of the IEC study programme's ``cold`` case: the gyro sits 3 °C below the
    static record's set point (−2 °C deviation, −1 °C place); each noise item is stated by its
    bound condition, whose g is (|c| + U(c))·ΔT, and its limit holds the bench's truth."""
    from gonio.analysis.coverage import spawn_seed
    from gonio.pipeline.coverage import case_stream, reduced_protocol, study_bench
    from gonio.pipeline.dispatch import screen_and_calibrate

    spec = get("iec62047-20")
    with tempfile.TemporaryDirectory() as d:
        proto = spec.load_protocol(str(reduced_protocol(spec.key, Path(d) / "r.toml")))
    bench = study_bench(spec, None, "cold")
    readings, truth = spec.run_trial(bench, proto, spawn_seed(5, case_stream(spec, "cold"), 0))
    static = [s for s in truth["segments"] if s["test"] == "static"]
    assert static and all(s["gyro_temperature_c"] - s["temperature_c"] == pytest.approx(-3.0,
                                                                                       abs=0.05)
                          for s in static)
    res = screen_and_calibrate(spec, readings, proto)
    for key in ("arw", "inband_noise", "broadband_noise"):
        it = res.items[key]
        bc = it.details["bound_condition"]
        assert bc["g_rel"]["dT_noise"] > 0 and it.uncertainty.k is None
        assert it.uncertainty.interval[1] == pytest.approx(
            (it.value + bc["reach_rest"]) / (1 - bc["g_rel"]["dT_noise"]), rel=1e-12)
        assert truth["items"][key]["value"] <= it.uncertainty.interval[1], key
