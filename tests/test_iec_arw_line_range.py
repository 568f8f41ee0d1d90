"""IEC 62047-20 5.4.5.2: the −½ line's τ range is the reading taken's rule applied to the
fitted model's curve, not to the data, so the line reading does not select its points by
their own scatter; the standard's reading (the rule on the data) is given beside.

Checked against things gonio does not compute: an exact curve written out here (white rate
noise plus rate random walk, σ² = N²/τ + K²τ/3, IEEE 952 Annex C) with antithetic log
perturbations (each τ once up, once down by the same factor): any reading that is the
geometric mean over a range fixed in advance returns N exactly on the pair average, whatever
the perturbation; a range chosen by the perturbed data does not (it reads low)."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from gonio.analysis.noise import allan_deviation
from gonio.specs.iec62047_20 import formulas as ief
from gonio.specs.iec62047_20 import items as I

N_SQRT_S, K2 = 108.0, 0.0063 * 108.0 ** 2 / 1.0       # (°/h)·√s; the −½ range ends near 5 s


def _exact(tau):
    tau = np.asarray(tau, float)
    return np.sqrt(N_SQRT_S ** 2 / tau + K2 * tau / 3.0)


MODEL = SimpleNamespace(N=N_SQRT_S, adev=_exact)


def _allan(adev):
    a = allan_deviation(np.random.default_rng(1).standard_normal(20_000), 0.1, "rate",
                        "decade:10", unit="deg/h")
    return dataclasses.replace(a, adev=np.asarray(adev, float))


def _ensemble(delta=0.02):
    """(tau, list of perturbed curves): each τ of the exact curve once × e^δ, once × e^−δ."""
    a0 = _allan(np.ones(1))
    tau = np.asarray(a0.tau_s, float)
    base = _exact(tau)
    out = []
    for k in range(tau.size):
        for s in (1.0, -1.0):
            e = np.zeros(tau.size)
            e[k] = s * delta
            out.append(base * np.exp(e))
    return tau, out


def test_the_line_range_is_the_rule_on_the_model_curve():
    a = _allan(_exact(_allan(np.ones(1)).tau_s) * 1.03)
    _, _, _, _, mask = I.arw_reading(a, MODEL)
    _, expect = ief.arw_minus_half_line(a.tau_s, _exact(a.tau_s))
    assert mask.any() and np.array_equal(mask, expect)
    slope = np.gradient(np.log(_exact(a.tau_s)), np.log(a.tau_s))   # the curve's own slope
    assert np.all(np.abs(slope[mask] + 0.5) <= 0.05) and abs(slope[mask.sum()] + 0.5) > 0.05


def test_antithetic_perturbations_average_to_the_model_N():
    """The certified reading over every ± pair averages (in log) to N exactly; the
    standard's rule on the same curves reads low — its range ends where a perturbation
    flattens the data's slope, keeping the lowered point."""
    tau, curves = _ensemble()
    ours, std = [], []
    for c in curves:
        a = _allan(c)
        value, *_ = I.arw_reading(a, MODEL)
        ours.append(math.log(value))
        std_val, std_mask = ief.arw_minus_half_line(a.tau_s, c)
        # the standard's range, corrected by the same model's lift over that range
        lift = I.arw_lift_factor(a.tau_s, std_mask, MODEL)
        std.append(math.log(std_val / lift))
    truth = math.log(N_SQRT_S / math.sqrt(3600.0))
    assert np.mean(ours) == pytest.approx(truth, abs=1e-12)
    # selection: −1.3·10⁻⁴ in ln (δ = 0.02; the curve's slope is −0.449 at the range's end)
    assert np.mean(std) < truth - 5e-5, np.mean(std) - truth


def test_item_gives_the_standard_reading_beside():
    """On a calibrated record the details carry the standard's reading (the rule on the
    data, uncorrected) beside the certified value, labelled, and its τ."""
    from gonio.bench.rate_gyro import NoiseState, load_rate_bench
    from gonio.analysis.noise import fit_markov_model

    g = load_rate_bench("mems-adxrs610").gyro
    x = NoiseState(g, np.random.default_rng(3)).samples(6000, 0.1, g.reference_temperature_c)
    a = allan_deviation(x * 3600.0, 0.1, "rate", "decade:10", unit="deg/h")
    value, line, ratio, _, mask = I.arw_reading(a, fit_markov_model(a))
    std_val, std_mask = ief.arw_minus_half_line(a.tau_s, a.adev)
    direct = math.exp(float(np.mean(np.log(a.adev[std_mask] * np.sqrt(a.tau_s[std_mask])))))
    assert std_val == pytest.approx(direct / 60.0, rel=1e-12)
    assert line == pytest.approx(math.exp(float(np.mean(
        np.log(a.adev[mask] * np.sqrt(a.tau_s[mask]))))) / 60.0, rel=1e-12)


def test_the_item_states_the_standard_reading_the_rule_gives_on_the_data():
    """The item's ``standard_reading`` (given beside, not certified) is the −½ line over the
    range the data's own slope gives, read at 1 h, uncorrected — recomputed here by hand from
    the record's Allan deviation (local slope by finite differences in log–log, the range from
    the shortest τ to the first slope outside −½ ± 0.05, the geometric mean of σ√τ, /60),
    so that a scaled or renamed reading fails."""
    from gonio.analysis.noise import fit_markov_model, fit_noise_model
    from gonio.bench.rate_gyro import NoiseState, load_rate_bench

    g = load_rate_bench("mems-adxrs610").gyro
    x = NoiseState(g, np.random.default_rng(11)).samples(20_000, 0.1, g.reference_temperature_c)
    a = allan_deviation(x * 3600.0, 0.1, "rate", "decade:10", unit="deg/h")
    key = ("allan", 6.0, 2500.0)
    cache = {key: (a, x * 3600.0, 0.1), "static_extent": (x.size, True),
             ("noise_fit", 6.0, 2500.0): fit_noise_model(a),
             ("noise_fit_shaped", 6.0, 2500.0): fit_markov_model(a)}
    ctx = SimpleNamespace(a_base=6.0, null_output=2500.0, cache=cache, has=lambda t: t == "static")
    item = I.arw(ctx)
    tau, sig = np.asarray(a.tau_s, float), np.asarray(a.adev, float)
    lt, ls = np.log(tau), np.log(sig)
    slope = np.empty(tau.size)
    slope[1:-1] = (ls[2:] - ls[:-2]) / (lt[2:] - lt[:-2])
    slope[0] = (ls[1] - ls[0]) / (lt[1] - lt[0])
    slope[-1] = (ls[-1] - ls[-2]) / (lt[-1] - lt[-2])
    n = int(np.argmax(np.abs(slope + 0.5) > 0.05)) if np.any(np.abs(slope + 0.5) > 0.05) \
        else tau.size
    assert n >= 2
    expect = math.exp(float(np.mean(ls[:n] + 0.5 * lt[:n]))) / 60.0
    got = item.details["standard_reading"]
    assert got["clause"] == "5.4.5.2"
    assert got["value"] == pytest.approx(expect, rel=1e-9)
    assert np.array_equal(np.asarray(item.details["standard_line_tau_s"]), tau[:n])
    assert "not certified" in got["text_en"] and "不作校准结果" in got["text_zh"]
