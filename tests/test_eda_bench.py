"""Equal-division averaging on the virtual bench: a table's known harmonic errors (orders 1–30)
and the goniometer's own error curve are recovered within their uncertainty, except the table
harmonics whose order is a multiple of n, which are reported unobservable (IEC 62047-20 A.3)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.bench.config import Harmonic, TableConfig
from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
from gonio.specs.ogam_draft.equal_division import eda_matrix_from_readings, equal_division_analysis
from gonio.specs.ogam_draft.protocol import parse_protocol


def eda_protocol(n, m, repeats=2):
    return parse_protocol({"protocol": {"name": "eda-test"}, "session": {"static_s": 20.0},
                           "equal_division": {"starts": n, "points": m, "repeats": repeats,
                                              "rate_dps": 60.0, "rest_s": 4.0,
                                              "read_delay_s": 2.0}})


def table_with_harmonics(rng) -> TableConfig:
    harm = tuple(Harmonic(h, float(0.3 / h * (0.5 + rng.random())), float(rng.uniform(0, 360)))
                 for h in range(1, 31))
    return TableConfig(name="test table", accel_dps2=120.0, positioning_harmonics=harm,
                       positioning_random_arcsec=0.005)


def bench_for(rng):
    b = load_bench("rlg")
    inst = replace(b.instrument, tilt_deg=0.0, bias_instability_dph=0.0, rrw_dphsh=0.0,
                   warmup_drift_dph=0.0,
                   position_harmonics=(Harmonic(1, 0.4, 30.0), Harmonic(2, 0.25, 100.0),
                                       Harmonic(3, 0.1, 200.0)))
    # At the pole, axis up, the Earth rate lies along the axis: no tilt coupling.
    return replace(b, instrument=inst, table=table_with_harmonics(rng), latitude_deg=90.0,
                   sample_rate_hz=50.0)


def project_out(values, x_deg, orders):
    """Remove the constant and the given harmonic orders (least squares on the grid)."""
    cols = [np.ones_like(x_deg)]
    for h in orders:
        cols += [np.cos(np.radians(h * x_deg)), np.sin(np.radians(h * x_deg))]
    a = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(a, values, rcond=None)
    return values - a @ coef, a @ coef - coef[0] * a[:, 0]


@pytest.mark.parametrize("n, m", [(12, 12), (8, 8), (8, 24)])
def test_bench_eda_recovers_table_and_goniometer(n, m):
    rng = np.random.default_rng(100 + n + m)
    bench = bench_for(rng)
    res = run_session(eda_protocol(n, m), bench, seed=n * m)
    D, starts, step = eda_matrix_from_readings(res.readings)
    out = equal_division_analysis(D, starts, step, noise="random_walk")
    x = out.table_position_deg
    # Truth: the table's indicated − true error at its grid positions, less what the
    # design cannot see (the constant, and harmonics of order a multiple of n on this grid).
    e = harmonic_sum_arcsec(x, bench.table.positioning_harmonics)
    unobs = [h for h in range(n, m, n)]
    t_obs, t_unobs = project_out(e, x, unobs)
    zt = (out.table_error_arcsec - t_obs) / out.table_u_arcsec
    assert np.max(np.abs(zt)) < 4.5, zt
    # Goniometer: its own position error g(jΔ) − g(0) plus its scale-factor error (the
    # instrument indicates with its nominal K), plus the unobservable table part.
    inst = bench.instrument
    phi = out.gonio_angle_deg
    g0 = harmonic_sum_arcsec(np.zeros(1), inst.position_harmonics)[0]
    g = harmonic_sum_arcsec(phi, inst.position_harmonics) - g0
    g = g + phi * 3600.0 * (inst.true_scale_factor_counts_per_deg
                            / inst.nominal_scale_factor_counts_per_deg - 1.0)
    # The table's unobservable part τ (period 360°/n) enters as −[τ(jΔ) − τ(0)].
    _, tau_grid = project_out(e, x, unobs)
    tau = dict(zip(np.round(x, 9), tau_grid))
    tau_j = np.array([tau[round(v % 360.0, 9)] for v in phi]) - tau[0.0]
    zg = (out.gonio_error_arcsec - (g - tau_j)) / out.gonio_u_arcsec
    assert np.max(np.abs(zg)) < 4.5, zg
    # Multiples of n are reported unobservable; others observable.
    hs = out.harmonics.set_index(out.harmonics.columns[0])
    for h in range(1, min(m // 2, 30) + 1):
        status = str(hs.loc[h, "table_status"])
        if h % n == 0:
            assert status != "observable", (h, status)
        elif h % m != 0 and h < m / 2:
            assert status == "observable", (h, status)
    # The test can fail: the same comparison against a wrong table is far off.
    assert np.max(np.abs((out.table_error_arcsec - 0.5 * t_obs) / out.table_u_arcsec)) > 4.5


def test_bench_eda_uncertainty_consistent_with_scatter():
    rng = np.random.default_rng(5)
    bench = bench_for(rng)
    z = {"random_walk": [], "white": []}
    for seed in range(6):
        res = run_session(eda_protocol(8, 8, repeats=1), bench, seed=seed)
        D, starts, step = eda_matrix_from_readings(res.readings)
        for model in z:
            out = equal_division_analysis(D, starts, step, noise=model)
            x = out.table_position_deg
            t_obs, _ = project_out(harmonic_sum_arcsec(x, bench.table.positioning_harmonics), x, [])
            z[model].append((out.table_error_arcsec - t_obs) / out.table_u_arcsec)
    # A gyro's readings along a start are a random walk from the zeroing: the GLS model
    # gives honest uncertainties, the white model understates them.
    assert 0.6 < np.concatenate(z["random_walk"]).std() < 1.5
    assert np.concatenate(z["white"]).std() > 1.5


def test_calibrate_analyses_eda_rows_and_certificate_carries_the_page(tmp_path):
    """gonio calibrate on equal-division readings: the rows are used (not listed unused),
    results.json gets ``equal_division``, the certificate a table-calibration section whose
    numbers equal results.json."""
    import html
    import json
    import re

    from gonio.specs.ogam_draft.bench import write_session
    from gonio.specs.ogam_draft.readings import read_readings
    from gonio.specs.ogam_draft.calibration import calibrate
    from gonio.specs.ogam_draft.outputs import write_calibration
    from gonio.specs.ogam_draft.certificate_pages import write_certificate
    from gonio.report.i18n import display, labels, minus_sign
    from gonio.specs.ogam_draft.phrases import LABELS

    proto = eda_protocol(4, 8, repeats=2)
    write_session(run_session(proto, bench_for(np.random.default_rng(0)), seed=1), tmp_path)
    result = calibrate(tmp_path / "readings.csv", proto)
    write_calibration(result, tmp_path)
    res = json.loads((tmp_path / "results.json").read_text())
    assert res["unused_readings"] == []
    e = res["extra"]["equal_division"]
    assert (e["n_starts"], e["m_points"], e["repeats"], e["noise"]) == (4, 8, 2, "random_walk")
    from gonio.specs.ogam_draft.equal_division import analyse_eda_readings

    rd = read_readings(tmp_path / "readings.csv")
    direct = analyse_eda_readings(rd.data, proto.extra["equal_division"],
                                  compensation_time_s=proto.session.static_s,
                                  latitude_deg=90.0, tilt_bound_deg=0.1,
                                  table_accel_dps2=float(rd.metadata["table_accel_dps2"]))
    assert e["coupling"]["note"] == direct.coupling.note
    assert np.allclose(e["table"]["error_arcsec"], direct.table_error_arcsec, atol=1e-6)
    page = write_certificate(res, tmp_path)["certificate.html"].read_text()
    assert html.escape(labels("en", LABELS)["eda"]) in page
    nums = re.findall(r'data-src="(extra\.equal_division[^"]+)" data-rule="([^"]+)"[^>]*>([^<]*)<',
                      page)
    assert len(nums) == 6 * 8 + 2
    U = res["extra"]["uncertainty"]["U_arcsec"]
    for src, rule, text in nums:
        v = res
        for part in src.split("."):
            v = v[int(part)] if isinstance(v, list) else v[part]
        assert html.unescape(text) == minus_sign(display(rule, v, U)), src
    # the coupling's sentence: the analysis' own words on the English page, the page's
    # language on the Chinese one (by the stored reason, never the English note)
    from gonio.specs.ogam_draft.phrases import COUPLING_TEXT
    reason = e["coupling"]["reason"]
    assert reason == direct.coupling.reason and reason in COUPLING_TEXT
    assert html.escape(direct.coupling.note) in page
    zh = write_certificate(res, tmp_path / "zh", lang="zh")["certificate.html"].read_text()
    assert html.escape(direct.coupling.note) not in zh
    assert COUPLING_TEXT[reason]["zh"].split("（")[0].split("：")[0] in zh
