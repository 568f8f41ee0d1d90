"""A noise rms is a dispersion and is stated as one: IEC 62047-20 5.4.5.1 b) in-band and
c) broadband rms by the one-sided χ² 95 % interval of :func:`gonio.kit.dispersion_uncertainty`
(ν = ½(rms/u_c)², no k, no "± U"), as JJF's B_s, beyond the bound of the gyro's temperature
during the static record where the 5.3.3.6 visits give its coefficient; IEC 5.3.3.4's half range by the normal
range's interval with no k and no ν. Checked against scipy.stats.chi2 and a Monte Carlo of
white-noise records whose true band rms is known in closed form."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from gonio.kit import dispersion_uncertainty, from_u, gum, item_statement
from gonio.result.model import Uncertainty


def _chi2_upper(s: float, u_c: float) -> tuple[float, float]:
    """ν = ½(s/u_c)² (JCGM 100 E.4.3 read backwards) and σ's one-sided 95 % upper limit from
    ν as stated, its integer part (no ∞ above 1000: the limit still moves with ν there)."""
    nu = 0.5 * (s / u_c) ** 2
    nu_s = max(1.0, math.floor(nu))
    return nu, s * math.sqrt(nu_s / stats.chi2.ppf(0.05, nu_s))


@pytest.mark.parametrize("s,u_c", [(1.0, 0.5), (48.0, 3.1), (0.0855, 2.6e-4), (2.0, 0.21)])
def test_dispersion_interval_is_the_chi2_upper_limit(s, u_c):
    u = dispersion_uncertainty(s, Uncertainty([], u_c, 2 * u_c, 2.0, 30.0, None, 0.95))
    nu, hi = _chi2_upper(s, u_c)
    assert u.k is None and u.k_source == "chi-square" and u.coverage_probability == 0.95
    assert u.nu_eff == pytest.approx(nu, rel=1e-12)
    assert u.interval[0] == 0.0 and u.interval[1] == pytest.approx(hi, rel=1e-10)
    assert u.U == pytest.approx(hi - s, rel=1e-9) and u.u_c == u_c
    st = item_statement({"value": s, "unit": "°/s", "measured": True, "nonnegative": True,
                         "uncertainty": u.to_json()})
    text = st.text()
    # the ν stated is the one the limit was computed with (0.0855/0.00026: ν = 54 067, not ∞)
    assert st.nu_eff == str(max(1, math.floor(nu))), st.nu_eff
    assert " ± " not in text and "k =" not in text and "p = 95 %" in text, text


def test_dispersion_of_zero_or_without_u_is_left_alone():
    u = Uncertainty([], 0.0, 0.0, 1.96, None, None, 0.95)
    assert dispersion_uncertainty(0.3, u) is u
    assert dispersion_uncertainty(0.0, Uncertainty([], 0.1, 0.2, 2.0, 5.0, None, 0.95)).k == 2.0


def test_band_rms_upper_bound_covers_white_noise():
    """The in-band item's chain (gonio's Welch density, the band rms, the Welch estimate's
    own u with ν = ½/u_rel², the GUM budget, the χ² statement) on 400 white-noise records of
    2¹⁵ samples: the true band rms σ·√(2Δt(f_hi − f_lo)) lies at or below the stated upper
    end in 95 % of records (Clopper–Pearson interval holding 0.95); the broadband item's
    u_rel = 1/√(segments × lines) is larger, and its upper end covers at least as often
    (Clopper–Pearson upper end ≥ 0.95). The upper end is never below the estimate."""
    from gonio.analysis.noise.psd import welch_band_rms_u_rel, welch_psd
    from gonio.specs.iec62047_20 import formulas as ief

    rng = np.random.default_rng(54512)
    dt, n, nper, sigma, f_lo, f_hi = 0.01, 2 ** 15, 4096, 0.7, 10.0, 40.0
    truth = sigma * math.sqrt(2.0 * dt * (f_hi - f_lo))
    trials, hits, hits_bb = 400, 0, 0
    nseg = 2 * n // nper - 1

    def stated(rms, u_rel):
        return dispersion_uncertainty(rms, gum(lambda r: r, [
            from_u("rms", rms, rms * u_rel, dof=0.5 / u_rel ** 2)]))

    for _ in range(trials):
        x = rng.normal(0.0, sigma, n)
        f, p = welch_psd(x, 1.0 / dt, nper)
        d = ief.broadband_noise_iec(f, p, f_lo, f_hi)
        sel = (f >= f_lo) & (f <= f_hi) & (p > 0)
        u = stated(d["rms_dps"], welch_band_rms_u_rel(n, nper, p[sel], float(f[1] - f[0])))
        assert u.k is None and u.interval[1] > d["rms_dps"]
        hits += truth <= u.interval[1]
        hits_bb += truth <= stated(d["rms_dps"], 1.0 / math.sqrt(nseg * d["lines"])).interval[1]
    ci = stats.binomtest(hits, trials, 0.95).proportion_ci(0.95)
    assert ci.low <= 0.95 <= ci.high, (hits / trials, ci)
    assert hits_bb >= hits
    assert stats.binomtest(hits_bb, trials, 0.95).proportion_ci(0.95).high >= 0.95


@pytest.fixture(scope="module")
def iec_noisy(tmp_path_factory):
    sys.path.insert(0, str(Path(__file__).parent))
    from test_rate_iec_items import small_protocol

    from gonio.formats.rate_readings import RateReadings
    from gonio.specs._rate_family.simulate import study_bench
    from gonio.specs.iec62047_20 import calibrate
    from gonio.specs.iec62047_20.simulate import simulate

    tmp = tmp_path_factory.mktemp("iecnoise")
    proto = small_protocol(tmp, "iec62047-20")
    res = simulate(study_bench(), str(proto), seed=3, noise=True)
    rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
    _IEC_DATA["readings"] = res.data
    return calibrate(rd, str(proto)), res.truth["items"]


#: the iec_noisy fixture's readings (its tests read the records' count off them)
_IEC_DATA: dict = {}


@pytest.mark.parametrize("key", ["inband_noise", "broadband_noise", "arw"])
def test_iec_noise_rms_stated_by_its_one_sided_limit(iec_noisy, key):
    """The item's one statement is the χ² upper limit of its lines other than the gyro's
    temperature during the static record, rms·√(ν/χ²_0.05,ν), ν = ½(rms/u_rest)² (scipy.stats
    .chi2), divided by 1 − g, g that temperature's bound relative error (the one-sided bound
    condition; its g is checked against the 5.3.3.6 coefficient in test_rate_bound_u_c);
    no k; the bench's true rms lies below the upper end. The same for 5.4.5.2's ARW
    (N = σ(τ)·√τ, a dispersion too; its line's edf in the budget)."""
    result, truth = iec_noisy
    it = result.items[key]
    u = it.uncertainty
    rows = {c["symbol"]: c for c in u.components}
    assert "dT_noise" in rows
    u_rest = math.sqrt(sum(c["contribution"] ** 2 for k, c in rows.items() if k != "dT_noise"))
    nu, hi = _chi2_upper(it.value, u_rest)
    g = it.details["bound_condition"]["g_rel"]["dT_noise"]
    assert 0 < g < 0.05
    assert u.k is None and u.k_source == "U = a + R: [0, (s + R)/(1 − g)]"
    assert u.nu_eff == pytest.approx(nu, rel=1e-12)
    assert u.interval == (0.0, pytest.approx(hi / (1.0 - g), rel=1e-10))
    assert truth[key]["value"] <= u.interval[1]
    st = item_statement(it, nonnegative=True)
    assert st.U is None and st.k is None and st.upper is not None and " ± " not in st.text()
    # ν stated: the rest's, as the limit was computed with it
    assert st.nu_eff == str(max(1, math.floor(nu)))


def test_iec_broadband_row_nu_is_the_one_its_u_implies(iec_noisy):
    """The broadband rms's Welch row: u_rel = 1/√(segments × lines) with the ν of a standard
    deviation of that spread, ½/u_rel² (not segments × lines, twice that), so the row's ν
    and the statement's ν = ½(rms/u_c)² tell one story."""
    result, _ = iec_noisy
    it = result.items["broadband_noise"]
    row = next(c for c in it.uncertainty.components if c["symbol"] == "rms")
    u_rel = row["u"] / it.value
    assert row["dof"] == pytest.approx(0.5 / u_rel ** 2, rel=1e-9)
    assert u_rel ** -2 == pytest.approx(round(u_rel ** -2), abs=1e-6)   # segments × lines
    assert round(u_rel ** -2) % it.details["lines"] == 0


def test_iec_half_range_states_no_k_and_no_nu(iec_noisy):
    """5.3.3.4: the interval is the normal range's for n records, not a t or χ² of some ν:
    the row prints "—" for k and ν_eff, never ν 2 beside no k. Its upper end checked
    independently of gonio's formula: hr·d_n/w_0.05 with d_n (the mean range) and w_0.05
    (the 5 % quantile of the range) of n standard normals by a seeded Monte Carlo of
    4·10⁵ draws, n counted off the readings' bias records (relative MC error ≈ 0.3 %)."""
    result, _ = iec_noisy
    it = result.items["bias_repeatability"]
    u = it.uncertainty
    assert u.k is None and u.nu_eff is None and u.interval[0] == 0.0
    bias = _IEC_DATA["readings"]
    bias = bias[bias["test"] == "bias"]
    n = len(bias.groupby(["run", "step"]))
    assert n >= 2
    x = np.random.default_rng(20261202).standard_normal((400_000, n))
    w = x.max(axis=1) - x.min(axis=1)
    upper = it.value * float(w.mean()) / float(np.quantile(w, 0.05))
    assert u.interval[1] == pytest.approx(upper, rel=1e-2)
    # the two-sided 95 % reading (w_0.025) or the median would be off by more than that
    assert abs(it.value * float(w.mean()) / float(np.quantile(w, 0.025)) - upper) > 0.05 * upper
    st = item_statement(it, nonnegative=True)
    assert st.k is None and st.nu_eff is None and st.upper is not None


def test_decision_on_a_chi2_interval_with_nu_above_1000():
    """A noise rms's ν is often above 1000 (stated by its integer part, never ∞, as its
    interval is computed): its decision takes σ's χ² distribution with that ν,
    P(σ ≤ T) = χ²_ν.sf(ν s²/T²) (scipy), not an error."""
    from gonio.analysis.conformity import decide_items
    from gonio.result.model import Item, Result

    s = 0.0856
    u = dispersion_uncertainty(s, Uncertainty([], 2.6e-4, 5e-4, 1.96, 5e4, None, 0.95))
    assert u.nu_eff > 1000
    r = Result("s", "S", {"broadband_noise": Item("broadband_noise", "broadband", "5.4.5.1 c)",
                                                   "°/s", s, uncertainty=u, nonnegative=True)},
               {}, {})
    (c,) = decide_items(r, [{"item": "broadband_noise", "upper": 0.0862}], {"rule": "guarded"})
    assert c.outcome == "pass", c
    nu = math.floor(u.nu_eff)
    want = stats.chi2.sf(nu * s * s / 0.0862 ** 2, nu)
    assert c.conformance_probability == pytest.approx(want, rel=1e-9)
