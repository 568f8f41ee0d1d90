"""The rate specifications' truths are computed from the bench's physical parameters, not by
the estimators under test (issue 24).

1. The closed forms of :mod:`gonio.bench.rate_truth` against a brute-force least-squares fit
   (numpy.polyfit) of the bench's own response function ``RateGyroConfig.response`` — the
   physics the session simulates — and against hand algebra for a linear gyro.
2. Every estimator formula (:mod:`gonio.specs._rate_family.formulas`,
   :mod:`gonio.specs.jjf1535.formulas`, :mod:`gonio.specs.iec62047_20.formulas`) replaced by a wrong one: the
   truths of JJF 1535 and IEC 62047-20 do not move (so the noise-off tests of
   tests/test_rate_bench.py, which compare the estimates with these truths, see a mutated
   formula; scripts/mutation.py shows that they do).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gonio.specs._rate_family import formulas as rg
from gonio.specs.iec62047_20 import formulas as ief
from gonio.specs.jjf1535 import formulas as jf
from gonio.bench import rate_truth as rt
from gonio.bench.rate_gyro import load_rate_bench


@pytest.fixture(scope="module")
def gyro():
    return load_rate_bench("mems-adxrs610").gyro


RATES = np.array([1, 1.6, 2.5, 4, 6.3, 10, 16, 25, 40, 63, 100.0])


@pytest.mark.parametrize("e", (0.0, 2.7e-3, -0.05))
def test_closed_forms_against_brute_force(gyro, e):
    assert rt.closed_form_valid(gyro, RATES, e)
    x = np.concatenate([-RATES, RATES])
    k, how = rt.slope_both_directions(gyro, RATES, e)
    assert how == "closed form"
    assert k == pytest.approx(np.polyfit(x, gyro.response(x + e), 1)[0], rel=1e-13)
    # the IEC fit includes the rest point: same slope (x = 0 adds nothing)
    x0 = np.concatenate([x, [0.0]])
    assert k == pytest.approx(np.polyfit(x0, gyro.response(x0 + e), 1)[0], rel=1e-13)
    kp, kn, _ = rt.slopes_per_direction(gyro, RATES, e)
    assert kp == pytest.approx(np.polyfit(RATES, gyro.response(RATES + e), 1)[0], rel=1e-13)
    assert kn == pytest.approx(np.polyfit(-RATES, gyro.response(-RATES + e), 1)[0], rel=1e-13)
    # the bench's response and the truth module's written-out one agree
    w = np.linspace(-400, 400, 8001)
    assert np.array_equal(rt.response_at(gyro, w), gyro.response(w))


def test_closed_forms_by_hand():
    """A gyro with asymmetry only: K = 1 + eαΣr/(2Σr²), K± = 1 ± α/2 exactly."""
    g = replace(load_rate_bench("mems-adxrs610").gyro, sf_cubic_per_dps2=0.0,
                sf_asymmetry=0.01, dead_band_dps=0.0)
    r = np.array([1.0, 2.0, 3.0])
    assert rt.slope_both_directions(g, r, 0.1)[0] == pytest.approx(1 + 0.1 * 0.01 * 6 / 28)
    kp, kn, _ = rt.slopes_per_direction(g, r, 0.1)
    assert (kp, kn) == (pytest.approx(1.005), pytest.approx(0.995))
    # a dead band above the smallest rate: the closed form does not apply, polyfit does
    gd = replace(g, dead_band_dps=1.5)
    k, how = rt.slope_both_directions(gd, r, 0.0)
    assert how.startswith("numpy.polyfit")
    assert k == pytest.approx(np.polyfit(np.r_[-r, r], gd.response(np.r_[-r, r]), 1)[0])
    assert rt.ls_slope_of_poly([-1.0, 0.0, 1.0, 3.0], 0.5, 0.0) == pytest.approx(0.5)
    assert rt.rule_walk([3, 2, 1], [True, False, True]) == 3.0
    assert rt.rule_walk([3, 2, 1], [False, True, True]) is None
    A, tau = 2.0, 10.0
    assert rt.exponential_interval_mean(A, tau, 0.0, 1e-9) == pytest.approx(A)
    t = np.linspace(5.0, 15.0, 200001)
    assert rt.exponential_interval_mean(A, tau, 5.0, 15.0) == pytest.approx(
        np.trapezoid(A * np.exp(-t / tau), t) / 10.0, rel=1e-9)
    f = np.array([10.0, 100.0])
    assert rt.log_grid_crossing(f, [1.0, 10 ** (-6 / 20)], 10 ** (-3 / 20)) == \
        pytest.approx(10 ** 1.5)


def _wrong(monkeypatch):
    """Replace every estimator formula the items use by a wrong one (sign, factor, offset)."""
    where = {"least_squares_line": rg, "minus3db_frequency": rg,
             **{n: jf for n in ("fit_scale_factor", "nonlinearity_jjf", "asymmetry_jjf",
                                "temperature_sensitivity", "fifty_percent_candidate",
                                "warmup_time_s")},
             **{n: ief for n in ("linearity_errors_iec", "symmetry_iec", "ratiometric_error_iec",
                                 "g_slope_iec", "resolution_iec", "hysteresis_iec")}}
    orig = {n: getattr(m, n) for n, m in where.items()}

    def scaled(name, factor):
        # floats and tuples of floats scaled; any other return (a ScaleFactorFit, an
        # Asymmetry) refused outright, so a truth calling those estimators fails too
        def f(*a, **k):
            r = orig[name](*a, **k)
            if isinstance(r, float):
                return r * factor
            if isinstance(r, tuple) and type(r) is tuple:
                return tuple(v * factor if isinstance(v, float) else v for v in r)
            raise AssertionError(f"the truth called the estimator {name}")
        return f

    for name in orig:
        monkeypatch.setattr(where[name], name, scaled(name, 1.37))
    monkeypatch.setattr(rg, "OMEGA_E_DPS", rg.OMEGA_E_DPS * 2)
    monkeypatch.setattr(rg, "MINUS_3DB_RATIO", 0.5)


def _flat(d):
    return {k: v["value"] for k, v in d.items()}


@pytest.mark.parametrize("spec", ("jjf1535-2015", "iec62047-20"))
def test_truth_does_not_use_the_estimators(spec, monkeypatch):
    if spec == "jjf1535-2015":
        from gonio.specs.jjf1535.protocol import load_protocol
        from gonio.specs.jjf1535.truth import truth
    else:
        from gonio.specs.iec62047_20.protocol import load_protocol
        from gonio.specs.iec62047_20.truth import truth
    bench = load_rate_bench("mems-adxrs610").without_noise()
    bench = replace(bench, gyro=replace(bench.gyro, warmup_bias_dps=0.12))
    proto = load_protocol(spec)
    before = _flat(truth(bench, proto))
    assert sum(isinstance(v, float) and v != 0 and math.isfinite(v)
               for v in before.values()) >= 10
    _wrong(monkeypatch)
    # the mutation is real: the estimators now give other numbers
    assert rg.least_squares_line([0, 1, 2], [0, 1, 2])[0] == pytest.approx(1.37)
    after = _flat(truth(bench, proto))
    assert after == before


def test_warmup_truth_does_not_use_the_warmup_estimator(monkeypatch):
    """7.2.9: the warm-up truth (noise on: the expected window stability, and noise off) comes
    from the bench's transient, its noise covariance and the procedure's W, P, t0, nominal —
    never from the estimator's window stabilities, exceedance search or detection interval."""
    from gonio.specs.jjf1535.protocol import load_protocol
    from gonio.specs.jjf1535.truth import truth

    proto = load_protocol("jjf1535-2015")
    noisy = load_rate_bench("mems-adxrs610")
    benches = (noisy, noisy.without_noise())
    before = [truth(b, proto)["warmup_time"] for b in benches]
    assert all(math.isfinite(t["value"]) and t["value"] > 0 for t in before)
    assert before[0]["value"] != before[0]["noise_free_s"]      # the noise is part of it

    def refuse(*_a, **_k):
        raise AssertionError("the warm-up truth called an estimator")
    for mod, name in ((jf, "window_stabilities"), (jf, "detection_interval"),
                      (jf, "last_exceedance_time"), (rg, "last_exceedance_time"),
                      (jf, "warmup_time_s")):
        monkeypatch.setattr(mod, name, refuse)
    assert [truth(b, proto)["warmup_time"] for b in benches] == before
