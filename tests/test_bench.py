"""The virtual bench: truth recovery against closed forms, noise scatter against its prediction,
determinism, and the rotation-time limits of the protocol."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.bench.config import Bench, Harmonic, InstrumentConfig, TableConfig
from gonio.specs.ogam_draft.bench.session import mount_scale_factor_counts_per_deg
from gonio.specs.ogam_draft.items import compute_characteristics
from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import parse_readings, write_readings
from gonio.specs.ogam_draft.protocol import load_protocol, parse_protocol

K_NOM = 76434.87


def small_protocol(series=2, rounds=12, step=30.0, compensation="measured"):
    """7.1 and 7.4 only, as a laboratory would write a reduced protocol."""
    return parse_protocol({
        "protocol": {"name": "small"},
        "session": {"earth_compensation": compensation, "static_s": 60.0},
        "scale_factor": {"rounds": [{"stop_deg": 60.0 * i} for i in range(1, 7)],
                         "read_delay_s": 5.0, "rest_s": 20.0},
        "angle_deviation": {"series": series, "rest_s": 20.0, "read_delay_s": 10.0,
                            "rounds": [{"stop_deg": step * i} for i in range(1, rounds + 1)]},
    })


def ideal_bench(**inst) -> Bench:
    base = dict(type="rlg", nominal_scale_factor_counts_per_deg=K_NOM, quantisation=False,
                counter_bits=64)
    base.update(inst)
    return Bench(name="ideal", instrument=InstrumentConfig(**base), table=TableConfig(),
                 latitude_deg=90.0, sample_rate_hz=200.0)


def through_files(result):
    """Readings as a laboratory file would carry them (write, then parse)."""
    import io
    import tempfile
    import pathlib

    d = pathlib.Path(tempfile.mkdtemp())
    write_readings(result.readings, d / "r.csv", result.metadata)
    return parse_readings((d / "r.csv").read_text(), path=d / "r.csv")


def test_truth_recovery_scale_factor_and_deviation_closed_form():
    # At the pole with the axis up the Earth rate lies along the table axis: the
    # measured compensation removes it exactly, and a tilt is a pure cos ψ factor.
    psi, err_ppm = 0.3, 2.0
    h = (Harmonic(1, 0.4, 20.0), Harmonic(3, 0.2, 100.0))
    bench = ideal_bench(tilt_deg=psi, scale_factor_error_ppm=err_ppm, position_harmonics=h)
    res = run_session(small_protocol(series=1), bench, seed=3)
    out = compute_characteristics(through_files(res))
    # Closed form: counts C = K_true (θ cos ψ + g(θ cos ψ)/3600), g the position harmonics.
    k_true = K_NOM * (1 + 1e-6 * err_ppm)
    c = math.cos(math.radians(psi))

    def g(x_deg):       # the position error vanishes at zeroing: g(x) − g(0)
        return g_raw(x_deg) - g_raw(0.0)

    def g_raw(x_deg):
        return sum(hh.amplitude_arcsec * math.sin(hh.order * math.radians(x_deg)
                                                   + math.radians(hh.phase_deg)) for hh in h)

    sf_theta = [60.0 * i for i in range(1, 7)]
    counts = [k_true * (th * c + g(th * c) / 3600.0) for th in sf_theta]
    k_expected = sum(ci / th for ci, th in zip(counts, sf_theta)) / 6
    assert out.scale_factor.value == pytest.approx(k_expected, rel=1e-9)
    kl = (max(ci / th for ci, th in zip(counts, sf_theta))
          - min(ci / th for ci, th in zip(counts, sf_theta))) / k_expected * 100
    assert out.scale_factor_nonlinearity.value == pytest.approx(kl, rel=1e-6)
    ad = out.angle_deviation.table
    for _, row in ad.iterrows():
        th = row["position_deg"]
        e_expected = (k_true * (th * c + g(th * c) / 3600.0) / k_expected - th) * 3600.0
        assert row["E_arcsec"] == pytest.approx(e_expected, abs=1e-6)


def test_truth_recovery_matches_truth_json():
    bench = ideal_bench(tilt_deg=0.2, scale_factor_error_ppm=-1.0)
    res = run_session(small_protocol(series=1), bench, seed=1)
    out = compute_characteristics(through_files(res))
    # K equals the true scale factor as seen through the mount, to 1e-9 relative.
    assert out.scale_factor.value == pytest.approx(
        mount_scale_factor_counts_per_deg(bench, 60.0), rel=1e-9)
    assert out.scale_factor.value == pytest.approx(
        K_NOM * (1 - 1e-6) * math.cos(math.radians(0.2)), rel=1e-9)
    truth = pd.DataFrame(res.truth["readings"])
    t = truth[truth.test == "angle_deviation"].set_index("round")
    for _, row in out.angle_deviation.table.iterrows():
        assert row["E_arcsec"] == pytest.approx(
            t.loc[row["round"], "systematic_deviation_calibrated_arcsec"], abs=1e-6)
        assert abs(row["E_arcsec"]) < 1e-6      # nothing systematic on this bench


def test_noise_scatter_matches_prediction():
    """With ARW, quantisation and table scatter on, E_ij − truth scatters as predicted."""
    arw = 0.002                                    # °/√h, large so that it dominates
    bench = ideal_bench(arw_dpsh=arw, quantisation=True)
    bench = replace(bench, table=TableConfig(positioning_random_arcsec=0.02))
    proto = small_protocol(series=4)
    z = []
    for seed in range(12):
        res = run_session(proto, bench, seed=seed)
        rd = res.readings
        tr = pd.DataFrame(res.truth["readings"])
        m = (rd.test == "angle_deviation").to_numpy()
        k = K_NOM                                  # compare counts in a fixed unit
        # Prediction (independent closed form): ARW over the time since zeroing, the
        # compensation rate's ARW error over the 60 s static phase, quantisation of two
        # counter readings and one rounding, the table scatter at zero and stop.
        t = rd.time_s[m].to_numpy()
        n_deg = arw / 60.0
        var_deg2 = n_deg ** 2 * t + n_deg ** 2 * t ** 2 / 60.0 + (3 / 12) / k ** 2
        zz = ((rd.gyro_counts[m].to_numpy() - tr.noise_free_counts[m].to_numpy()) / k) \
            / np.sqrt(var_deg2)
        z.append(zz)
    z = np.concatenate(z)
    assert abs(z.mean()) < 4 * 1 / math.sqrt(z.size) * 3   # correlated within a series
    assert 0.85 < z.std() < 1.15


def test_same_seed_same_bytes(tmp_path):
    from gonio.specs.ogam_draft.bench import write_session

    bench = load_bench("rlg")
    proto = small_protocol(series=1)
    bench = replace(bench, sample_rate_hz=100.0)
    a = write_session(run_session(proto, bench, seed=7), tmp_path / "a")
    b = write_session(run_session(proto, bench, seed=7), tmp_path / "b")
    c = write_session(run_session(proto, bench, seed=8), tmp_path / "c")
    assert a["readings"].read_bytes() == b["readings"].read_bytes()
    assert a["truth"].read_bytes() == b["truth"].read_bytes()
    assert a["readings"].read_bytes() != c["readings"].read_bytes()


def test_write_session_refuses_to_replace_readings_as_the_cli_does(tmp_path):
    """The Python API refuses what ``gonio simulate --out`` refuses: an existing readings or
    truth file (a laboratory's, or an earlier run's) is replaced only with ``force``."""
    from gonio.specs.ogam_draft.bench import write_session

    bench = replace(load_bench("rlg"), sample_rate_hz=100.0)
    s7 = run_session(small_protocol(series=1), bench, seed=7)
    s8 = run_session(small_protocol(series=1), bench, seed=8)
    first = write_session(s7, tmp_path / "run")["readings"].read_bytes()
    with pytest.raises(GonioError, match="readings.csv exists"):
        write_session(s8, tmp_path / "run")
    assert (tmp_path / "run" / "readings.csv").read_bytes() == first       # untouched
    lab = tmp_path / "lab"
    lab.mkdir()
    (lab / "truth.json").write_text("{}")                  # a file gonio did not write
    with pytest.raises(GonioError, match="truth.json exists"):
        write_session(s8, lab)
    assert not (lab / "readings.csv").exists() and (lab / "truth.json").read_text() == "{}"
    again = write_session(s8, tmp_path / "run", force=True)["readings"].read_bytes()
    assert again != first


def test_rotation_time_limit_enforced():
    bench = replace(load_bench("rlg"), table=TableConfig(accel_dps2=5.0))
    with pytest.raises(GonioError, match="scale_factor.rounds"):
        run_session(load_protocol("ogam-draft"), bench, seed=0)


def test_earth_rate_compensation_needed():
    """Without compensation a 40° N axis-up session shows the Earth rate: ~9.7″ per second."""
    bench = replace(ideal_bench(), latitude_deg=40.0)
    res = run_session(small_protocol(series=1, compensation="none"), bench, seed=0)
    rd = res.readings
    m = rd.test == "angle_deviation"
    e = (rd.gyro_counts[m] / K_NOM - rd.table_deg[m]) * 3600
    rate = (e / rd.time_s[m]).to_numpy()
    expected = 7.292115e-5 * math.sin(math.radians(40.0)) * 180 / math.pi * 3600
    # The compensation-free error grows at the Earth rate on the axis (plus the K
    # mismatch of no scale-factor correction, nil here).
    assert np.allclose(rate, expected, rtol=1e-6)
    res2 = run_session(small_protocol(series=1, compensation="measured"), bench, seed=0)
    rd2 = res2.readings
    e2 = (rd2.gyro_counts[m] / K_NOM - rd2.table_deg[m]) * 3600
    assert np.abs(e2).max() < 1e-6


def test_fog_rectangle_integration_error_is_bounded():
    """FOG: the rectangle rule at a finite sample rate leaves an error of order a·Δt²."""
    base = ideal_bench(type="fog", integration="rectangle")
    res = run_session(small_protocol(series=1), replace(base, sample_rate_hz=100.0), seed=0)
    rd = res.readings
    m = (rd.test == "angle_deviation").to_numpy()
    e = (rd.gyro_counts[m] / K_NOM - rd.table_deg[m]) * 3600
    a, dt = 60.0, 0.01
    assert np.abs(e).max() < 4 * a * dt * dt * 3600          # four corners per move
    assert np.abs(e).max() > 1e-6                              # and it is not zero
