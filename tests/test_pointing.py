"""Pointing consistency (draft 7.7) on the virtual bench: zero within noise with a correct
compensation; with a wrong latitude or azimuth in the computed compensation, the spread that
the closed-form residual (gonio.specs.ogam_draft.compensation) predicts."""

from __future__ import annotations

import math
import pathlib
import tempfile

import numpy as np
import pytest

from gonio.specs.ogam_draft.bench import run_session
from gonio.specs.ogam_draft.bench.config import Bench, InstrumentConfig, TableConfig
from gonio.specs.ogam_draft.items import compute_characteristics
from gonio.specs.ogam_draft.compensation import measured_compensation, pointing_consistency_prediction
from gonio.specs.ogam_draft.readings import parse_readings, write_readings
from gonio.specs.ogam_draft.protocol import parse_protocol

K_NOM = 76434.87
LAT = 40.0
ROUNDS = [{"stop_deg": 60.0 * i} for i in range(1, 7)]


def protocol(compensation, **session):
    return parse_protocol({
        "protocol": {"name": "pointing"},
        "session": {"earth_compensation": compensation, "static_s": 30.0, **session},
        "angle_deviation": {"series": 1, "rest_s": 12.0, "read_delay_s": 10.0, "rounds": ROUNDS},
        "pointing_consistency": {"orientations": ["up", "north", "east"], "series": 1,
                                 "rest_s": 12.0, "read_delay_s": 10.0},
    })


def bench(**inst):
    base = dict(type="rlg", nominal_scale_factor_counts_per_deg=K_NOM, quantisation=False)
    base.update(inst)
    return Bench("b", InstrumentConfig(**base), TableConfig(), latitude_deg=LAT,
                 sample_rate_hz=100.0)


def pointing(result):
    d = pathlib.Path(tempfile.mkdtemp())
    write_readings(result.readings, d / "r.csv", result.metadata)
    r = parse_readings((d / "r.csv").read_text(), path=d / "r.csv")
    # No 7.1 rows: counts become angles with the nominal K (= the true K on this bench).
    res = compute_characteristics(r, nominal_scale_factor_counts_per_deg=K_NOM)
    c = res.pointing_consistency
    assert c.measured, c.reason
    return c


def times_of(result):
    rd = result.readings
    return rd[rd.test == "angle_deviation"]["time_s"].to_numpy()


@pytest.mark.parametrize("session,label", [
    ({"compensation_latitude_deg": LAT + 1.0}, "latitude 1° off"),
    ({"compensation_latitude_deg": LAT - 1.0}, "latitude 1° off, south"),
    ({"compensation_azimuth_error_deg": 1.0}, "azimuth 1° off"),
    ({"compensation_azimuth_error_deg": -2.0}, "azimuth 2° off"),
])
def test_wrong_computed_compensation_gives_the_predicted_spread(session, label):
    res = run_session(protocol("computed", **session), bench(), seed=0)
    c = pointing(res)
    pred = pointing_consistency_prediction(
        LAT, times_of(res),
        compensation_latitude_deg=session.get("compensation_latitude_deg"),
        azimuth_error_deg=session.get("compensation_azimuth_error_deg", 0.0))
    table = c.table.set_index("orientation")
    for g in ("up", "north", "east"):
        assert table.loc[g, "E_arcsec"] == pytest.approx(pred.deviation_arcsec[g], abs=1e-6), g
    pts = c.tables["points"]
    for g in ("up", "north", "east"):
        e = pts[pts.orientation == g].sort_values("round")["E_arcsec"].to_numpy()
        np.testing.assert_allclose(e, pred.points_arcsec[g], atol=1e-6)
    assert c.details["spread_arcsec"] == pytest.approx(pred.spread_arcsec, abs=1e-6)
    assert pred.spread_arcsec > 1.0          # several arcsec: far outside the 0.30″ budget
    assert c.value == pytest.approx(pred.spread_arcsec / c.details["reference_angle_arcsec"] * 100)


def test_correct_computed_compensation_gives_zero_spread():
    c = pointing(run_session(protocol("computed"), bench(), seed=0))
    assert abs(c.details["spread_arcsec"]) < 1e-6


@pytest.mark.parametrize("compensation", ["measured", "computed"])
def test_correct_compensation_is_zero_within_noise(compensation):
    arw, static = 0.0005, 30.0
    z_all, spreads, sig = [], [], []
    for seed in range(6):
        res = run_session(protocol(compensation), bench(arw_dpsh=arw, quantisation=True),
                          seed=seed)
        c = pointing(res)
        t = times_of(res)
        n = arw / 60.0 * 3600.0                               # ″/√s
        comp_u = measured_compensation(static, arw_dpsh=arw,
                                       scale_factor_counts_per_deg=K_NOM).u_rate_arcsec_s
        # Prediction: ARW over t, the compensation's error × t (measured only), and the
        # quantisation of two counter readings and one rounding (1 count = 3600/K ″).
        var = n ** 2 * t + (comp_u * t) ** 2 * (compensation == "measured") \
            + 0.25 * (3600.0 / K_NOM) ** 2
        pts = c.tables["points"]
        for g in ("up", "north", "east"):
            e = pts[pts.orientation == g].sort_values("round")["E_arcsec"].to_numpy()
            z_all.append(e / np.sqrt(var))
        spreads.append(c.details["spread_arcsec"])
        sig.append(math.sqrt(var.max()))
    z = np.concatenate(z_all)
    assert np.all(np.abs(z) < 4.5)
    assert 0.6 < z.std() < 1.4                  # correlated within a series: loose
    assert max(spreads) < 4 * 2 * max(sig)      # max − min of three extremes
    # ... whereas a 1° latitude error would show several arcsec:
    pred = pointing_consistency_prediction(LAT, t, compensation_latitude_deg=LAT + 1.0)
    assert pred.spread_arcsec > 10 * max(spreads)
