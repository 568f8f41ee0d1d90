"""Tests of gonio.specs.ogam_draft.equal_division (equal-division averaging, IEC 62047-20 Annex A.3).

Independent references used here:
* the truth of the synthetic data, evaluated in this file from the harmonic
  series, and its observable part obtained by an FFT (bins that are multiples
  of n removed) — not by the module's null-space computation;
* for n = m, the classical closed-form averages (column means, closure sums);
* a dense numpy least-squares solve with explicit gauge rows;
* Monte Carlo scatter over 200 seeds for the uncertainties;
* Annex A.3's statement that averaging n shifted copies keeps only orders that
  are multiples of n.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from gonio.cli import main
from gonio.specs.ogam_draft.equal_division import (compare_tables, eda_matrix_from_readings, equal_division_analysis,
                       harmonic_transfer, load_eda_protocol, simulate_eda_matrix)
from gonio.errors import GonioError

import functools  # noqa: E402

# The synthetic matrices of these tests carry independent (white) reading noise: analyse
# them with the white model; the random-walk model (the default, for gyros) is tested on
# the virtual bench in tests/test_eda_bench.py.
_eda_default = equal_division_analysis
equal_division_analysis = functools.partial(_eda_default, noise="white")


# ----------------------------------------------------------------------------- helpers
def _random_harmonics(orders, scale, rng):
    return {int(h): (float(scale * rng.uniform(0.2, 1.0)), float(rng.uniform(0, 2 * np.pi)))
            for h in orders}


def _series(x_deg, harm, zeroed=False):
    """Σ A cos(h x + φ) (minus its value at 0 if zeroed), evaluated here independently."""
    x = np.deg2rad(np.asarray(x_deg, float))
    out = np.zeros_like(x)
    for h, v in harm.items():
        a, ph = v if isinstance(v, tuple) else (v, 0.0)
        out += a * np.cos(h * x + ph)
        if zeroed:
            out -= a * np.cos(ph)
    return out


def _expected(table_h, gonio_h, n, m):
    """Observable truth: table without its DFT bins ≡ 0 mod n; goniometer absorbs them."""
    step = 360.0 / m
    t = _series(np.arange(m) * step, table_h)
    F = np.fft.fft(t)
    hidden = (np.arange(m) % n) == 0                 # includes bin 0 (the gauge constant)
    F_obs = np.where(hidden, 0, F)
    t_obs = np.fft.ifft(F_obs).real
    tau = t - t_obs                                  # period-(m/n) part + constant
    j = np.arange(1, m + 1)
    g = _series(j * step, gonio_h, zeroed=True) - (tau[j % m] - tau[0])
    return t_obs, g


def _readings_frame(D, start_deg, step_deg):
    R, n, m = D.shape
    r, k, j = np.meshgrid(np.arange(R), np.arange(n), np.arange(1, m + 1), indexing="ij")
    table = j.ravel() * step_deg
    return pd.DataFrame({
        "test": "equal_division", "series": r.ravel() + 1, "round": k.ravel() + 1,
        "time_s": j.ravel() * 6.0, "start_deg": np.asarray(start_deg)[k.ravel()],
        "table_deg": table, "gyro_deg": table + D.ravel() / 3600.0})


def _write_csv(path, df):
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# instrument: FOG goniometer\n# serial: 0042\n")
        df.to_csv(fh, index=False, float_format="%.12f")
    return path


CASES = [(8, 8), (8, 24), (12, 12)]


# ----------------------------------------------------------------------------- recovery
@pytest.mark.parametrize("n,m", CASES)
def test_noise_free_recovers_observable_truth_exactly(n, m):
    rng = np.random.default_rng(100 + n + m)
    th = _random_harmonics(range(1, 31), 1.0, rng)
    gh = _random_harmonics(range(1, 31), 0.3, rng)
    sim = simulate_eda_matrix(th, gh, n, m, 1, 0.0, rng)
    res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    t_exp, g_exp = _expected(th, gh, n, m)
    np.testing.assert_allclose(res.table_error_arcsec, t_exp, atol=1e-9)
    np.testing.assert_allclose(res.gonio_error_arcsec, g_exp, atol=1e-9)
    assert res.unobservable_dim == m // n - 1
    assert res.residual_std_arcsec < 1e-9


@pytest.mark.parametrize("n,m", CASES)
def test_noisy_recovery_within_uncertainty_and_harmonic_report(n, m):
    rng = np.random.default_rng(7 * n + m)
    th = _random_harmonics(range(1, 31), 1.0, rng)
    gh = _random_harmonics(range(1, 31), 0.3, rng)
    sim = simulate_eda_matrix(th, gh, n, m, 3, 0.05, rng)
    res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg, max_order=30)
    t_exp, g_exp = _expected(th, gh, n, m)
    zt = (res.table_error_arcsec - t_exp) / res.table_u_arcsec
    zg = (res.gonio_error_arcsec - g_exp) / res.gonio_u_arcsec
    assert np.all(np.abs(zt) < 4.5) and np.all(np.abs(zg) < 4.5)
    # the unobservable part is not small here: the test would fail without removing it
    t_all = _series(np.arange(m) * sim.step_deg, th)
    if m != n:
        assert np.max(np.abs(res.table_error_arcsec - (t_all - t_all.mean()))) > 0.3
    hm = res.harmonics
    assert list(hm.order) == list(range(1, 31))
    mult = hm.order % n == 0
    assert set(hm.table_status[mult]) <= {"unobservable", "invisible"}
    assert set(hm.table_status[~mult]) <= {"observable", "aliased"}
    assert (hm.table_status[hm.order % m == 0] == "invisible").all()
    assert (hm.table_status[(hm.order % n == 0) & (hm.order % m != 0)] == "unobservable").all()
    # Annex A.3: the average of n shifted copies keeps exactly the multiples of n
    np.testing.assert_allclose(hm.eda_mean_transfer, mult.astype(float), atol=1e-12)
    # aliasing on the m-point grid: h > m/2 folds to min(h mod m, m − h mod m)
    alias = np.minimum(hm.order % m, m - hm.order % m)
    assert (hm.table_alias_order == alias).all()
    assert ((hm.table_status == "aliased") == ((alias != hm.order) & ~mult)).all()


def test_n_equals_m_matches_classical_averages():
    sim = simulate_eda_matrix({1: 2.0, 5: (1.0, 0.3), 7: 0.5}, {2: 0.4, 3: (0.2, 1.0)},
                              12, 12, 1, 0.3, 5)
    res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    D = sim.D_arcsec[0]
    m = 12
    g = D.mean(axis=0)                                   # Annex A.3: average over starts
    E = D - g
    fwd = E[:, :m - 1].sum(axis=1) / m                   # runs starting at q
    bwd = -np.array([sum(E[(q - j) % m, j - 1] for j in range(1, m)) for q in range(m)]) / m
    np.testing.assert_allclose(res.gonio_error_arcsec, g, atol=1e-12)
    np.testing.assert_allclose(res.table_error_arcsec, (fwd + bwd) / 2, atol=1e-12)


def test_matches_dense_lstsq_with_explicit_gauge_rows():
    n, m, R = 8, 24, 3
    sim = simulate_eda_matrix({1: 1.0, 8: 0.7, 11: 0.4}, {1: 0.2, 5: 0.1}, n, m, R, 0.1, 11)
    res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    s = m // n
    rows, y = [], []
    for r in range(R):
        for k in range(n):
            p = k * s
            for j in range(1, m + 1):
                a = np.zeros(2 * m)
                a[j - 1] += 1
                a[m + (p + j) % m] -= 1
                a[m + p] += 1
                rows.append(a)
                y.append(sim.D_arcsec[r, k, j - 1])
    A = np.array(rows)
    # gauge: the table sums to zero over each residue class mod m/n
    C = np.zeros((s, 2 * m))
    for q in range(s):
        C[q, m + np.arange(q, m, s)] = 1.0
    theta = np.linalg.lstsq(np.vstack([A, C]), np.concatenate([y, np.zeros(s)]), rcond=None)[0]
    np.testing.assert_allclose(res.gonio_error_arcsec, theta[:m], atol=1e-10)
    np.testing.assert_allclose(res.table_error_arcsec, theta[m:], atol=1e-10)
    rank = np.linalg.matrix_rank(A)
    assert res.dof == A.shape[0] - rank
    rss = np.sum((A @ theta - y) ** 2)
    assert res.residual_std_arcsec == pytest.approx(np.sqrt(rss / res.dof), rel=1e-10)


@pytest.mark.parametrize("n,m,R", [(8, 8, 1), (8, 24, 1), (12, 12, 2)])
def test_uncertainties_consistent_with_scatter_over_seeds(n, m, R):
    th = {1: 2.0, 2: (0.5, 1.0), 9: 0.3, 16: 0.2}
    gh = {1: 0.4, 3: (0.2, 0.5)}
    t_exp, g_exp = _expected(th, gh, n, m)
    zt, zg, est = [], [], []
    for seed in range(200):
        sim = simulate_eda_matrix(th, gh, n, m, R, 0.2, seed)
        res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
        zt.append((res.table_error_arcsec - t_exp) / res.table_u_arcsec)
        zg.append((res.gonio_error_arcsec - g_exp) / res.gonio_u_arcsec)
        est.append(np.concatenate([res.table_error_arcsec, res.gonio_error_arcsec]))
    zt, zg = np.array(zt), np.array(zg)
    assert 0.85 < zt.std() < 1.15
    assert 0.85 < zg.std() < 1.15
    assert abs(zt.mean()) < 0.1 and abs(zg.mean()) < 0.1
    # the reported u (last run) against the empirical spread of the estimates
    emp = np.array(est).std(axis=0, ddof=1)
    rep = np.concatenate([res.table_u_arcsec, res.gonio_u_arcsec])
    np.testing.assert_allclose(rep / emp, 1.0, atol=0.3)


# ----------------------------------------------------------------------------- closure, gauge
def test_closure_detects_goniometer_full_turn_error():
    n = m = 12
    sim = simulate_eda_matrix({1: 1.0, 2: 0.5}, {1: 0.3}, n, m, 2, 0.05, 3)
    res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    assert res.closure.consistent and abs(res.closure.table_sum_arcsec) < 1e-10
    # a scale-factor error of 2e-6 adds 2e-6·φ: 2.592″ after a full turn
    phi = np.arange(1, m + 1) * sim.step_deg
    D = sim.D_arcsec + 2e-6 * phi * 3600.0
    res2 = equal_division_analysis(D, sim.start_deg, sim.step_deg)
    c = res2.closure
    assert not c.consistent and c.z > 10
    assert abs(c.full_turn_arcsec - 2e-6 * 360 * 3600) < 4 * c.u_full_turn_arcsec
    np.testing.assert_allclose(c.per_start_full_turn_arcsec, D[:, :, -1].mean(axis=0))
    # the table is untouched by a goniometer error (it only changes g)
    np.testing.assert_allclose(res2.table_error_arcsec, res.table_error_arcsec, atol=1e-10)


def test_zero_gauge_differs_by_a_constant():
    sim = simulate_eda_matrix({1: 1.0, 3: 0.4}, {2: 0.2}, 8, 24, 2, 0.05, 9)
    a = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    b = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg, gauge="zero")
    assert b.table_error_arcsec[0] == 0.0 and b.table_u_arcsec[0] < 1e-9
    d = b.table_error_arcsec - a.table_error_arcsec
    np.testing.assert_allclose(d, d[0], atol=1e-12)
    np.testing.assert_allclose(b.gonio_error_arcsec, a.gonio_error_arcsec, atol=1e-12)
    assert b.closure.table_sum_arcsec == pytest.approx(-24 * a.table_error_arcsec[0])


def test_repeats_axis_and_list_input_agree():
    sim = simulate_eda_matrix({1: 1.0}, {1: 0.1}, 8, 8, 3, 0.1, 4)
    a = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    b = equal_division_analysis(np.moveaxis(sim.D_arcsec, 0, 2), sim.start_deg,
                                sim.step_deg, repeats_axis=2)
    c = equal_division_analysis(list(sim.D_arcsec), sim.start_deg, sim.step_deg)
    for r in (b, c):
        np.testing.assert_allclose(r.table_error_arcsec, a.table_error_arcsec, atol=1e-12)
    assert a.repeats == 3 and a.dof == 3 * 64 - 15


# ----------------------------------------------------------------------------- comparison
def test_compare_tables_recovers_known_difference():
    gh = {1: 0.3, 2: (0.2, 0.4)}
    ta = {1: 2.0, 3: (0.6, 0.2), 5: 0.3}
    tb = {1: 1.5, 2: (0.4, 1.0), 5: 0.3}
    sa = simulate_eda_matrix(ta, gh, 12, 12, 2, 0.05, 21)
    sb = simulate_eda_matrix(tb, gh, 12, 12, 2, 0.05, 22)
    a = equal_division_analysis(sa.D_arcsec, sa.start_deg, sa.step_deg)
    b = equal_division_analysis(sb.D_arcsec, sb.start_deg, sb.step_deg)
    cmp_ = compare_tables(a, b)
    x = np.arange(12) * 30.0
    truth = _series(x, ta) - _series(x, tb)
    truth -= truth.mean()
    z = (cmp_.difference_arcsec - truth) / cmp_.u_difference_arcsec
    assert np.all(np.abs(z) < 4.5)
    assert np.max(np.abs(truth)) > 1.0                    # a real difference was recovered
    # independent runs, both already zero-sum (closure gauge): u² = u_a² + u_b² (GUM 5.1)
    np.testing.assert_allclose(cmp_.u_difference_arcsec,
                               np.hypot(a.table_u_arcsec, b.table_u_arcsec), rtol=1e-9)
    # same goniometer in both runs: chi² of its curves ~ m (99.9 % quantile of chi²(12) ≈ 32.9)
    assert cmp_.gonio_points == 12 and cmp_.gonio_chi2 < 32.9


def test_compare_tables_on_common_positions_of_different_grids():
    ta = {1: 1.0, 2: 0.5}
    tb = {1: 0.2}
    a = equal_division_analysis(**_kw(simulate_eda_matrix(ta, {1: 0.1}, 24, 24, 1, 0.0, 1)))
    b = equal_division_analysis(**_kw(simulate_eda_matrix(tb, {1: 0.1}, 8, 8, 1, 0.0, 1)))
    cmp_ = compare_tables(a, b)
    np.testing.assert_allclose(cmp_.position_deg, np.arange(8) * 45.0)
    x = np.arange(8) * 45.0
    truth = _series(x, ta) - _series(x, tb)
    np.testing.assert_allclose(cmp_.difference_arcsec, truth - truth.mean(), atol=1e-9)


def _kw(sim):
    return {"D": sim.D_arcsec, "start_deg": sim.start_deg, "step_deg": sim.step_deg}


# ----------------------------------------------------------------------------- input errors
def test_starts_off_the_step_grid_raise():
    sim = simulate_eda_matrix({1: 1.0}, None, 5, 12, 1, 0.01, 0)   # 72° starts, 30° step
    with pytest.raises(GonioError, match="not a multiple of the step"):
        equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    with pytest.raises(GonioError, match="columns"):
        equal_division_analysis(sim.D_arcsec[..., :-1], sim.start_deg, sim.step_deg)
    with pytest.raises(GonioError, match="non-finite"):
        D = sim.D_arcsec.copy()
        D[0, 0, 0] = np.nan
        equal_division_analysis(D, [0, 30, 60, 90, 120], 30.0)
    with pytest.raises(GonioError, match="integer"):
        equal_division_analysis(sim.D_arcsec, sim.start_deg, 35.0)


def test_harmonic_transfer_irregular_starts_partial():
    # two starts 90° apart on a 24-point grid: orders not multiple of 4 are partly seen
    df = harmonic_transfer([0.0, 90.0], 15.0, 8)
    assert (df.table_status[df.order == 4] == "unobservable").all()
    np.testing.assert_allclose(df.eda_mean_transfer,
                               np.abs(1 + np.exp(1j * np.deg2rad(90.0) * df.order)) / 2,
                               atol=1e-12)


def test_readings_roundtrip_and_validation():
    sim = simulate_eda_matrix({1: 1.0, 4: 0.3}, {2: 0.2}, 8, 24, 2, 0.05, 2)
    df = _readings_frame(sim.D_arcsec, sim.start_deg, sim.step_deg)
    df.index = np.arange(len(df)) + 4
    D, start, step = eda_matrix_from_readings(df.sample(frac=1.0, random_state=1))
    np.testing.assert_allclose(D, sim.D_arcsec, atol=1e-8)
    np.testing.assert_allclose(start, sim.start_deg)
    assert step == 15.0
    # other tests' rows and readings at the zero are ignored
    extra = pd.DataFrame({"test": ["zero_stability", "equal_division"], "series": [1, 1],
                          "round": [1, 1], "time_s": [0, 0], "start_deg": [np.nan, 0.0],
                          "table_deg": [np.nan, 0.0], "gyro_deg": [0.0, 0.0]})
    D2, _, _ = eda_matrix_from_readings(pd.concat([df, extra], ignore_index=True))
    np.testing.assert_allclose(D2, D)
    # incomplete grid
    with pytest.raises(GonioError, match="incomplete grid: no reading for series 1, round 2"):
        eda_matrix_from_readings(df.drop(index=df.index[30]))
    # a step that is not j·Δ names the line
    bad = df.copy()
    bad.loc[bad.index[5], "table_deg"] = 97.0
    with pytest.raises(GonioError, match=r"^line 9: column table_deg: table_deg 97"):
        eda_matrix_from_readings(bad)
    # inconsistent start for a round
    bad = df.copy()
    bad.loc[bad.index[3], "start_deg"] = 10.0
    with pytest.raises(GonioError, match="line 7: column start_deg"):
        eda_matrix_from_readings(bad)
    # duplicate
    with pytest.raises(GonioError, match="duplicate"):
        eda_matrix_from_readings(pd.concat([df, df.iloc[[0]]]))
    # unparsable number
    bad = df.astype({"gyro_deg": object})
    bad.loc[bad.index[2], "gyro_deg"] = "x"
    with pytest.raises(GonioError, match="line 6: column gyro_deg: expected a number"):
        eda_matrix_from_readings(bad)
    # no start_deg column: the number of starts is needed
    nostart = df.drop(columns="start_deg")
    with pytest.raises(GonioError, match="start_deg"):
        eda_matrix_from_readings(nostart)
    D3, start3, _ = eda_matrix_from_readings(nostart, starts=8)
    np.testing.assert_allclose(start3, np.arange(8) * 45.0)
    with pytest.raises(GonioError, match="--starts 6"):
        eda_matrix_from_readings(df, starts=6)


# ----------------------------------------------------------------------------- protocol
def test_protocol_file_and_validation(tmp_path):
    p = load_eda_protocol()
    assert (p.starts, p.points, p.step_deg, p.rate_dps) == (12, 12, 30.0, 60.0)
    np.testing.assert_allclose(p.start_deg, np.arange(12) * 30.0)
    head = '[protocol]\nname = "x"\ntitle = "x"\nspecification = "x"\n[equal_division]\n'
    f = tmp_path / "bad.toml"
    f.write_text(head + "starts = 5\npoints = 12\n", encoding="utf-8")
    with pytest.raises(GonioError, match="equal_division.starts"):
        load_eda_protocol(f)
    f.write_text(head + "steps = 5\n", encoding="utf-8")
    with pytest.raises(GonioError, match="equal_division.steps: unknown key"):
        load_eda_protocol(f)


# ----------------------------------------------------------------------------- CLI
def test_cli_json_plot_and_errors(tmp_path, capsys):
    sim = simulate_eda_matrix({1: 2.0, 3: 0.5}, {2: 0.3}, 8, 8, 2, 0.05, 1)
    df = _readings_frame(sim.D_arcsec, sim.start_deg, sim.step_deg)
    f = _write_csv(tmp_path / "r.csv", df)
    fig = tmp_path / "out" / "eda.png"
    assert main(["eda", str(f), "--noise", "white", "--json", "--plot", str(fig),
                 "--no-coupling"]) == 0
    out = json.loads(capsys.readouterr().out)
    ref = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    np.testing.assert_allclose(out["table"]["error_arcsec"], ref.table_error_arcsec, atol=1e-5)
    np.testing.assert_allclose(out["goniometer"]["u_arcsec"], ref.gonio_u_arcsec, atol=1e-5)
    assert out["dof"] == ref.dof and out["closure"]["consistent"] is True
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["eda", str(f), "--starts", "8"]) == 0
    assert "full-turn goniometer error" in capsys.readouterr().out
    # bad input: a missing reading, a wrong --starts, a missing file → exit 2, one line
    g = _write_csv(tmp_path / "bad.csv", df.drop(index=17))
    assert main(["eda", str(g)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and "incomplete grid" in err and err.count("\n") == 1
    assert main(["eda", str(f), "--starts", "4"]) == 2
    assert "--starts 4" in capsys.readouterr().err
    assert main(["eda", str(tmp_path / "none.csv")]) == 2
    h = tmp_path / "line.csv"
    h.write_text("# serial: 1\ntest,series,round,time_s,start_deg,table_deg,gyro_deg\n"
                 "equal_division,1,1,1,0,180,180\nequal_division,1,1,2,0,3x0,360\n",
                 encoding="utf-8")
    assert main(["eda", str(h)]) == 2
    assert "line.csv:4: column table_deg: expected a number" in capsys.readouterr().err
