"""A calibrated table's degrees of freedom in the range items' Monte Carlo (K_l 7.2, C_v 7.6,
C_g 7.7; beyond the draft): the calibration's errors are drawn as scaled-and-shifted t with the
calibration's ν (JCGM 101 6.4.9; a covariance of one joint estimate as the multivariate t), by
the one function :func:`calibration_error_draws` that every draw goes through.

Checked against closed forms and a second algorithm: the draws' variance ν/(ν − 2)·u²; the
quantile of one position's (or one combination's) error against Student's t (SciPy); the
joint draws of a covariance against SciPy's own multivariate t on a statistic that tells a
joint χ² from independent ones (the largest |δe| of the positions); and a consistency whose
table dominates its errors, whose interval widens when the calibration's ν is small."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from gonio.specs.ogam_draft import item_uncertainty as iu
from gonio.specs.ogam_draft.item_uncertainty import (CalibratedTable, ConditionDeviation,
                                                     calibration_error_draws,
                                                     consistency_corrected_budget)
from gonio.specs.ogam_draft.table_calibration import TableCalibration

M = 200_000


def _cov(n: int, u: np.ndarray, rho: float = 0.4) -> np.ndarray:
    return rho ** np.abs(np.subtract.outer(np.arange(n), np.arange(n))) * np.outer(u, u)


def test_variance_is_nu_over_nu_minus_two():
    """Independent positions with their own ν (10, 6, ∞) and a covariance of one joint
    estimate (ν = 8): the draws' covariance is ν/(ν − 2)·V (the t's variance), per position
    for the first, the whole matrix for the second; without ``dof``, V itself."""
    u = np.array([0.02, 0.03, 0.05])
    x = [0.0, 120.0, 240.0]
    ind = TableCalibration(x, [0.0] * 3, u, "t", dof=[10, 6, math.inf])
    d = calibration_error_draws(ind, np.random.default_rng(1), M)
    want = u ** 2 * np.array([10 / 8, 6 / 4, 1.0])
    # sd of a sample variance of t_6 (kurtosis 3 + 6/(ν − 4) = 6): √((κ − 1)/M) ≈ 0.5 %
    assert np.var(d, axis=0) == pytest.approx(want, rel=0.03)
    assert abs(np.corrcoef(d.T)[0, 1]) < 0.01                     # independent positions

    v = _cov(3, u)
    joint = TableCalibration(x, [0.0] * 3, u, "t", cov_arcsec2=v, dof=[8, 8, 8])
    d = calibration_error_draws(joint, np.random.default_rng(2), M)
    assert np.cov(d.T) == pytest.approx(8 / 6 * v, rel=0.03, abs=1e-7)
    normal = TableCalibration(x, [0.0] * 3, u, "t", cov_arcsec2=v)
    d = calibration_error_draws(normal, np.random.default_rng(2), M)
    assert np.cov(d.T) == pytest.approx(v, rel=0.02, abs=1e-7)


@pytest.mark.parametrize("nu", [3.0, 5.0])
def test_quantile_of_one_position_is_student_t(nu):
    """One position's error over its u, and a combination cᵀδe over √(cᵀVc) of a covariance
    of one joint estimate (a multivariate t's every linear combination is t_ν), have the
    quantiles of Student's t with ν: the 97.5 % point of |δe|/u is t.ppf(0.975, ν) (3.18 at
    ν = 3, where the normal's 1.96 is 0.6 of it)."""
    u = np.array([0.02, 0.04, 0.03, 0.05])
    x = [0.0, 90.0, 180.0, 270.0]
    q_t = stats.t.ppf(0.975, nu)
    ind = TableCalibration(x, [0.0] * 4, u, "t", dof=[nu] * 4)
    d = calibration_error_draws(ind, np.random.default_rng(3), M)
    for p in range(4):
        assert np.quantile(np.abs(d[:, p]) / u[p], 0.95) == pytest.approx(q_t, rel=0.02)
    v = _cov(4, u, 0.6)
    joint = TableCalibration(x, [0.0] * 4, u, "t", cov_arcsec2=v, dof=[nu] * 4)
    c = np.array([1.0, -1.0, 0.5, 0.0])        # e(stop) − e(zero) and half a K part
    y = calibration_error_draws(joint, np.random.default_rng(4), M) @ c
    assert np.quantile(np.abs(y) / math.sqrt(c @ v @ c), 0.95) == pytest.approx(q_t, rel=0.02)
    assert q_t > 1.2 * stats.norm.ppf(0.975)


def test_joint_draws_are_scipys_multivariate_t():
    """A covariance of one joint estimate (ν = 3) draws one χ² per draw for every position:
    the distribution of the largest |δe_p|/u_p over five positions agrees with SciPy's
    multivariate t (a second algorithm; two-sample KS), and differs from independent t's per
    position (which a per-position draw would give: the largest of five independent heavy
    tails is larger)."""
    u = np.array([0.02, 0.03, 0.04, 0.03, 0.02])
    v = _cov(5, u, 0.3)
    x = [0.0, 72.0, 144.0, 216.0, 288.0]
    joint = TableCalibration(x, [0.0] * 5, u, "t", cov_arcsec2=v, dof=[3] * 5)
    ours = np.max(np.abs(calibration_error_draws(joint, np.random.default_rng(5), 50_000)) / u,
                  axis=1)
    ref = stats.multivariate_t(loc=np.zeros(5), shape=v, df=3).rvs(
        size=50_000, random_state=np.random.default_rng(6))
    theirs = np.max(np.abs(ref) / u, axis=1)
    assert stats.ks_2samp(ours, theirs).pvalue > 1e-3
    ind = TableCalibration(x, [0.0] * 5, u, "t", dof=[3] * 5)
    sep = np.max(np.abs(calibration_error_draws(ind, np.random.default_rng(5), 50_000)) / u,
                 axis=1)
    assert stats.ks_2samp(sep, theirs).pvalue < 1e-6


def test_without_dof_the_draws_are_unchanged():
    """No ``dof`` (ν = ∞): the generator is used as for the normal draws, byte for byte (the
    covariance's eigen-root times standard normals, JCGM 101 6.4.8), so a calibration without
    ν keeps its numbers."""
    u = np.array([0.02, 0.03, 0.05])
    v = _cov(3, u)
    cal = TableCalibration([0.0, 120.0, 240.0], [0.0] * 3, u, "t", cov_arcsec2=v)
    lam, q = np.linalg.eigh(v)
    want = np.random.default_rng(9).standard_normal((1000, 3)) @ (q * np.sqrt(lam)).T
    assert np.array_equal(calibration_error_draws(cal, np.random.default_rng(9), 1000), want)


def _consistency(dof, draws: int = 4000):
    """C_v of three rates whose E_v sit at 120°, 240°, 330° (zeroed at 0°) with small means'
    u (0.005″): the table's calibration (u 0.05″ per position) dominates the range's errors."""
    x = [0.0, 120.0, 240.0, 330.0]
    cal = TableCalibration(x, [0.0] * 4, [0.05] * 4, "tc.csv",
                           dof=None if dof is None else [dof] * 4)
    cs = [ConditionDeviation("10", 0.30, 120.0, 0.005, 4),
          ConditionDeviation("30", -0.10, 240.0, 0.005, 4),
          ConditionDeviation("60", 0.05, 330.0, 0.005, 4)]
    return consistency_corrected_budget("rate_consistency", cs, 1296000.0, 1e6,
                                        table_mpe_arcsec=0.1, drift_half_width_arcsec=0.0,
                                        k=2.0, table_cal=CalibratedTable(cal), draws=draws)


def test_small_nu_widens_the_range_interval():
    """The same C_v with the calibration's ν = ∞, 30, 5 and 3: the belt's 95 % interval
    never narrows as ν falls (the t's tails reach beyond the normal's; common random numbers,
    so the steps are the t's, not a reshuffling of the other draws), ν = 30 is close to ∞,
    ν = 3 clearly wider; the source of the range's line says the errors were drawn as t."""
    nus = [None, 30.0, 5.0, 3.0]
    b = [_consistency(nu) for nu in nus]
    w = [x.interval[1] - x.interval[0] for x in b]
    assert all(later >= earlier for earlier, later in zip(w, w[1:])), w
    assert w[3] > 1.3 * w[0]
    assert abs(w[1] / w[0] - 1.0) < 0.1
    assert b[3].interval[1] > b[0].interval[1]
    src = b[3].components[0].source
    assert "t with the calibration's" in src and "t with" not in b[0].components[0].source


@pytest.mark.parametrize("nu", [2.0, 1.0, 2.9])
def test_dof_below_three_refused(tmp_path, nu):
    """ν < 3 (a t with no variance: the Monte Carlo's means and spreads would be noise) is
    refused in one line, by the file's check (its line and column) and by the draws (a
    calibration built otherwise, an equal-division comparison's)."""
    from gonio.errors import GonioError
    from gonio.specs.ogam_draft.table_calibration import read_table_calibration

    f = tmp_path / "tc.csv"
    f.write_text(f"table_deg,error_arcsec,u_arcsec,dof\n0,0.0,0.03,5\n60,0.1,0.03,{nu:g}\n",
                 encoding="utf-8")
    with pytest.raises(GonioError) as e:
        read_table_calibration(f)
    msg = str(e.value)
    assert "tc.csv:3: column dof" in msg and "dof must be >= 3" in msg and "\n" not in msg
    cal = TableCalibration([0.0, 60.0], [0.0] * 2, [0.03] * 2, "eda", dof=[5.0, nu])
    with pytest.raises(GonioError, match="dof must be >= 3"):
        calibration_error_draws(cal, np.random.default_rng(1), 10)
    joint = TableCalibration([0.0, 60.0], [0.0] * 2, [0.03] * 2, "eda",
                             cov_arcsec2=np.diag([9e-4, 9e-4]), dof=[nu, nu])
    with pytest.raises(GonioError, match="dof must be >= 3"):
        calibration_error_draws(joint, np.random.default_rng(1), 10)


def test_t_drawn_from_the_normal_draws():
    """Independent positions: the t draws are the normal draws' z carried to t_ν by their
    quantile (the generator advances as for the normal draws), so |δe| is at least the normal
    draw's and rises as ν falls, draw by draw; the quantile is SciPy's t at Φ(z)."""
    u = np.array([0.02, 0.03])
    cal = {nu: TableCalibration([0, 60], [0, 0], u, "t", dof=None if nu is None else [nu] * 2)
           for nu in (None, 30.0, 5.0, 3.0)}
    rngs = {nu: np.random.default_rng(11) for nu in cal}
    d = {nu: calibration_error_draws(c, rngs[nu], 500) for nu, c in cal.items()}
    for a, b in ((None, 30.0), (30.0, 5.0), (5.0, 3.0)):
        assert np.all(np.abs(d[b]) >= np.abs(d[a])) and np.all(np.sign(d[b]) == np.sign(d[a]))
    want = stats.t.ppf(stats.norm.cdf(d[None] / u), 5.0) * u
    assert np.allclose(d[5.0], want, rtol=1e-9, atol=1e-12)
    assert np.array_equal(rngs[None].standard_normal(5), rngs[3.0].standard_normal(5))


def test_every_range_draw_goes_through_the_one_function(monkeypatch):
    """K_l's, C_v's and C_g's Monte Carlo take their table draws from
    :func:`calibration_error_draws` alone: replaced by draws ten times as wide, the
    consistency's interval (its range and its choice) widens accordingly."""
    b0 = _consistency(None)
    real = iu.calibration_error_draws
    monkeypatch.setattr(iu, "calibration_error_draws",
                        lambda cal, rng, draws: 10.0 * real(cal, rng, draws))
    b1 = _consistency(None)
    assert b1.interval[1] > 3.0 * b0.interval[1]


def test_study_case_calibration_is_student_t():
    """The ``tablecalpart`` coverage case's calibration (gonio validate --cases tablecalpart)
    is what it claims against the bench's parameters: it lacks 330°, states dof ν = 3, and
    its standardised errors (stated − the bench's true harmonic error)/u over many trials
    have Student's t₃ quantile (3.18 at 97.5 %; the normal's 1.96 would under-cover it), so
    a budget taking u as known would be too narrow and one taking ν covers."""
    from gonio.specs.ogam_draft.bench import load_bench
    from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
    from gonio.specs.ogam_draft.study import (TABLE_CALIBRATION_PART_DOF,
                                              case_table_calibration, draw_type_b,
                                              validation_protocol)

    p = validation_protocol(all_items=True)
    base = load_bench("rlg")
    z = []
    for seed in range(400):
        b = draw_type_b(base, p, seed)
        cal = case_table_calibration("tablecalpart", b, p, seed)
        assert 330.0 not in cal.table_deg and cal.table_deg.size == 11
        assert set(cal.dof.tolist()) == {TABLE_CALIBRATION_PART_DOF}
        true = np.asarray(harmonic_sum_arcsec(cal.table_deg, b.table.positioning_harmonics))
        z.append((cal.error_arcsec - true) / cal.u_arcsec)
    z = np.abs(np.concatenate(z))
    assert np.quantile(z, 0.95) == pytest.approx(stats.t.ppf(0.975, 3.0), rel=0.06)
    assert case_table_calibration("tablecal", b, p, 1).dof is None
    assert case_table_calibration("typeb", b, p, 1) is None
