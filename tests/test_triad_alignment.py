"""Gyro-triad alignment (issue 18): the alignment article's worked numbers, rotations and
misalignment matrices, the virtual triad, the estimate of M and b (exact without noise,
within uncertainty with noise over many seeds, GUM against Monte Carlo, robust fit with
outliers), the averaging time from the Allan deviation, IEC 62047-20 5.2, the readings
format and the CLI.

Independent references: the article's printed values ([Looney-alignment]), closed forms (Rodrigues,
the ± difference formula of the article eq. 30a, white-noise Allan deviation N/√τ),
numerical quadrature, Student-t coverage probabilities, and a simulation of the fit.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy import stats

from gonio.specs.triad_alignment.analysis import (COVERAGE, cross_axis_sensitivity_iec,
                                            cross_axis_sensitivity_pm, cross_axis_table,
                                            estimate_alignment, gum_propagate)
from gonio.specs.triad_alignment.bench import (TriadBench, TriadProtocol, ThermalModel, load_triad_bench,
                               load_triad_protocol, run_alignment_session, write_triad_session)
from gonio.cli import main
from gonio.errors import GonioError
from gonio.specs.triad_alignment.readings import (TriadReadings, format_triad_readings, parse_triad_readings,
                                 read_triad_readings)
from gonio.physics import alignment as al
from gonio.physics.earth import earth_rate_enu, earth_rate_on_axis_dps
from gonio.units import deg_sqrt_s_from_deg_sqrt_h, dps_to_dph


# ----------------------------------------------------------------- helpers
def bench(arw=0.0, bi=0.0, fs=20.0, lat=49.2, **kw) -> TriadBench:
    nonorth = np.array([[0, 2.0e-3, -1.5e-3], [0.8e-3, 0, 3.0e-3], [-2.2e-3, 1.1e-3, 0]])
    cc = np.array([[0, 1e-3, 0], [-5e-4, 0, 0], [0, 8e-4, 0]])
    args = dict(name="test", latitude_deg=lat, sample_rate_hz=fs, instrument="t", serial="s",
                output_unit="lsb", scale_per_dps=(50.0, 50.4, 49.7), nonorthogonality_rad=nonorth,
                mounting_rad=(4.5e-3, -3.0e-3, 14.6e-3), cross_coupling=cc,
                bias_dps=(0.2, -0.15, 0.08), arw_deg_sqrt_h=(arw,) * 3,
                bias_instability_dph=(bi,) * 3, rate_random_walk_dph_sqrt_h=(0.0,) * 3,
                thermal=ThermalModel())
    args.update(kw)
    return TriadBench(**args)


def protocol(static_s=0.0, revolutions=1, rates=(50.0, 100.0), static_dwell=10.0) -> TriadProtocol:
    return TriadProtocol("t", "triad-alignment", tuple(rates), revolutions, 0.5, True,
                         static_dwell, {"x": "+y", "y": "+z", "z": "+x"}, static_s, {})


def readings_of(session):
    return parse_triad_readings(format_triad_readings(session.readings, session.metadata), "r.csv")


# ------------------------------------------------------- the article's numbers
def test_article_worked_budget_and_where_it_differs():
    """[Looney-alignment] eq. 5a–5c: 0.3°, R_S 29.1 mm, 0.83°, 1.28°."""
    tilt = math.degrees(al.ledge_tilt_rad(0.2, 44.0))
    assert round(tilt, 1) == 0.3                       # printed 0.3°: rounded
    assert tilt == pytest.approx(math.degrees(math.atan2(0.2, 44.0)), rel=1e-12)
    assert abs(tilt - 0.2604) < 5e-5                   # exact value, not 0.3
    rs = al.rotation_radius_mm(39.6, 42.6)
    assert round(rs, 1) == 29.1
    skew = math.degrees(al.screw_clearance_skew_rad(2.85, 2.0, 29.1))
    assert math.floor(skew * 100) / 100 == 0.83        # printed 0.83: truncated ...
    assert round(skew, 2) == 0.84                      # ... rounding gives 0.84
    total = math.degrees(al.total_misalignment_rad(math.radians(1.0), math.radians(skew)))
    assert abs(total - 1.3039) < 1e-4
    # the printed 1.28° is not the RSS of the printed 1° and 0.83° (1.2996°) ...
    assert round(math.hypot(1.0, 0.83), 2) == 1.30
    # ... but of 1° and 0.8°
    assert round(math.hypot(1.0, 0.8), 2) == 1.28
    b = al.misalignment_budget(ledge_tolerance_mm=0.2, width_mm=44.0, hole_diameter_mm=2.85,
                               screw_diameter_mm=2.0, rotation_radius=29.1, psi_imu_deg=1.0)
    assert b.psi_sys_deg == pytest.approx(skew) and b.total_deg == pytest.approx(total)
    assert b.wanted_scale == pytest.approx(math.cos(math.radians(total)))
    from gonio.specs import get
    sb = get("triad-alignment").budget()
    assert sb.rotation_radius_mm == pytest.approx(rs) and abs(sb.total_deg - 1.3042) < 1e-4


def test_article_platform_and_noise_examples():
    """[Looney-alignment] eq. 13c (1.9°), 13d (14.8°), 30b (62 °/h, averaging 0.1 s)."""
    assert round(math.degrees(al.allowed_cross_axis_angle_rad(1.0, 30.0)), 1) == 1.9
    assert round(math.degrees(al.allowed_axis_angle_rad(1.0, 30.0)), 1) == 14.8
    # the leaked angle at the limit is exactly 1° of a 30° heading change
    phi = al.allowed_cross_axis_angle_rad(1.0, 30.0)
    assert 30.0 * math.sin(phi) == pytest.approx(1.0, rel=1e-12)
    lim_dph = dps_to_dph(al.alignment_noise_limit_dps(100.0, math.radians(0.1)))
    assert math.floor(lim_dph) == 62
    # ARW 0.3 °/√h (white only): N/√τ ≤ limit from τ = (N/limit)² ≈ 0.082 s: the article's
    # 0.1 s with some margin
    n_dph_sqrt_s = dps_to_dph(deg_sqrt_s_from_deg_sqrt_h(0.3))      # (°/h)·√s
    tau_star = (n_dph_sqrt_s / lim_dph) ** 2
    assert 0.05 < tau_star < 0.1


def test_misalignment_effect_is_cos_and_sin():
    for psi in (0.0, 0.01, 0.3):
        a = al.sensing_axes_exact([[0, psi, 0], [0, 0, 0], [0, 0, 0]])
        c, s = al.misalignment_effect(psi)
        assert a[0, 0] == pytest.approx(c, abs=1e-15) and a[0, 1] == pytest.approx(s, abs=1e-15)


# ---------------------------------------------------------------- rotations
@pytest.mark.parametrize("angles", [(0.01, 0, 0), (0, -0.02, 0), (0.003, 0.004, -0.005),
                                    (0.2, -0.1, 0.3)])
def test_rotation_exact_and_small_angle(angles):
    r = al.rotation_xyz(*angles)
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-14) and np.linalg.det(r) == pytest.approx(1.0)
    # independent: Rodrigues about each axis composed vs. scipy
    from scipy.spatial.transform import Rotation
    ref = Rotation.from_euler("xyz", angles).as_matrix()   # extrinsic x, then y, then z
    assert np.allclose(r, ref, atol=1e-14)
    err = al.small_angle_error(*angles)
    th = max(abs(a) for a in angles)
    assert err <= 1.5 * th ** 2 and err > 0.2 * th ** 2


def test_sensing_axis_matrix_small_angle_within_second_order():
    nonorth = np.array([[0, 2e-3, -1.5e-3], [0.8e-3, 0, 3e-3], [-2.2e-3, 1.1e-3, 0]])
    a1 = al.sensing_axis_matrix(nonorth, (4.5e-3, -3e-3, 14.6e-3), exact=True)
    a2 = al.sensing_axis_matrix(nonorth, (4.5e-3, -3e-3, 14.6e-3), exact=False)
    assert np.allclose(np.linalg.norm(a1, axis=1), 1.0, atol=1e-15)
    diff = np.max(np.abs(a1 - a2))
    assert 1e-6 < diff < 0.02 ** 2


def test_decompose_recovers_construction():
    a = al.sensing_axes_exact([[0, 0.01, -0.02], [0.005, 0, 0.0], [0.0, 0.03, 0]])
    m = al.system_matrix([2.0, 3.0, 4.0], a)
    d = al.decompose_system_matrix(m)
    assert d["scale"] == pytest.approx([2.0, 3.0, 4.0], rel=1e-14)
    assert np.array(d["phi_rad"])[0, 2] == pytest.approx(-0.02, rel=1e-12)
    assert np.array(d["psi_rad"])[2] == pytest.approx(0.03, rel=1e-10)
    assert np.array(d["cross_axis"])[1, 0] == pytest.approx(math.sin(0.005) / a[1, 1], rel=1e-12)
    r = al.rotation_xyz(0.01, 0.02, -0.03)
    assert np.allclose(al.first_column_from_orthogonality(r[:, 1], r[:, 2]), r[:, 0])


@pytest.mark.parametrize("up,north0,table,rate,dur", [("+z", "+x", 10.0, 7.0, 13.0),
                                                      ("-y", "+x", 200.0, -50.0, 3.3),
                                                      ("+x", "-z", 0.0, 0.0, 5.0),
                                                      ("-x", "+y", 33.0, 100.0, 7.2)])
def test_mean_earth_rate_against_quadrature(up, north0, table, rate, dur):
    w = np.degrees(earth_rate_enu(49.2))
    got = al.mean_earth_rate_ref(w, up, north0, table, rate, dur)
    from scipy.integrate import simpson
    ts = np.linspace(0.0, dur, 2001)
    c0 = al.ref_to_enu(up, north0, 0.0)
    th = np.radians(table + rate * ts)
    rz_t_w = np.column_stack([np.cos(th) * w[0] + np.sin(th) * w[1],       # Rz(θ)ᵀ w
                              -np.sin(th) * w[0] + np.cos(th) * w[1], np.full_like(th, w[2])])
    vals = rz_t_w @ c0                                                        # C0ᵀ Rz(θ)ᵀ w
    ref = simpson(vals, x=ts, axis=0) / dur
    assert np.allclose(got, ref, rtol=0, atol=1e-12)
    # the component along the up axis is the vertical Earth rate (physics.earth)
    assert float(got @ al.signed_axis(up)) == pytest.approx(earth_rate_on_axis_dps(49.2, "up"),
                                                             rel=1e-12)


# ----------------------------------------------------------- the estimate of M
def test_exact_recovery_without_noise():
    b = bench()
    s = run_alignment_session(protocol(), b, seed=1)
    r = readings_of(s)
    res = estimate_alignment(r)
    assert np.allclose(res.system_matrix, b.system_matrix, rtol=0, atol=1e-9)
    assert np.allclose(res.bias_output, b.bias_output, rtol=0, atol=1e-9)
    assert np.allclose(res.alignment_matrix @ b.system_matrix, np.eye(3), atol=1e-11)
    assert np.max(np.abs(res.leakage_against(b.system_matrix))) < 1e-11
    # the article's ± difference (eq. 30a): column j = (G₊ − G₋)/(2ω) about axis j
    al_rows = r.rows("alignment")
    for j, ax in enumerate("xyz"):
        p = al_rows[(al_rows.up == f"+{ax}") & (al_rows.rate_dps == 100.0)].iloc[0]
        m = al_rows[(al_rows.up == f"+{ax}") & (al_rows.rate_dps == -100.0)].iloc[0]
        col = (p[["out_x", "out_y", "out_z"]].to_numpy(float)
               - m[["out_x", "out_y", "out_z"]].to_numpy(float)) / 200.0
        assert np.allclose(col, b.system_matrix[:, j], atol=1e-10)
    # without the Earth rate in the model the noise-free recovery fails (the test can fail)
    r0 = readings_of(s)
    r0.metadata["latitude_deg"] = "0.0"
    res0 = estimate_alignment(r0)
    assert np.max(np.abs(res0.bias_output - b.bias_output)) > 1e-3


def test_figure_language_is_per_call():
    """A Chinese drawing leaves no language behind: the next figure drawn without a language
    is English (figure text was once a module-wide setting, so an English plot made after a
    Chinese certificate in the same process came out in Chinese)."""
    from matplotlib.text import Text

    from gonio.specs.triad_alignment.figures import FIG_TEXT, alignment_figure

    res = estimate_alignment(readings_of(run_alignment_session(protocol(), bench(), seed=1)))

    def texts(fig):
        return {t.get_text() for t in fig.findobj(Text)}

    zh = texts(alignment_figure(res, lang="zh"))
    en = texts(alignment_figure(res))
    assert FIG_TEXT["cross_title"][1] in zh and FIG_TEXT["cross_title"][0] not in zh
    assert FIG_TEXT["cross_title"][0] in en
    assert not any("\u4e00" <= c <= "\u9fff" for t in en for c in t)


def test_cross_axis_iec_5_2():
    """Constructed check of the IEC digest: 100 °/s about X, 3.0 mV, 6.0 mV/(°/s) → 0.5 %."""
    assert cross_axis_sensitivity_iec(3.0, 0.0, 6.0, 100.0) == pytest.approx(0.005, rel=1e-15)
    assert cross_axis_sensitivity_pm(1003.0, 997.0, 6.0, 100.0) == pytest.approx(0.005)
    with pytest.raises(GonioError):
        cross_axis_sensitivity_iec(3.0, 0.0, 0.0, 100.0)
    b = bench()
    res = estimate_alignment(readings_of(run_alignment_session(protocol(), b, seed=2)))
    tab = cross_axis_table(res)
    m = b.system_matrix
    for row in tab.itertuples(index=False):
        i, j = "xyz".index(row.gyro), "xyz".index(row.about)
        assert row.sensitivity == pytest.approx(m[i, j] / m[i, i], abs=1e-12)
        # the ± variant on one gyro's outputs gives the same (single-axis gyro, 5.2)
    rows = readings_of(run_alignment_session(protocol(), b, seed=2)).rows("alignment")
    p = rows[(rows.up == "+x") & (rows.rate_dps == 100.0)].iloc[0]
    q = rows[(rows.up == "+x") & (rows.rate_dps == -100.0)].iloc[0]
    k_zx = cross_axis_sensitivity_pm(p.out_z, q.out_z, m[2, 2], 100.0)
    assert k_zx == pytest.approx(m[2, 0] / m[2, 2], abs=1e-12)


def _coverage_bounds(n_events: int, z: float = 3.5):
    sd = math.sqrt(COVERAGE * (1 - COVERAGE) / n_events)
    return COVERAGE - z * sd, COVERAGE + z * sd


def test_within_uncertainty_over_many_seeds():
    """White noise: (θ̂ − θ)/u ~ t_ν, so k = t_{0.9545,ν} intervals cover 95.45 %. Bounds
    from the number of events; shown to reject u wrong by 20 %."""
    b = bench(arw=0.6)
    p = protocol(static_dwell=5.0)
    n_seeds = 120
    hits = []
    leak_hits = []
    for seed in range(n_seeds):
        s = run_alignment_session(p, b, seed=seed)
        res = estimate_alignment(TriadReadings(s.readings.assign(line=np.arange(len(s.readings))),
                                               s.metadata, "r.csv"))
        err = np.column_stack([res.system_matrix - b.system_matrix,
                               res.bias_output - b.bias_output])
        u = np.column_stack([res.u_system_matrix, res.u_bias_output])
        hits.append(np.abs(err) <= res.coverage_factor_theta * u)
        lk = res.leakage_against(b.system_matrix)
        off = ~np.eye(3, dtype=bool)
        leak_hits.append(np.abs(lk[off]) <= 2.0 * res.leakage_u[off] * 1.1)
    cov = float(np.mean(hits))
    lo, hi = _coverage_bounds(12 * n_seeds)
    nu = float(res.dof[0])                   # ν_w of M: the dwells about their block's bias
    k = stats.t.ppf(0.5 + COVERAGE / 2, nu)
    for f in (0.8, 1.2):     # coverage if every u were 20 % off: outside the bounds
        alt = 2 * stats.t.cdf(k * f, nu) - 1
        assert not lo <= alt <= hi
    assert lo <= cov <= hi, (cov, lo, hi)
    assert np.mean(leak_hits) > 0.9


def test_gum_against_monte_carlo():
    b = bench(arw=0.6)
    res = estimate_alignment(readings_of(run_alignment_session(protocol(), b, seed=7)),
                             monte_carlo=3000, seed=3)
    ratio = np.concatenate([res.u_mc_theta / np.sqrt(np.diag(res.cov_theta))]
                           + [res.u_mc[k] / res.u_derived[k] for k in res.u_mc
                              if np.all(res.u_derived[k] > 0)])
    # 3000 trials: relative sd of an sd estimate 1.3 %; 5 % allows for the linearisation
    assert np.all(np.abs(ratio - 1.0) < 0.06), ratio
    c = gum_propagate(lambda v: np.array([v[0] / v[1]]), np.array([2.0, 4.0]), np.diag([0.01, 0.04]))
    assert c[0, 0] == pytest.approx(0.01 / 16 + 0.04 * 4 / 256, rel=1e-6)


def test_robust_fit_with_outliers():
    b = bench(arw=0.6)
    s = run_alignment_session(protocol(), b, seed=11)
    clean = readings_of(s)
    ols_clean = estimate_alignment(clean)
    rob_clean = estimate_alignment(clean, robust=True)
    assert np.all(np.abs(rob_clean.system_matrix - ols_clean.system_matrix)
                  <= 1.0 * ols_clean.u_system_matrix)
    df = s.readings.copy()
    al_idx = df.index[df.test == "alignment"]
    sd = float(ols_clean.sigma_output[0])
    df.loc[al_idx[2], "out_x"] += 300 * sd          # a glitch in one dwell of gyro x
    df.loc[al_idx[9], "out_z"] -= 200 * sd          # and one of gyro z
    bad = parse_triad_readings(format_triad_readings(df, s.metadata), "bad.csv")
    ols = estimate_alignment(bad)
    rob = estimate_alignment(bad, robust=True)
    err_ols = np.abs(ols.system_matrix - b.system_matrix) / ols_clean.u_system_matrix
    err_rob = np.abs(rob.system_matrix - b.system_matrix) / rob.u_system_matrix
    assert err_ols.max() > 10
    assert err_rob.max() < 4.0
    flagged = {(o["line"], o["channel"]) for o in rob.outliers}
    lines = bad.rows("alignment")["line"]
    assert (int(lines.iloc[2]), "out_x") in flagged and (int(lines.iloc[9]), "out_z") in flagged
    assert len(flagged) <= 4


def test_averaging_time_from_allan_deviation():
    """White noise only: ADEV = N/√τ; the chosen τ is the first octave with N/√τ ≤ limit."""
    arw = 0.5                                        # τ* mid-octave (0.64 … 1.28 s)
    b = bench(arw=arw, fs=50.0)
    res = estimate_alignment(readings_of(run_alignment_session(protocol(static_s=200.0), b, seed=4)))
    avg = res.averaging
    lim = al.alignment_noise_limit_dps(50.0, math.radians(0.1))
    assert avg.noise_limit_dps == pytest.approx(lim)
    n_dps = deg_sqrt_s_from_deg_sqrt_h(arw)
    tau_star = (n_dps / lim) ** 2                    # ≈ 0.91 s
    taus = np.array(avg.tau_s)
    expected = taus[np.nonzero(taus >= tau_star)[0][0]]
    assert all(t == expected for t in avg.tau_needed_s), (avg.tau_needed_s, tau_star)
    assert avg.sufficient == (avg.shortest_dwell_s >= expected)


def test_bench_with_bias_instability_recovers_m():
    """The packaged bench (ARW + bias instability): M within 4u (bias drifts in-run)."""
    b = load_triad_bench("mems-triad")
    p = dataclasses.replace(load_triad_protocol("triad-alignment"), static_duration_s=0.0)
    res = estimate_alignment(readings_of(run_alignment_session(p, b, seed=5)))
    z = np.abs(res.system_matrix - b.system_matrix) / res.u_system_matrix
    assert z.max() < 4.5
    assert np.max(np.abs(res.leakage_against(b.system_matrix))) < 1e-4


# -------------------------------------------------------------- format and CLI
def test_readings_round_trip_and_determinism(tmp_path):
    b = bench(arw=0.3)
    s1 = run_alignment_session(protocol(static_s=5.0), b, seed=3)
    s2 = run_alignment_session(protocol(static_s=5.0), b, seed=3)
    t1 = format_triad_readings(s1.readings, s1.metadata)
    assert t1 == format_triad_readings(s2.readings, s2.metadata)
    assert t1 != format_triad_readings(*(lambda s: (s.readings, s.metadata))(
        run_alignment_session(protocol(static_s=5.0), b, seed=4)))
    paths = write_triad_session(s1, tmp_path / "o")
    r = read_triad_readings(paths["readings"])
    assert np.array_equal(r.data["out_x"].to_numpy(), s1.readings["out_x"].to_numpy())
    assert json.loads(paths["truth"].read_text())["system_matrix"] == b.system_matrix.tolist()


@pytest.mark.parametrize("edit,where", [
    (lambda t: t.replace("\nalignment,", "\nalignmnt,", 1), "column test"),
    (lambda t: t.replace("# latitude_deg: 49.2\n", ""), "latitude_deg"),
    (lambda t: t.replace(",+x,+y,", ",+x,+x,", 1), "column north0"),
])
def test_readings_errors_name_the_place(edit, where):
    s = run_alignment_session(protocol(), bench(), seed=0)
    text = edit(format_triad_readings(s.readings, s.metadata))
    with pytest.raises(GonioError) as e:
        parse_triad_readings(text, "x.csv")
    assert where in str(e.value) and "x.csv" in str(e.value)


def test_cli_simulate_align_and_errors(tmp_path, capsys):
    proto = tmp_path / "p.toml"
    proto.write_text(
        '[protocol]\nname = "quick"\n[alignment]\nrates_dps = [100.0]\nrevolutions = 1\n'
        'static_dwell_s = 5.0\n[static]\nduration_s = 20.0\n', encoding="utf-8")
    out = tmp_path / "sim"
    assert main(["simulate", "--spec", "triad-alignment", "--protocol", str(proto),
                 "--out", str(out), "--seed", "2"]) == 0
    first = (out / "readings.csv").read_bytes()
    # an existing readings file is replaced only with --force (issue 14)
    assert main(["simulate", "--spec", "triad-alignment", "--protocol", str(proto),
                 "--out", str(out), "--seed", "2"]) == 2
    assert main(["simulate", "--spec", "triad-alignment", "--protocol", str(proto),
                 "--out", str(out), "--seed", "2", "--force"]) == 0
    assert (out / "readings.csv").read_bytes() == first
    assert not (out / "thermal.csv").exists()
    capsys.readouterr()
    png = tmp_path / "a.png"
    assert main(["align", str(out / "readings.csv"), "--json", "--monte-carlo", "200",
                 "--plot", str(png)]) == 0
    res = json.loads(capsys.readouterr().out)
    truth = json.loads((out / "truth.json").read_text())
    m = np.array(res["system_matrix"])
    u = np.array(res["u_system_matrix"])
    assert np.all(np.abs(m - np.array(truth["system_matrix"])) < 6 * u)
    assert png.stat().st_size > 1000
    assert main(["align", str(out / "readings.csv"), "--robust", "--monte-carlo", "0"]) == 0
    assert "alignment matrix" in capsys.readouterr().out
    pages = []
    for name in ("a.html", "b.html"):
        assert main(["align", str(out / "readings.csv"), "--monte-carlo", "100",
                     "--report", str(tmp_path / name)]) == 0
        pages.append((tmp_path / name).read_bytes())
    page = pages[0]
    assert pages[0] == pages[1] and b"<svg" in page
    # the page shows M as the certified item states it (its bound-condition interval, the
    # statement rule's digits)
    from gonio.specs.triad_alignment.calibration import calibrate
    from gonio.specs.triad_alignment.pages import certified_cell, value_with_u
    item = calibrate(out / "readings.csv").items["M_xx"]
    assert item.uncertainty.u_c == pytest.approx(u[0][0], rel=1e-9)
    cell = certified_cell(item)
    assert item.uncertainty.k is None and cell.encode() in page
    assert value_with_u(49.99371, 0.0028) == "49.9937 ± 0.0028"
    bad = tmp_path / "bad.csv"
    bad.write_text((out / "readings.csv").read_text().replace("# format: gonio-triad-readings/1",
                                                              "# format: other"))
    assert main(["align", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "format" in err
    assert main(["simulate", "--spec", "nope", "--out", str(tmp_path / "n")]) == 2
    assert "triad-alignment" in capsys.readouterr().err


def test_uneven_static_record_is_an_error_naming_the_line():
    s = run_alignment_session(protocol(static_s=5.0), bench(arw=0.3), seed=0)
    df = s.readings.copy()
    idx = df.index[df.test == "static"][10]
    df.loc[idx, "time_s"] += 0.5
    line = int(s.readings.index.get_loc(idx)) + 1 + sum(
        1 for ln in format_triad_readings(df, s.metadata).splitlines() if ln.startswith("#")) + 1
    with pytest.raises(GonioError) as e:       # the reader refuses times that go back (issue 26)
        estimate_alignment(parse_triad_readings(format_triad_readings(df, s.metadata), "u.csv"))
    assert (f"u.csv:{line}:" in str(e.value) or f"line {line} " in str(e.value)) \
        and "time_s" in str(e.value), str(e.value)


def test_specification_plug_in(tmp_path):
    from gonio.specs import available, get

    spec = get("triad-alignment")
    assert "triad-alignment" in available() and spec.default_bench == "mems-triad"
    b = bench(arw=0.3)
    paths = write_triad_session(run_alignment_session(protocol(static_s=0.0), b, seed=9),
                                tmp_path / "s")
    cal = spec.calibrate(paths["readings"])
    out = json.loads(json.dumps(cal.to_json(), allow_nan=False))["extra"]
    assert out["thermal_model"] is None and out["alignment"]["averaging_time"] is None
    m = np.array(out["alignment"]["system_matrix"])
    u = np.array(out["alignment"]["u_system_matrix"])
    assert np.all(np.abs(m - b.system_matrix) <= 5 * u)
    assert len(out["cross_axis"]) == 6
    # the matrix elements are items with their covariance: per gyro, its row of M and its bias
    # from one fit; the diagonal is each item's u_c squared, the matrix symmetric
    covs = cal.to_json()["covariances"]
    assert [c["items"] for c in covs] == [[f"M_{a}x", f"M_{a}y", f"M_{a}z", f"b_{a}"]
                                          for a in "xyz"]
    for c in covs:
        C = np.array(c["matrix"])
        assert np.allclose(C, C.T, rtol=1e-12, atol=0)
        assert np.allclose(np.sqrt(np.diag(C)), [cal.items[k].uncertainty.u_c for k in c["items"]],
                           rtol=1e-12)


def test_bias_wander_does_not_widen_m():
    """The packaged bench (ARW + bias instability): the bias wanders between the
    orientations and the static positions, recorded minutes apart; the ± pairs of an
    orientation cancel it, so u(M) rests on the scatter about each block's own bias. With
    one s² of all residuals (the wander counted into M) the pooled sd of z over 9 × 30 M
    elements was 0.66; the bounds hold z ~ t_ν (sd √(ν/(ν−2)) = 1.22 at ν = 6) with
    sampling room and reject that."""
    b = load_triad_bench("mems-triad")
    p = dataclasses.replace(load_triad_protocol("triad-alignment"), static_duration_s=0.0)
    z = []
    for seed in range(900, 930):
        res = estimate_alignment(readings_of(run_alignment_session(p, b, seed=seed)))
        z.append(((res.system_matrix - b.system_matrix) / res.u_system_matrix).ravel())
        assert np.all(res.sigma_components[:, 1] >= 0)
    sd = float(np.std(z, ddof=1))
    assert 0.8 <= sd <= 1.35, sd
