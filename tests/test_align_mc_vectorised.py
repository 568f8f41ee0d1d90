"""``gonio align --monte-carlo`` vectorised in bounded chunks (issue 26): the same trials
as one trial after the other — same draws from the seed, each refitted by weighted least
squares on its own — so the standard deviations equal those of a plain per-trial loop
written here (numpy.linalg.lstsq per channel, the module's derived quantities per trial;
to ~1e-12 relative, the solves' rounding), and chunk boundaries (Chan's combination) do
not change the figures beyond rounding."""

from __future__ import annotations

import numpy as np
import pytest

from gonio.specs.triad_alignment.bench import load_triad_bench, load_triad_protocol, run_alignment_session
from gonio.specs.triad_alignment.readings import format_triad_readings, parse_triad_readings
from gonio.physics.alignment import decompose_system_matrix
from gonio.specs.triad_alignment import analysis as an


@pytest.fixture(scope="module")
def readings():
    s = run_alignment_session(load_triad_protocol("triad-alignment"),
                              load_triad_bench("mems-triad"), 2)
    return parse_triad_readings(format_triad_readings(s.readings, s.metadata), "r.csv")


def derived_one(t):
    """The derived vector of one θ, written out (independent of the batch code)."""
    mb = t.reshape(3, 4)
    m, b = mb[:, :3], mb[:, 3]
    minv = np.linalg.inv(m)
    d = decompose_system_matrix(m)
    phi, s = np.array(d["phi_rad"]), np.array(d["cross_axis"])
    off = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]
    return np.concatenate([minv.ravel(), d["scale"], d["psi_rad"], [phi[i, j] for i, j in off],
                           [s[i, j] for i, j in off], minv @ b])


def loop_reference(readings, n, seed, sigma_components):
    """The per-trial Monte Carlo as before the change (one draw, three fits per trial), with
    the estimate's noise model: white σ_w/√w per dwell plus one N(0, σ_B²) offset per block
    (each orientation's rotating dwells, each static dwell), drawn after the dwells."""
    rows = readings.rows("alignment")
    x = np.column_stack([an.dwell_regressors(rows, readings.latitude_deg), np.ones(len(rows))])
    w = rows["n_samples"].to_numpy(float)
    w = w / w.max()
    mbs = []
    for c in an.OUT:
        th, _, _, _, _ = an._fit_channel(x, rows[c].to_numpy(float), w, False)
        mbs.append(th)
    fitted = x @ np.array(mbs).T
    sd = np.asarray(sigma_components)[:, 0][None, :] / np.sqrt(w)[:, None]
    sd_b = np.asarray(sigma_components)[:, 1]
    rot = rows["rate_dps"].to_numpy() != 0
    ups = list(dict.fromkeys(rows["up"][rot]))
    block = [ups.index(u) if r else None for u, r in zip(rows["up"], rot)]
    nxt = len(ups)
    for k, b in enumerate(block):
        if b is None:
            block[k], nxt = nxt, nxt + 1
    zb = np.zeros((len(rows), nxt))
    zb[np.arange(len(rows)), block] = 1.0
    assert np.any(sd_b > 0)                 # the packaged bench's bias wander is seen
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 1801]))
    sw = np.sqrt(w)
    T, D = [], []
    for _ in range(n):
        g = rng.standard_normal((len(rows) + nxt, 3))
        ys = fitted + sd * g[:len(rows)] + zb @ (sd_b[None, :] * g[len(rows):])
        t = np.concatenate([np.linalg.lstsq(x * sw[:, None], ys[:, i] * sw, rcond=None)[0]
                            for i in range(3)])
        T.append(t)
        D.append(derived_one(t))
    return np.std(T, axis=0, ddof=1), np.std(D, axis=0, ddof=1)


def test_vectorised_trials_equal_the_loop(readings):
    res = an.estimate_alignment(readings, monte_carlo=3000, seed=11)
    u_t, u_d = loop_reference(readings, 3000, 11, res.sigma_components)
    np.testing.assert_allclose(res.u_mc_theta, u_t, rtol=1e-10)
    for k, sl in an._DERIVED_SLICES.items():
        np.testing.assert_allclose(res.u_mc[k], u_d[sl], rtol=1e-10, err_msg=k)


def test_chunks_and_draw_pieces_do_not_change_the_figures(readings, monkeypatch):
    whole = an.estimate_alignment(readings, monte_carlo=2500, seed=4)
    monkeypatch.setattr(an, "MC_CHUNK", 700)          # several Chan combinations
    monkeypatch.setattr(an, "MC_DRAWS", 1000)         # many draw pieces inside a chunk
    monkeypatch.setattr(an.chunked_std, "__defaults__", (700,))
    parts = an.estimate_alignment(readings, monte_carlo=2500, seed=4)
    np.testing.assert_allclose(parts.u_mc_theta, whole.u_mc_theta, rtol=1e-11)
    other = an.estimate_alignment(readings, monte_carlo=2500, seed=5)
    assert not np.allclose(other.u_mc_theta, whole.u_mc_theta, rtol=1e-6)   # the seed matters


def test_derived_trials_equal_the_stacked_formulas():
    """The Monte Carlo's element-by-element derived quantities (Cramer's rule, row norms)
    equal the stacked LAPACK inverse and the physics module's decomposition to rounding,
    on matrices far from the identity (misaligned, unequal scale factors, signs)."""
    rng = np.random.default_rng(8)
    th = rng.normal(0.0, 0.3, (500, 12))
    th[:, [0, 5, 10]] += rng.choice([-1.0, 1.0], (500, 3)) * rng.uniform(0.5, 80.0, (500, 3))
    got, ref = an._derived_trials(th), an._derived_batch(th)
    np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-14)
    sl = an._DERIVED_SLICES
    for k in ("scale", "psi_rad", "phi_rad", "cross_axis"):     # no inverse: the same ops
        np.testing.assert_allclose(got[:, sl[k]], ref[:, sl[k]], rtol=1e-15, atol=0)


def test_derived_trials_refuse_singular_and_zero_rows():
    th = np.tile(np.eye(3, 4).ravel(), (4, 1))
    th[2, 4:7] = th[2, 0:3]                       # trial 2: two equal rows, det 0
    with pytest.raises(an.GonioError, match="singular"):
        an._derived_trials(th)
    th[2, 4:7] = 0.0                              # a zero row is singular too
    with pytest.raises(an.GonioError):
        an._derived_trials(th)
