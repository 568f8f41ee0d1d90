"""IEC 62047-20: one rule for the rate random walk's E[K²] on one certificate.

Every item whose budget carries the bias drift between its records (the scale-factor slope
and everything computed with it, linearity, 5.1.3.5, 5.1.3.8, 5.3.3.3, 5.3.3.6–5.3.3.9)
takes E[K²] from ``formulas.walk_k2_iec``, the posterior mean given the static record's Allan
variances (``items.drift_coef_dps``), and no longer from the 95 % bound of
``formulas.walk_coefficient_bound``; 5.3.3.5's bootstrap draws its walk at the same E[K²]
(``items.drift_coef_power_on_dps``). The test replaces the rule and the bound by others
and requires each such item's U to move, and the shared rate-family rule (JJF 1535's,
``drift_coefficients`` with the 68 % limits and K̂² + u_K²) to be called by no IEC item:
an item that kept its own rule, or went back to the shared one, fails here.

One virtual calibration of the pinned small programme (tests/data/pins, seed 7).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from gonio.specs._rate_family import formulas as rg
from gonio.specs.iec62047_20 import calibrate
from gonio.specs.iec62047_20 import formulas as ief

ROOT = Path(__file__).resolve().parents[1]
PROTOCOL = ROOT / "tests" / "data" / "pins" / "iec62047-20-small.toml"

#: The items whose budgets carry the bias drift as a standard uncertainty.
DRIFT_ITEMS = ("scale_factor", "initial_sf_variation", "sf_temperature_coefficient",
               "ratiometric_error", "linearity", "symmetry", "bias_ratiometric_error",
               "bias_temperature_coefficient", "bias_hysteresis", "g_sensitivity",
               "startup_time", "bias_drift_after_power_on")


def _numbers(result) -> dict:
    items = result.items.items() if isinstance(result.items, dict) else \
        [(i.key, i) for i in result.items]
    return {k: (it.value, None if it.uncertainty is None else it.uncertainty.U)
            for k, it in items}


@pytest.fixture(scope="module")
def readings(tmp_path_factory):
    out = tmp_path_factory.mktemp("iec-walk")
    r = subprocess.run([sys.executable, "-m", "gonio", "simulate", "--spec", "iec62047-20",
                        "--protocol", str(PROTOCOL), "--seed", "7", "--out", str(out / "sim")],
                       cwd=out, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return out / "sim" / "readings.csv"


@pytest.fixture(scope="module")
def plain(readings):
    return _numbers(calibrate(readings, PROTOCOL))


def test_no_item_uses_the_shared_rule(readings, plain, monkeypatch):
    def refused(*a, **k):
        raise AssertionError("an IEC item used the shared rate-family drift rule")
    for name in ("drift_coefficients", "bias_drift_u", "record_difference_u"):
        monkeypatch.setattr(rg, name, refused)
    assert _numbers(calibrate(readings, PROTOCOL)) == plain


def test_every_drift_item_takes_the_one_rule(readings, plain, monkeypatch):
    rule = ief.walk_k2_iec
    calls = []

    def other(*args, **kw):                     # another rule: 4× the E[K²]
        calls.append(kw)
        return 4.0 * rule(*args, **kw) + 1e-3
    monkeypatch.setattr(ief, "walk_k2_iec", other)
    now = _numbers(calibrate(readings, PROTOCOL))
    assert calls
    kept = [k for k in DRIFT_ITEMS if now[k][1] == plain[k][1]]
    assert not kept, f"U unchanged by the walk rule: {kept}"
    # the bias is not untouched: its e_TU line is the chamber bound × (|β| + U(β)), U(β) of
    # 5.3.3.6, a drift item
    untouched = {"arw", "bias_instability", "inband_noise", "broadband_noise", "frequency_band"}
    assert all(now[k] == plain[k] for k in untouched)


def test_no_drift_item_takes_the_95_percent_bound(readings, plain, monkeypatch):
    """E[K²] is the posterior mean, not the end of a rectangle up to the 95 % bound: scaling
    that bound moves no drift item's U."""
    bound = ief.walk_coefficient_bound

    def spy(tau_s, adev, edf, p=0.95):
        return 0.25 * bound(tau_s, adev, edf, p)
    monkeypatch.setattr(ief, "walk_coefficient_bound", spy)
    now = _numbers(calibrate(readings, PROTOCOL))
    assert all(now[k] == plain[k] for k in DRIFT_ITEMS)


def test_no_posterior_falls_back_to_the_bound_not_to_zero(readings, plain, monkeypatch):
    """A record whose likelihood gives no finite posterior mean (no usable τ) must not drop
    the walk from the drift terms (E[K²] = 0 would understate every drift item's U): the
    record's 95 % bound stands in, so each drift item's U is at least as large as with the
    posterior mean on this record (whose bound is above it)."""
    monkeypatch.setattr(ief, "walk_k2_iec", lambda *a, **k: float("nan"))
    now = _numbers(calibrate(readings, PROTOCOL))
    smaller = [k for k in DRIFT_ITEMS if now[k][1] is not None and plain[k][1] is not None
               and now[k][1] < plain[k][1] * (1 - 1e-9)]
    assert not smaller, f"U fell below the posterior mean's without a walk term: {smaller}"


def test_the_ratiometric_rest_points_take_the_windows_covariance(readings, monkeypatch):
    """5.3.3.3's drift line between a supply's rest point and V_BASE's is the five-term
    model's covariance of the two rest windows (``items.window_drift_u_dps``), not the
    adjacent records' floor (``items.drift_u_dps`` at their separation): the supply runs are
    minutes apart, where the flicker's difference has grown past that floor. Each call's
    windows are the rest points' (start, span), minutes apart; the stated line is the
    windows' u in output units, and larger than the floor's at the same separation (on the
    old rule the two were equal: 400-trial coverage 0.935, z mean +0.26 → 0.960, +0.15)."""
    from gonio.specs.iec62047_20 import items as I

    calls = []
    real = I.window_drift_u_dps

    def spy(ctx, first, second):
        u = real(ctx, first, second)
        calls.append((ctx, first, second, u))
        return u

    monkeypatch.setattr(I, "window_drift_u_dps", spy)
    res = calibrate(readings, PROTOCOL)
    it = dict((i.key, i) for i in res.items)["bias_ratiometric_error"] \
        if not isinstance(res.items, dict) else res.items["bias_ratiometric_error"]
    drift = next(c for c in it.uncertainty.components if c["symbol"] == "drift")
    ours = [(ctx, f, s, u) for ctx, f, s, u in calls
            if abs(u * abs(ctx.a_base) - drift["u"]) <= 1e-12 * drift["u"]]
    assert ours, [(f, s) for _, f, s, _ in calls]
    ctx, first, second, u = ours[0]
    sep = abs(first[0] - second[0])
    assert sep > 60.0 and first[1] > 0 and second[1] == first[1]
    assert u > 1.05 * I.drift_u_dps(ctx, sep)
