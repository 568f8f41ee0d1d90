"""E (7.4) where the built-in programme measured the tilt in situ: every E_ij corrected for the
tilt × Earth-rate coupling at the measured ψ and azimuth (the reading's own and that of the
7.1 K it is converted with), certified with the physical budget whose line tilt_Em is the
correction's u; the draft's reading (E as measured, Annex A's four lines) beside. Checked
against the bench: the same instrument's noise-free session untilted (the truth the
correction aims at), never the estimator; the u against a Monte Carlo of the whole chain
(noisy tilt-estimate rests → ψ, α → the correction)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.study import (ideal_bench, tilted, validation_protocol,
                                          worst_azimuth)


def _analyse(proto, bench, budget="physical"):
    res = run_session(proto, bench, seed=5)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    return analyse(Readings(df, dict(res.metadata)), proto, budget=budget)


@pytest.fixture(scope="module")
def sessions():
    """The rlg instrument with noise, bias, drift and table errors off, the Earth rate on:
    tilted at the A.1 bound at two azimuths (the worst for the 7.1 K and 90° from it), and
    untilted (the truth: the same instrument's E with no coupling to correct)."""
    proto = validation_protocol(all_items=True)
    assert proto.tilt_estimate is not None
    base = replace(load_bench("rlg"), sample_rate_hz=5.0)
    quiet = replace(ideal_bench(base), earth_rate=True)
    az = worst_azimuth(base, proto, 0.1)
    tilt = [_analyse(proto, tilted(quiet, 0.1, a)) for a in (az, az + 90.0)]
    return proto, quiet, tilt, _analyse(proto, quiet)


def test_e_corrected_at_the_measured_tilt_meets_the_untilted_instrument(sessions):
    """Per point, the corrected E_i equals the untilted session's to 2 mas, where the draft's
    reading (as measured) is off by the coupling (> 0.1″, 50× more); E is the corrected
    curve's signed extreme; the draft's value is kept beside, uncorrected."""
    _, _, tilt, flat = sessions
    truth = flat.results.angle_deviation.table["E_arcsec"].to_numpy()
    # untilted, the estimate measures ψ ≈ 0 and the correction is nil
    assert flat.results.angle_deviation.details["tilt_correction"][
        "max_abs_correction_arcsec"] < 1e-3
    for rep in tilt:
        e = rep.results.angle_deviation
        fixed = np.abs(e.table["E_arcsec"].to_numpy() - truth).max()
        raw = np.abs(e.table["E_draft_arcsec"].to_numpy() - truth).max()
        assert fixed < 0.002 and raw > 0.1 and raw > 50 * fixed, (raw, fixed)
        v = e.table["E_arcsec"].to_numpy()
        assert e.value == v[np.argmax(np.abs(v))]
        d = e.details["estimates"]["draft"]
        assert d["value"] == e.table["E_draft_arcsec"].to_numpy()[
            np.argmax(np.abs(e.table["E_draft_arcsec"].to_numpy()))]
        assert e.details["stated"] == "tilt_corrected"
        assert abs(e.details["tilt_correction"]["tilt_deg"] - 0.1) < 1e-4


def test_physical_budget_carries_the_correction_not_the_bound(sessions):
    """The certified (physical) budget has tilt_Em, the correction's u, in place of tilt_E at
    the A.1 bound, and its U is smaller; results.json gives the draft's E and U beside."""
    _, _, tilt, _ = sessions
    rep = tilt[0]
    syms = [c.symbol for c in rep.uncertainty.gum.contributions]
    assert "tilt_Em" in syms and "tilt_E" not in syms
    unc = rep.uncertainty_dict()
    assert unc["draft_reading"]["E_arcsec"] == rep.results.angle_deviation.details[
        "estimates"]["draft"]["value"]
    ia = rep.item_uncertainty["angle_deviation"]
    em = [c for c in ia.components if c.symbol == "tilt_Em"][0]
    assert em.beyond_draft and "measured" in em.clause


def test_no_measured_tilt_keeps_e_as_measured_with_the_bound_line(sessions):
    """A programme without the tilt estimate: E as measured, the bound's tilt_E line."""
    proto, quiet, _, _ = sessions
    plain = replace(proto, extra={k: v for k, v in proto.extra.items()
                                  if k != "tilt_estimate"})
    assert plain.tilt_estimate is None
    rep = _analyse(plain, tilted(quiet, 0.1, 30.0))
    e = rep.results.angle_deviation
    assert "estimates" not in e.details and "E_draft_arcsec" not in e.table
    syms = [c.symbol for c in rep.uncertainty.gum.contributions]
    assert "tilt_E" in syms and "tilt_Em" not in syms


def test_correction_u_against_a_monte_carlo_of_the_tilt_estimate():
    """u of the correction (linear propagation of the fit's covariance, JCGM 100 5.2) against
    the spread of the correction over noisy tilt-estimate rests (JCGM 101: the whole chain
    redone per draw): within 10 % (400 draws) at every reading, where u is not negligible."""
    from gonio.specs import DEFAULT_KEY, get
    from gonio.specs.ogam_draft.budget_extra import (angle_tilt_correction,
                                                     scale_factor_tilt_correction)
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.tilt_estimate import estimate_tilt

    p = load_protocol(get(DEFAULT_KEY).default_protocol)
    sf = pd.DataFrame({"table_deg": [60.0, 120.0, 180.0, 240.0, 300.0, 360.0],
                       "time_s": [11.0, 12.0, 13.0, 14.0, 15.0, 16.0]})
    ad = pd.DataFrame({"table_deg": [30.0, 120.0, 210.0, 360.0],
                       "time_s": [10.5, 12.0, 13.5, 16.0]})
    th = np.arange(12) * 30.0
    amp = 11.522126 * math.sin(math.radians(0.08))
    clean = 9.7 + amp * np.cos(np.radians(th + 50.0))
    rng = np.random.default_rng(11)
    sigma = 0.2 * amp                      # a rest's noise: u(ψ) ≈ 6 %, u(α) ≈ 3.3°

    def corr(y):
        c = scale_factor_tilt_correction(sf, p, 40.0, estimate_tilt(th, y, 40.0, "up"))
        return angle_tilt_correction(sf, ad, p, 40.0, c)

    out = [corr(clean + rng.normal(0.0, sigma, th.size)) for _ in range(400)]
    draws = np.array([c.error_arcsec for c in out])
    # each draw's u rests on its own fit's residuals (ν = 9): compare the mean of u²
    u = np.sqrt(np.mean([c.u_arcsec ** 2 for c in out], axis=0))
    sd = draws.std(axis=0, ddof=1)
    assert np.all(np.abs(sd / u - 1.0) < 0.10), (sd, u)
    assert np.abs(draws.mean(axis=0) - corr(clean).error_arcsec).max() < 0.2 * sd.max()
