"""Allan confidence intervals at long τ, where few clusters remain: the noise type for the edf
is taken from where enough decimated points identify it (``ID_RELIABLE_POINTS``), never from a
few dozen points (on white rate noise the lag-1 method then called 26 % of the records
flicker or white phase, and the edf grew 2× to 10⁴×).

Checked against what does not come from gonio: the true Allan variance of white rate noise
(σ²·τ0/τ, closed form), and allantools' Greenhall edf for white FM (α = 0) and its χ²
interval. Coverage of the 95 % interval is counted at the longest τ each procedure uses:
the octave τ ≥ 4096 samples of a 2¹⁷-sample record (≤ 32 clusters) and the longest τ of the
rate specifications' ``decade:10`` set on a record of the JJF static record's length.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import beta

from gonio.analysis.noise.allan import ID_RELIABLE_POINTS, allan_deviation

allantools = pytest.importorskip("allantools", reason="pip install '.[test]'")

#: Records per case: enough that a coverage of 95 % is told from one of 80 % (Clopper–Pearson).
RECORDS = 80


def white_rate(rng, n: int, sigma: float = 1.0) -> np.ndarray:
    return sigma * rng.standard_normal(n)


def clopper_pearson(x: int, n: int) -> tuple[float, float]:
    lo = beta.ppf(0.025, x, n - x + 1) if x > 0 else 0.0
    hi = beta.ppf(0.975, x + 1, n - x) if x < n else 1.0
    return float(lo), float(hi)


@pytest.mark.parametrize("n, taus, m_min", [(1 << 17, "octave", 4096),
                                             (72000, "decade:10", None)],
                         ids=["2^17-octave-long", "jjf-static-decade10-longest"])
def test_long_tau_intervals_cover_white_rate_noise(n, taus, m_min):
    rng = np.random.default_rng(20261129)
    hits, edf_off, total = 0, 0, 0
    for _ in range(RECORDS):
        r = allan_deviation(white_rate(rng, n), 1.0, "rate", taus, confidence=0.95)
        sel = r.m >= m_min if m_min else r.m == r.m.max()
        for m, lo, hi, edf in zip(r.m[sel], r.ci_low[sel], r.ci_high[sel], r.edf[sel]):
            truth = 1.0 / float(m)                    # σ²τ0/τ, white rate noise, σ = τ0 = 1
            hits += lo ** 2 <= truth <= hi ** 2
            ref = allantools.edf_greenhall(alpha=0, d=2, m=int(m), N=r.n_phase,
                                           overlapping=True, modified=False)
            edf_off += not (0.5 * ref <= edf <= 1.0001 * ref)   # never above white FM's
            total += 1
    lo, hi = clopper_pearson(hits, total)
    assert hi >= 0.95 and lo >= 0.85, (hits, total, lo, hi)
    assert edf_off == 0, f"{edf_off} of {total} edf above allantools' white-FM edf"


def test_identification_reliable_where_points_allow():
    """Where at least ID_RELIABLE_POINTS decimated points remain the type is identified there
    (white rate noise: α = 0 on every record); an interval at a long τ is allantools' χ² interval
    at the carried type."""
    rng = np.random.default_rng(7)
    n = 1 << 17
    for _ in range(10):
        r = allan_deviation(white_rate(rng, n), 1.0, "rate", "octave", confidence=0.95)
        enough = (r.n_phase - 1) // r.m >= ID_RELIABLE_POINTS
        assert np.all(r.alpha[enough] == 0)
        assert np.all(r.alpha[~enough] <= 0)
        i = int(np.argmax(r.m))
        lo, hi = allantools.confidence_interval(float(r.adev[i]), float(r.edf[i]), ci=0.95)
        assert np.isclose(lo, r.ci_low[i], rtol=1e-9) and np.isclose(hi, r.ci_high[i], rtol=1e-9)


def test_a_change_of_type_at_long_tau_is_kept():
    """Random-walk rate noise growing at long τ: the identified lower α (a smaller edf: wider
    intervals) is kept where it is seen, not replaced by the white type carried from short τ."""
    rng = np.random.default_rng(3)
    n = 1 << 17
    low = 0
    for _ in range(10):
        rate = rng.standard_normal(n) + np.cumsum(rng.standard_normal(n)) * 0.05
        r = allan_deviation(rate, 1.0, "rate", "octave")
        low += int(r.alpha[-1] < 0)
    assert low >= 8
