"""Issue 12, defect 6: the default equal-division example on the virtual bench.

The bench's table has known positioning harmonics; the instrument is tilted 0.05° at
40.2° N, so the tilt × Earth-rate coupling reaches ~1.3″ on the longest readings — ten
times the table's error. Estimated as a nuisance, the table error agrees with the truth
within U = t_95(ν)·u at ≥ 95 % of positions over 20 seeds; the plain fit does not.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
from gonio.specs.ogam_draft.equal_division import (analyse_eda_readings, coupling_design,
                                           load_eda_protocol)
from gonio.specs.ogam_draft.protocol import load_protocol


def _truth(bench, res):
    """Table error (indicated − true) at the grid, closure gauge, observable orders only."""
    x = res.table_position_deg
    obs = tuple(h for h in bench.table.positioning_harmonics if h.order % res.n_starts)
    t = harmonic_sum_arcsec(x, obs)
    return t - t.mean()


@pytest.mark.slow
def test_default_eda_example_table_within_U_over_20_seeds():
    proto = load_protocol("eda")
    ep = load_eda_protocol()
    bench = replace(load_bench("rlg"), sample_rate_hz=50.0)
    inside, inside_plain, amps = [], [], []
    for seed in range(20):
        run = run_session(proto, bench, seed=seed)
        kw = dict(latitude_deg=bench.latitude_deg, tilt_bound_deg=0.1,
                  compensation_time_s=proto.session.static_s,
                  table_accel_dps2=bench.table.accel_dps2)
        res = analyse_eda_readings(run.readings, ep, **kw)
        assert res.coupling.separable
        U = stats.t.ppf(0.975, res.dof) * res.table_u_arcsec
        inside.append(np.abs(res.table_error_arcsec - _truth(bench, res)) <= U)
        amps.append(res.coupling.amplitude_arcsec_s)
        plain = analyse_eda_readings(run.readings, ep, coupling=False)
        Up = stats.t.ppf(0.975, plain.dof) * plain.table_u_arcsec
        inside_plain.append(np.abs(plain.table_error_arcsec - _truth(bench, plain)) <= Up)
    frac = float(np.mean(inside))
    assert frac >= 0.95, frac
    # The coupling estimate is the bench's: Ω_⊥ tan ψ = 15.041″/s·cos 40.2°·tan 0.05°.
    omega = 15.041067 * np.cos(np.radians(bench.latitude_deg))
    expect = omega * np.tan(np.radians(bench.instrument.tilt_deg))
    assert abs(np.mean(amps) / expect - 1) < 0.05, (np.mean(amps), expect)
    # The test can fail: without the nuisance the table is biased (issue 12, defect 6).
    assert float(np.mean(inside_plain)) < 0.5


def _pq_by_quadrature(grid, pos_deg, t_read, x0_deg):
    """∫₀^t (cos θ − cos x₀) dt and the same with sin, for each reading time, on the grid."""
    out = []
    for tj in t_read:
        sel = grid <= tj
        th, g = np.radians(pos_deg[sel]), grid[sel]
        out.append((np.trapezoid(np.cos(th) - np.cos(np.radians(x0_deg)), g),
                    np.trapezoid(np.sin(th) - np.sin(np.radians(x0_deg)), g)))
    return np.array(out)


def test_coupling_design_against_quadrature_of_the_tables_motion():
    """P, Q of coupling_design equal ∫(cos θ − cos x_k) dt of the table's real rest-to-rest
    motion (30° at 60 °/s² is a triangular profile of 2·sqrt(0.5) = 1.41 s; at constant
    rate a 0.5 s ramp), integrated on a fine grid; the constant-rate design is measurably
    off for the accelerating table."""
    a, step, delay, x0 = 60.0, 30.0, 5.0, 60.0
    t = np.array([[11.0, 23.0, 35.5]])
    dur = 2.0 * np.sqrt(step / a)
    ends = t[0] - delay
    grid = np.linspace(0.0, t[0, -1], 2_000_001)
    pos, ramp = np.full_like(grid, x0), np.full_like(grid, x0)
    for i, e in enumerate(ends):
        s = np.clip(grid - (e - dur), 0.0, dur)
        moved = np.where(s < dur / 2, 0.5 * a * s ** 2, step - 0.5 * a * (dur - s) ** 2)
        pos = np.where(grid >= e - dur, x0 + step * i + moved, pos)
        r = np.clip(grid - (e - step / 60.0), 0.0, step / 60.0) * 60.0
        ramp = np.where(grid >= e - step / 60.0, x0 + step * i + r, ramp)
    C_acc = coupling_design(t, [x0], step, delay, 60.0, a)[0]
    C_const = coupling_design(t, [x0], step, delay, 60.0)[0]
    exact_acc = _pq_by_quadrature(grid, pos, t[0], x0)
    assert np.allclose(C_acc, exact_acc, atol=1e-4, rtol=0)
    assert np.allclose(C_const, _pq_by_quadrature(grid, ramp, t[0], x0), atol=1e-4, rtol=0)
    assert np.abs(C_const - exact_acc).max() > 0.05


def test_says_when_coupling_cannot_be_estimated():
    """Without time_s the coupling cannot be estimated: the result and the CLI text say
    so, with its size at the tilt bound."""
    import pandas as pd

    from gonio.specs.ogam_draft.commands import eda_text as _text

    rows = [{"test": "equal_division", "series": 1, "round": k + 1, "table_deg": 90.0 * j,
             "gyro_deg": 90.0 * j + 1e-5 * (j % 3), "start_deg": 90.0 * k}
            for k in range(4) for j in range(1, 5)]
    res = analyse_eda_readings(pd.DataFrame(rows), load_eda_protocol(), latitude_deg=40.0,
                               tilt_bound_deg=0.1)
    assert not res.coupling.separable and res.coupling.max_effect_arcsec > 0
    assert res.to_dict()["coupling"]["separable"] is False
    out = _text(res)
    assert "WARNING: the coupling cannot be estimated" in out and "″ at the tilt bound" in out


def test_gonio_eda_on_the_default_example(tmp_path, capsys):
    """`gonio simulate --protocol eda` then `gonio eda`, from the outside: the coupling is
    estimated and the table error agrees with the bench's truth within U."""
    import json

    from gonio.specs.ogam_draft.bench import write_session
    from gonio.cli import main

    proto = load_protocol("eda")
    bench = replace(load_bench("rlg"), sample_rate_hz=50.0)
    write_session(run_session(proto, bench, seed=7), tmp_path)
    capsys.readouterr()
    assert main(["eda", str(tmp_path / "readings.csv"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["coupling"]["separable"] is True and out["coupling"]["max_effect_arcsec"] > 0.5
    x = np.array(out["table"]["position_deg"])
    obs = tuple(h for h in bench.table.positioning_harmonics if h.order % out["n_starts"])
    t = harmonic_sum_arcsec(x, obs)
    err = np.array(out["table"]["error_arcsec"]) - (t - t.mean())
    U = stats.t.ppf(0.975, out["dof"]) * np.array(out["table"]["u_arcsec"])
    assert np.mean(np.abs(err) <= U) >= 10 / 12
    assert main(["eda", str(tmp_path / "readings.csv")]) == 0
    assert "coupling (estimated, removed)" in capsys.readouterr().out
