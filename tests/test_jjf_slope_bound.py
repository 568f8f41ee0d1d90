"""JJF 1535 7.2.5 K_t and 7.2.14 B_t with the gyro's temperature error at the chamber's set
points at its bound: the `cold` study case puts the gyro 3 °C below the hot set point (the room
point is not in the chamber), which shortens the span each slope is divided by, and a
root-sum-square line for it under-covered (K_t 24 of 40, B_t 33 of 40, seed 20261261). Each
slope's reach now carries b_i = |x_i|·B/(|T_i − T_rt| − B) (gonio.specs.jjf1535.items
.temperature_slope_bound) in the interval of the extreme of magnitudes; checked here against
the readings' own metadata, scipy's quantiles and the bench's truth."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import pytest
from scipy import stats

from gonio.specs import get

SLOPES = ("sf_temperature_sensitivity", "bias_temperature_sensitivity")


@pytest.fixture(scope="module")
def cold_trials():
    """Three trials of JJF 1535's study programme in the `cold` case, calibrated: (readings,
    truth, result) each."""
    from gonio.analysis.coverage import spawn_seed
    from gonio.pipeline.coverage import case_stream, reduced_protocol, study_bench
    from gonio.pipeline.dispatch import screen_and_calibrate

    spec = get("jjf1535-2015")
    with tempfile.TemporaryDirectory() as d:
        proto = spec.load_protocol(str(reduced_protocol(spec.key, Path(d) / "r.toml")))
    bench = study_bench(spec, None, "cold")
    out = []
    for i in range(3):
        rd, truth = spec.run_trial(bench, proto,
                                   spawn_seed(20261261, case_stream(spec, "cold"), i))
        out.append((rd, truth, screen_and_calibrate(spec, rd, proto)))
    return out


def _bound_c(metadata: dict) -> float:
    return float(metadata["chamber_deviation_bound_c"]) + \
        float(metadata["chamber_uniformity_c"]) / 2.0


@pytest.mark.parametrize("key", SLOPES)
def test_each_slope_reaches_its_temperature_bound(cold_trials, key):
    """b_i recomputed from the item's temperatures, slopes and the readings' chamber bounds;
    the upper end max_i(|x_i| + t(ν_i)·u_i + b_i) with the t quantile of the interval's own
    upper tail (scipy); u_c kept beside, not stated (the bound condition in the details)."""
    from gonio.result.statement import u_c_certified

    for rd, _, res in cold_trials:
        it = res.items[key]
        d = it.details
        B = _bound_c(rd.metadata)
        rt = d["room_index"]
        temps = d["temperatures_c"]
        slopes = d["slopes_per_c"] if key == SLOPES[0] else d["slopes"]
        others = [j for j in range(len(temps)) if j != rt]
        want = [abs(slopes[j]) * B / (abs(temps[j] - temps[rt]) - B) for j in others]
        bc = d["bound_condition"]
        assert bc["b"] == pytest.approx(want, rel=1e-12) and set(bc["a_lines"]) == {"dT"}
        mi = d["max_abs_interval"]
        q = stats.norm.cdf(mi["c_upper"])
        upper = max(abs(mi["x"][i]) + stats.t.ppf(q, bc["nu_rest"][i]) * bc["u_rest"][i]
                    + want[i] for i in range(len(others)))
        assert it.uncertainty.interval[1] == pytest.approx(upper, rel=1e-9)
        assert not u_c_certified(it)


@pytest.mark.parametrize("key", SLOPES)
def test_the_bound_holds_the_truth_the_rest_alone_misses(cold_trials, key):
    """In every cold trial the bench's truth lies inside the stated interval, and above the
    upper end the other lines alone would give (the bound is what holds it)."""
    for _, truth, res in cold_trials:
        it = res.items[key]
        t = truth["items"][key]["value"]
        lo, hi = it.uncertainty.interval
        assert lo <= t <= hi, (key, lo, t, hi)
        d = it.details
        mi, bc = d["max_abs_interval"], d["bound_condition"]
        q = stats.norm.cdf(mi["c_upper"])
        rest = max(abs(mi["x"][i]) + stats.t.ppf(q, bc["nu_rest"][i]) * bc["u_rest"][i]
                   for i in range(len(bc["b"])))
        if key == SLOPES[0]:        # K_t read 6 % low at the hot point: beyond the noise
            assert t > rest, (t, rest)


def test_the_bound_is_exact_for_a_linear_response():
    """A response linear in T read over a span shortened or stretched by up to B, divided by
    the nominal span: the true slope lies within the reading ± b at every δ in [−B, B] and at
    δ = −B exactly on the bound."""
    from gonio.specs.jjf1535.items import temperature_slope_bound

    beta, d, B = 1.6e-4, 50.0, 3.0
    for delta in (-B, -1.0, 0.0, 2.0, B):
        x = beta * (d + delta) / d
        assert abs(beta - x) <= temperature_slope_bound(x, d, B) * (1 + 1e-12)
    x = beta * (d - B) / d
    assert temperature_slope_bound(x, d, B) == pytest.approx(beta - x, rel=1e-12)
    assert math.isinf(temperature_slope_bound(1.0, 2.0, B))


def test_each_points_rest_is_its_model_without_the_bounded_line():
    """The u_i, ν_i of the bound condition are each point's budget less the line ``dT``
    (gonio.result.gum.rest_of): the same as the model evaluated again without that input (the
    slope (a − b)/(b·d) at d's value), u by JCGM 100 5.1.2 and ν by Welch–Satterthwaite; and
    max_magnitude_statement's figures carry them."""
    from gonio.kit import from_u, gum, type_b
    from gonio.result.gum import max_magnitude_statement, rest_of

    pts, rest2, x = [], [], []
    for Ki, uK, nu, d in ((1.62e-4, 2e-8, 7, 45.0), (1.50e-4, 3e-8, 12, -60.0)):
        pts.append(gum(lambda a, b, t: (a - b) / (b * t), [
            from_u("K_i", Ki, uK, dof=nu), from_u("K_rt", 1.55e-4, 1.5e-8, dof=9),
            type_b("dT", d, 3.0, "rectangular")]))
        rest2.append(gum(lambda a, b: (a - b) / (b * d), [
            from_u("K_i", Ki, uK, dof=nu), from_u("K_rt", 1.55e-4, 1.5e-8, dof=9)]))
        x.append((Ki - 1.55e-4) / (1.55e-4 * d))
    for p, q in zip(pts, rest2):
        ur, nr = rest_of(p, ("dT",))
        assert ur == pytest.approx(q.u_c, rel=1e-9)
        assert nr == pytest.approx(q.nu_eff, rel=1e-9)
        assert ur < p.u_c
    b = [1e-6, 2e-6]
    _, u, fig = max_magnitude_statement(pts[0], x, pts, max(abs(v) for v in x),
                                        bounded={"symbol": "dT", "b": b, "basis": "test"})
    bc = fig["bound_condition"]
    assert bc["u_rest"] == pytest.approx([q.u_c for q in rest2], rel=1e-9)
    assert bc["nu_rest"] == pytest.approx([q.nu_eff for q in rest2], rel=1e-9)
    assert bc["b"] == b and u.interval[1] == pytest.approx(bc["upper"])
