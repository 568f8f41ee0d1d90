"""Estimators, edf and noise identification of gonio.analysis.noise, each against
something independent: published reference values (NIST SP 1065's 1000-point test
set; Stable32's printed intervals for it), allantools (peer library, test only), a
second algorithm (direct sums vs the correlation expansion), and closed forms."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import allantools
import allantools.ci
import numpy as np
import pytest

from gonio.analysis import noise
from gonio.analysis.noise import edf as edfmod
from gonio.errors import GonioError

DATA = Path(__file__).parent / "data"
ONE_SIGMA = math.erf(1 / math.sqrt(2))


def nbs_1000():
    """The SP 1065 1000-point test frequency data (portable generator, §12.2)."""
    n = [1234567890]
    for _ in range(999):
        n.append((16807 * n[-1]) % 2147483647)
    assert n[1:4] == [395529916, 1209410747, 633705974]  # printed in SP 1065
    return np.array(n, dtype=np.float64) / 2147483647.0


# ------------------------------------------------------------- published values
#: SP 1065 (2008) p. 108 / Riley "The calculation of time domain frequency
#: stability", Table III: deviations of the 1000-point set at τ = 1, 10, 100.
SP1065_1000 = {"adev": [2.922319e-01, 9.159953e-02, 3.241343e-02],
               "mdev": [2.922319e-01, 6.172376e-02, 2.170921e-02],
               "totdev": [2.922319e-01, 9.134743e-02, 3.406530e-02],
               "hdev": [2.943883e-01, 9.581083e-02, 3.237638e-02]}


@pytest.mark.parametrize("kind", sorted(SP1065_1000))
def test_sp1065_1000_point_deviations(kind):
    y = nbs_1000()
    r = noise.allan_deviation(y, 1.0, "rate", [1, 10, 100], kind=kind, alpha=0)
    np.testing.assert_allclose(r.adev, SP1065_1000[kind], rtol=2e-6)


def _stable32_rows():
    with open(DATA / "stable32_phase_dat.csv") as fh:
        rows = [r for r in csv.reader(line for line in fh if not line.startswith("#"))]
    head = rows[0]
    return [dict(zip(head, r)) for r in rows[1:]]


@pytest.mark.parametrize("kind", ["adev", "mdev", "hdev", "totdev"])
def test_stable32_intervals_on_the_1000_point_set(kind):
    """Deviation, number of terms and the 68.3 % interval (α = 0) as Stable32 prints
    them: the interval follows from Greenhall's edf (SP 1065 Table 7 for totdev)."""
    rows = [r for r in _stable32_rows() if r["kind"] == kind]
    ms = [int(r["m"]) for r in rows]
    r = noise.allan_deviation(nbs_1000(), 1.0, "rate", ms, kind=kind, alpha=0,
                              confidence=ONE_SIGMA)
    ref = {k: np.array([float(x[k]) for x in rows]) for k in ("dev", "dev_min", "dev_max")}
    assert r.n_pairs.tolist() == [int(x["n"]) for x in rows]
    np.testing.assert_allclose(r.adev, ref["dev"], rtol=6e-5)
    np.testing.assert_allclose(r.ci_low, ref["dev_min"], rtol=4e-4)
    np.testing.assert_allclose(r.ci_high, ref["dev_max"], rtol=4e-4)


def test_mdev_interval_at_large_m_uses_its_own_edf():
    """Issue 15: at m = 128 the MDEV edf is 5.3 (the ADEV one is 9.6)."""
    e_mod = noise.edf_for("mdev", 1001, [128], [0])[0]
    e_adev = noise.edf_for("adev", 1001, [128], [0])[0]
    assert e_mod == pytest.approx(5.32, abs=0.01) and e_adev == pytest.approx(9.55, abs=0.01)


# ------------------------------------------------------------- Greenhall's edf
def _allantools_edf(alpha, d, m, n, modified):
    try:
        return allantools.ci.edf_greenhall(alpha, d, m, n, overlapping=True,
                                           modified=modified)
    except (NotImplementedError, AssertionError):
        return None  # allantools lacks case 4 with r <= d, and Table 2 for alpha = -4


@pytest.mark.parametrize("d, modified", [(2, False), (2, True), (3, False)])
def test_edf_greenhall_matches_allantools_on_a_grid(d, modified):
    checked = 0
    for alpha in range(2, -5, -1):
        if alpha + 2 * d <= 1:
            continue
        for n in (64, 257, 1001, 10_000, 1_000_003):
            length = (lambda m: m + m * d) if modified else (lambda m: 1 + m * d)
            ms = [m for m in (1, 2, 3, 4, 7, 8, 16, 25, 33, 34, 50, 64, 100, 128, 333, 1000,
                              4096, 30_000, 200_000) if n - length(m) >= 0]
            ours = noise.edf_greenhall(alpha, d, ms, n, modified=modified)
            for m, o in zip(ms, ours):
                ref = _allantools_edf(alpha, d, m, n, modified)
                if ref is None:
                    continue
                assert o == pytest.approx(ref, rel=1e-6), (alpha, n, m)
                checked += 1
    assert checked > 200


def test_edf_white_phase_closed_form_for_few_terms():
    """Case 4 (α = +2, unmodified) where allantools has no formula (r ≤ d): the basic
    sum, evaluated term by term from [GR2003] eq. (10), equals the closed form."""
    for d in (2, 3):
        for m, n in ((10, 1 + d * 10 + 5), (10, 1 + d * 10 + 12), (40, 1 + d * 40 + 30),
                     (10, 1 + d * 10 + 50)):
            e = noise.edf_greenhall(2, d, [m], n)[0]
            length = 1 + m * d
            big_m = 1 + math.floor(m * (n - length) / m)
            j = min(big_m, (d + 1) * m)
            s = edfmod._basic_sum(np.array([j]), np.array([big_m]), np.array([m]),
                                  np.array([m]), 2, d)[0]
            inv = s / (edfmod._sz(0.0, float(m), 2, d) ** 2 * big_m)
            assert e == pytest.approx(1 / inv, rel=1e-9)


@pytest.mark.parametrize("alpha, d, table", [
    (0, 2, "2"), (-1, 2, "2"), (-2, 2, "2"), (-1, 3, "2"), (-2, 3, "2"), (-3, 3, "2"),
    (0, 2, "1"), (-1, 2, "1"), (-2, 2, "1"), (2, 2, "1"), (-4, 3, "1")])
def test_greenhall_table_coefficients_from_the_basic_sum(alpha, d, table):
    """The transcribed (a0, a1) of [GR2003] Tables 1 and 2 are the large-r behaviour of
    the exact basic sum: r/edf = a0 − a1/r, fitted here at r = 20 and 40 (F = 1 for
    Table 1, F = ∞ for Table 2, S large)."""
    s = 300.0
    f = 1.0 if table == "1" else None
    vals = []
    for r in (20.0, 40.0):
        big_m = r * s
        j = (d + 1) * s
        bs = edfmod._basic_sum(np.array([j]), np.array([big_m]), np.array([s]),
                               None if f is None else np.array([f]), alpha, d)[0]
        vals.append(bs / (edfmod._sz(0.0, f, alpha, d) ** 2 * big_m) * r)
    a1 = (vals[1] - vals[0]) / (1 / 20 - 1 / 40)
    a0 = vals[1] + a1 / 40
    tab = edfmod.GR_TABLE1 if table == "1" else edfmod.GR_TABLE2
    t0, t1 = tab[alpha][d - 1]
    assert a0 == pytest.approx(t0, abs=0.006) and a1 == pytest.approx(t1, abs=0.02)


def test_edf_of_all_taus_capped_branch_interpolation():
    """With more than 512 estimates the capped branch is interpolated (``all`` τ):
    within 2e-5 of the exact evaluation, flicker phase noise (α = 1) included since the
    grid holds the kinks of the sum (issue 26)."""
    for kind in ("adev", "mdev", "hdev"):
        ms = noise.averaging_factors(6001, "all", kind=kind)
        for a in (1, 0, -1, -2):
            fast = noise.edf_for(kind, 6001, ms, np.full(ms.size, a))
            edfmod._CAPPED_EXACT, keep = 10 ** 9, edfmod._CAPPED_EXACT
            try:
                exact = noise.edf_for(kind, 6001, ms, np.full(ms.size, a))
            finally:
                edfmod._CAPPED_EXACT = keep
            np.testing.assert_allclose(fast, exact, rtol=2e-5)


def test_totdev_edf_is_sp1065_table7():
    # b·N/m − c with (b, c) of SP 1065 Table 7
    assert noise.edf_totdev(1001, [10], [0])[0] == pytest.approx(1.5 * 100.1)
    assert noise.edf_totdev(1001, [10], [-1])[0] == pytest.approx(1.17 * 100.1 - 0.22)
    assert noise.edf_totdev(1001, [10], [-2])[0] == pytest.approx(0.93 * 100.1 - 0.36)


def test_chi2_interval_coverage_mdev_white_noise():
    """68.3 % intervals of MDEV with the Greenhall edf cover the truth ≈ 68 % of the time,
    also at large m where the ADEV edf would be far too large."""
    rng = np.random.default_rng(5)
    hits = np.zeros(3)
    trials = 300
    for _ in range(trials):
        y = rng.standard_normal(1024)
        r = noise.allan_deviation(y, 1.0, "rate", [1, 16, 128], kind="mdev", alpha=0)
        m = r.m.astype(float)
        truth = np.sqrt((m ** 2 + 1) / (2 * m ** 3))  # exact MVAR of white rate noise
        hits += (r.ci_low <= truth) & (truth <= r.ci_high)
    cover = hits / trials
    assert np.all(np.abs(cover - 0.683) < 0.07), cover


# -------------------------------------------------------- noise identification
def _powerlaw_phase(rng, n, alpha):
    """Phase with rate PSD ∝ f^alpha (FFT synthesis), for noise-id tests."""
    f = np.fft.rfftfreq(4 * n)
    spec = rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)
    spec[0] = 0
    spec[1:] *= f[1:] ** ((alpha - 2) / 2.0)  # phase PSD ∝ f^(alpha-2)
    return np.fft.irfft(spec)[:n]


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
def test_lag1_noise_id_recognises_each_type_and_matches_allantools(alpha):
    rng = np.random.default_rng(10 + alpha)
    x = _powerlaw_phase(rng, 1 << 15, alpha)
    assert noise.noise_id_lag1(x, 4)[0] == alpha
    for m in (1, 4, 16):
        for d_max in (2, 3):
            ours = noise.noise_id_lag1(x, m, d_max=d_max)
            ref = allantools.ci.autocorr_noise_id(x, m, data_type="phase", dmax=d_max)
            assert ours[0] == ref[0] and ours[1] == pytest.approx(ref[1], abs=1e-9)


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
def test_b1_rn_noise_id_cross_check(alpha):
    rng = np.random.default_rng(20 + alpha)
    x = _powerlaw_phase(rng, 1 << 15, alpha)
    assert noise.noise_id_b1(x, 8) == alpha


def test_b1_expected_is_the_barnes_ratio():
    # white FM (μ = −1): B1 = 1; random walk FM (μ = 1): N/2; flicker FM (μ = 0): N ln N/(2(N−1) ln 2)
    assert edfmod.b1_expected(50, -1) == pytest.approx(1.0)
    assert edfmod.b1_expected(50, 1) == pytest.approx(25.0)
    assert edfmod.b1_expected(50, 0) == pytest.approx(50 * math.log(50) / (2 * 49 * math.log(2)))


def test_identified_types_reported_and_used():
    rng = np.random.default_rng(3)
    y = rng.standard_normal(200_000) + 0.02 * np.cumsum(rng.standard_normal(200_000))
    r = noise.allan_deviation(y, 0.01, "rate", "octave")
    assert r.alpha[0] == 0 and r.alpha[-3] == -2
    np.testing.assert_allclose(r.edf, noise.edf_for("adev", r.n_phase, r.m, r.alpha))
    # on pure noise the B1/R(n) cross-check agrees with the lag-1 identification
    for alpha, y in ((0, rng.standard_normal(100_000)),
                     (-2, np.cumsum(rng.standard_normal(100_000)))):
        r = noise.allan_deviation(y, 1.0, "rate", "octave")
        ok = np.isfinite(r.alpha_b1) & (r.m <= y.size / 64)  # ≥ 64 averages for B1
        assert ok.sum() >= 8
        assert np.all(r.alpha_b1[ok] == alpha) and np.all(r.alpha[ok] == alpha)


# -------------------------------------------------------------- vs allantools
@pytest.mark.parametrize("kind, fn", [("adev", allantools.oadev), ("mdev", allantools.mdev),
                                      ("hdev", allantools.ohdev),
                                      ("totdev", allantools.totdev)])
def test_estimators_match_allantools(kind, fn):
    rng = np.random.default_rng(1)
    y = 100 + rng.standard_normal(30_000) + 0.01 * np.cumsum(rng.standard_normal(30_000))
    r = noise.allan_deviation(y, 0.01, "rate", "decade:4", kind=kind, alpha=0)
    _, dev, _, _ = fn(y, rate=100, data_type="freq", taus=r.tau_s)
    np.testing.assert_allclose(r.adev[: dev.size], dev, rtol=1e-9)
    xa = np.cumsum(np.r_[0.0, y]) * 0.01
    ra = noise.allan_deviation(xa, 0.01, "angle", "decade:4", kind=kind, alpha=0)
    np.testing.assert_allclose(ra.adev[: dev.size], dev, rtol=1e-8)


@pytest.mark.parametrize("kind, fn", [("adev", allantools.oadev), ("hdev", allantools.ohdev)])
def test_octave_sums_match_allantools_to_1e12(kind, fn):
    """The chunked sums of squares (BLAS dot products of pieces, a summation order of their
    own) on a record of 600 000 points, octave τ up to beyond a chunk (2¹⁷ points): equal to
    allantools' whole-array sums to 1e-12 on a zero-mean record (where the peer's own
    cumulative sum loses nothing)."""
    rng = np.random.default_rng(7)
    y = rng.standard_normal(600_000) + 1e-3 * np.cumsum(rng.standard_normal(600_000))
    y -= y.mean()
    r = noise.allan_deviation(y, 0.01, "rate", "octave", kind=kind, alpha=0)
    assert r.m.max() > 1 << 16
    _, dev, _, _ = fn(y, rate=100, data_type="freq", taus=r.tau_s)
    np.testing.assert_allclose(r.adev[: dev.size], dev, rtol=1e-12)


def _exact_sums(x, ms, coef):
    """Σ_n (Σ_j coef[j]·x[n + j·m])² with each term from differences of the phase (ADEV:
    (x[n+2m] − x[n+m]) − (x[n+m] − x[n]); HDEV: the third difference likewise) and the
    squares summed exactly rounded (math.fsum): a second algorithm for the sums."""
    out = []
    for m in ms:
        d = x[m:] - x[:-m]
        d = d[m:] - d[:-m]
        if len(coef) == 4:
            d = -(d[m:] - d[:-m])
        out.append(math.fsum((d * d).tolist()))
    return np.array(out)


@pytest.mark.parametrize("order", [2, 3])
def test_matrix_product_sums_against_exact_sums_and_allantools(monkeypatch, order):
    """The in-memory sums by BLAS matrix products (band matrix × rows of the phase), with
    products of 2¹² terms so that m up to beyond a product, the leftover rows and a last
    partial row longer than a product all occur: equal to the exactly rounded sums of the
    differences' squares within the stated bound, and to allantools to 1e-12; the products
    path is used."""
    from gonio.analysis.noise import allan
    monkeypatch.setattr(allan, "_PRODUCT_BLOCK", 1 << 12)
    monkeypatch.setattr(allan, "_PRODUCT_MIN_N", 0)
    used = []
    orig = allan._sum_sq_products
    monkeypatch.setattr(allan, "_sum_sq_products",
                        lambda x, m, c, b: used.append(m) or orig(x, m, c, b))
    y = np.random.default_rng(11).standard_normal(100_003)
    y -= y.mean()
    x = np.r_[0.0, np.cumsum(y)]
    ms = [16, 17, 63, 64, 100, 999, 1024, 5000, 12_345, 30_000, 33_333 - order]
    coef = allan._COEF["adev" if order == 2 else "hdev"]
    got = allan._sums_by_products(x, ms, order)
    assert used == ms
    np.testing.assert_allclose(got, _exact_sums(x, ms, coef), rtol=allan.PRODUCT_RTOL, atol=0)
    kind, fn = ("adev", allantools.oadev) if order == 2 else ("hdev", allantools.ohdev)
    r = noise.allan_deviation(y, 0.01, "rate", ms, kind=kind, alpha=0)
    _, dev, _, _ = fn(y, rate=100, data_type="freq", taus=r.tau_s)
    np.testing.assert_allclose(r.adev, dev, rtol=1e-12, atol=0)


def test_matrix_product_sums_refused_where_the_phase_dwarfs_its_differences(monkeypatch):
    """Rate random walk: the phase is far larger than its second differences at short τ,
    and the bound of the products' rounding exceeds PRODUCT_RTOL there: those m are summed
    by differences (the same bytes as the differences path), the longer ones by products;
    every m within the bound of the exact sums."""
    from gonio.analysis.noise import allan
    monkeypatch.setattr(allan, "_PRODUCT_MIN_N", 0)
    rng = np.random.default_rng(4)
    y = 0.05 * np.cumsum(rng.standard_normal(200_000)) + rng.standard_normal(200_000)
    y -= y.mean()
    x = np.r_[0.0, np.cumsum(y)]
    ms = [16, 64, 256, 4096, 32_768]
    got = allan._sums_by_products(x, ms)
    diff = allan._sums_direct_shared(x, ms)
    top = np.max(np.abs(x))
    delta = 1.01 * 4 * 2.0 ** -53 * top            # ADEV: the one partial sum a − 2b
    length = x.size - 2 * np.array(ms)
    r = delta * np.sqrt(length / diff)
    refused = 2 * r + r * r + 3 * 2.0 ** -53 > allan.PRODUCT_RTOL
    assert refused[0] and not refused[-1]
    assert np.array_equal(got[refused], diff[refused])
    np.testing.assert_allclose(got, _exact_sums(x, ms, allan._COEF["adev"]),
                               rtol=allan.PRODUCT_RTOL, atol=0)


def test_matrix_product_sums_same_bytes_whatever_the_blas_threads():
    """One BLAS thread inside: the sums are the same bytes whether the caller allows one
    thread or two, and on a repeated run."""
    from threadpoolctl import threadpool_limits

    from gonio.analysis.noise import allan
    y = np.random.default_rng(5).standard_normal(300_000)
    with threadpool_limits(limits=2):
        a = noise.allan_deviation(y, 0.01, "rate", "octave", kind="hdev")
    with threadpool_limits(limits=1):
        b = noise.allan_deviation(y, 0.01, "rate", "octave", kind="hdev")
    c = noise.allan_deviation(y, 0.01, "rate", "octave", kind="hdev")
    assert a.adev.tobytes() == b.adev.tobytes() == c.adev.tobytes()
    assert (a.m >= allan._PRODUCT_MIN_M).sum() >= 10


@pytest.mark.parametrize("kind", ["adev", "mdev", "hdev"])
def test_all_taus_expansion_matches_direct_sums(kind):
    rng = np.random.default_rng(3)
    n = 40_000
    y = rng.standard_normal(n) + 0.01 * np.cumsum(rng.standard_normal(n))
    r = noise.allan_deviation(y, 1.0, "rate", "all", kind=kind, alpha=0)
    assert r.m.size == (n // (2 if kind == "adev" else 3))
    pick = np.unique(np.r_[1, 2, 3, 50, 777, rng.integers(1, r.m[-1], 40), r.m[-5:]])
    direct = noise.allan_deviation(y, 1.0, "rate", pick, kind=kind, alpha=0)
    np.testing.assert_allclose(r.adev[pick - 1], direct.adev, rtol=2e-6)


def test_wedge_correlation_against_its_definition():
    from gonio.analysis.noise.allan import _wedge_corr
    rng = np.random.default_rng(0)
    z = rng.standard_normal(700)
    for s, c in ((1, 1), (1, 2), (2, 1)):
        w = _wedge_corr(z, 200, s, c)
        for m in (0, 1, 7, 8, 9, 63, 64, 65, 150, 200):
            ref = sum(z[n] * z[n + c * m] for n in range(s * m) if n + c * m < z.size)
            assert w[m] == pytest.approx(ref, abs=1e-9), (s, c, m)


# ----------------------------------------------------------------------- gaps
def test_gaps_are_skipped_not_interpolated_and_counted():
    rng = np.random.default_rng(4)
    y = rng.standard_normal(5000)
    yg = y.copy()
    yg[1000:1010] = np.nan
    yg[3000] = np.nan
    r = noise.allan_deviation(yg, 1.0, "rate", [1, 4, 16], alpha=0)
    # each term spans 2m samples; a term is valid when none of them is NaN
    for m, got_n, got_dev in zip(r.m, r.n_pairs, r.adev):
        m = int(m)
        terms = []
        for k in range(5000 - 2 * m + 1):
            a, b = yg[k: k + m], yg[k + m: k + 2 * m]
            if np.isfinite(a).all() and np.isfinite(b).all():
                terms.append(b.mean() - a.mean())
        terms = np.array(terms)
        assert got_n == terms.size
        assert got_dev == pytest.approx(math.sqrt(0.5 * np.mean(terms ** 2)), rel=1e-10)
    assert r.n_gaps == 11


def test_gap_resistant_adev_matches_allantools_gradev():
    rng = np.random.default_rng(6)
    x = np.cumsum(rng.standard_normal(4000))
    x[500:520] = np.nan
    x[2222] = np.nan
    r = noise.allan_deviation(x, 1.0, "angle", [1, 2, 4, 8, 16, 32], alpha=0)
    _, dev, _, _ = allantools.gradev(x, rate=1.0, data_type="phase", taus=r.tau_s)
    # allantools does not remove the line through the end points; a ramp of x is
    # cancelled by the second difference anyway
    np.testing.assert_allclose(r.adev, dev, rtol=1e-9)


def test_gaps_in_modified_and_hadamard():
    rng = np.random.default_rng(7)
    y = rng.standard_normal(3000)
    y[700] = np.nan
    for kind in ("mdev", "hdev"):
        r = noise.allan_deviation(y, 1.0, "rate", [1, 5], kind=kind, alpha=0)
        gap_free = noise.allan_deviation(y[701:], 1.0, "rate", [1, 5], kind=kind, alpha=0)
        # fewer valid terms than the two pieces' total spans, same statistic size
        assert np.all(r.n_pairs < 3000) and np.all(r.n_pairs > gap_free.n_pairs)
        np.testing.assert_allclose(r.adev, gap_free.adev, rtol=0.1)
    with pytest.raises(GonioError, match="gap-free"):
        noise.allan_deviation(y, 1.0, "rate", [1], kind="totdev")


def test_infinite_values_rejected_with_index():
    with pytest.raises(GonioError, match="index 3"):
        noise.allan_deviation([1.0, 2.0, 3.0, np.inf, 1.0], 1.0, "rate")


@pytest.mark.parametrize("kind", ["adev", "mdev", "hdev"])
def test_overwrite_data_detrends_in_place_with_the_same_result(kind):
    # overwrite_data=True reuses an angle record's memory (the bootstrap's records); the
    # deviation must be the one of the copying path, bit for bit, and only then is the
    # caller's array changed. Checked against allantools too (independent).
    rng = np.random.default_rng(4)
    x = np.cumsum(rng.standard_normal(200_001)) * 0.01 + np.arange(200_001) * 3e-4
    ref_in = x.copy()
    a = noise.allan_deviation(x, 0.01, "angle", kind=kind, alpha=0)
    assert np.array_equal(x, ref_in)                            # not overwritten
    y = x.copy()
    b = noise.allan_deviation(y, 0.01, "angle", kind=kind, alpha=0, overwrite_data=True)
    assert np.array_equal(a.adev, b.adev)
    assert not np.array_equal(y, ref_in)                        # detrended in place
    peer = {"adev": allantools.oadev, "mdev": allantools.mdev, "hdev": allantools.ohdev}[kind]
    _, dev, _, _ = peer(x - np.linspace(x[0], x[-1], x.size), rate=100.0, data_type="phase",
                        taus=a.tau_s)
    np.testing.assert_allclose(b.adev, dev, rtol=1e-9)


def test_all_tau_edf_capped_grid_is_built_once_whatever_the_noise_type(monkeypatch):
    """issue 26: the all-τ ADEV took 2 s on some white-noise records of 10⁶ samples and
    14 s on others. The cause: the capped branch of Greenhall's edf rebuilt its grid for
    every chunk of 16 384 τ, and whether that branch ran at all depended on the noise type
    identified at the largest τ (by chance: α = 2 has a closed form, α = 1 or ≤ 0 not).
    The grid is now built once per branch, α and d (per record length): at most one
    grid evaluation per noise type, however many chunks of τ and whatever the data."""
    grids = []
    real = edfmod._basic_sum

    def counting(j_lim, *a, **k):
        if np.size(j_lim) > 512:
            grids.append(np.size(j_lim))
        return real(j_lim, *a, **k)

    monkeypatch.setattr(edfmod, "_basic_sum", counting)
    monkeypatch.setattr(edfmod, "_CAPPED_CACHE", {})
    x = np.random.default_rng(3).standard_normal(80_000)
    for alpha in (1, 0):
        r = noise.allan_deviation(x, 1.0, "rate", "all", alpha=alpha)
        assert r.m.size > 2 * 16_384          # several chunks of τ
    assert len(grids) == 2, grids             # one grid per noise type, not one per chunk
    noise.allan_deviation(x, 1.0, "rate", "all", alpha=1)
    assert len(grids) == 2                    # and kept for the next record of this length
