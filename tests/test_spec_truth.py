"""``SPEC.truth`` of the optical draft and the triad alignment (issue 23): the true values come
from the bench's physical parameters, never from the estimators — a noise-free calibration
on an ideal bench finds them, and the truth does not move when the estimators are broken."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gonio.specs import get
from gonio.units import deg_to_arcsec


def _ogam_noise_free():
    from gonio.specs.ogam_draft.bench import load_bench, run_session
    from gonio.specs.ogam_draft.readings import Readings
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.study import ideal_bench

    bench = replace(ideal_bench(load_bench("rlg")), sample_rate_hz=20.0)
    proto = load_protocol("ogam-draft")
    res = run_session(proto, bench, seed=0)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    from gonio.specs.ogam_draft.calibration import analyse
    rep = analyse(Readings(df, dict(res.metadata)), proto,       # the analysis objects
                  static_record=res.static_record)
    return bench, proto, res, rep


def test_ogam_truth_is_what_a_noise_free_calibration_finds(monkeypatch):
    bench, proto, res, rep = _ogam_noise_free()
    truth = get("ogam-draft").truth(bench, proto)
    assert set(truth) == {"scale_factor", "scale_factor_nonlinearity", "zero_stability",
                          "angle_deviation"}
    items = rep.result().items
    # K and K_l: the noise-free 7.1 on an error-free table is the bench's K through the mount;
    # K_l as the draft reads it (the range as measured: no error to correct for here)
    assert items["scale_factor"].value == pytest.approx(truth["scale_factor"]["value"],
                                                        rel=1e-12)
    kl = items["scale_factor_nonlinearity"].details["estimates"]["draft"]["value"]
    assert kl == pytest.approx(truth["scale_factor_nonlinearity"]["value"], rel=1e-12)
    assert truth["scale_factor_nonlinearity"]["value"] > 0       # the instrument's own K_l
    assert items["zero_stability"].value == pytest.approx(truth["zero_stability"]["value"],
                                                          abs=1e-12)
    # E: the truth is referred to the mount's true K, the calibration to its own K from 7.1;
    # per point they differ by exactly the scale-factor term (K_mount/K_cal − 1)·angle
    pts = rep.results.angle_deviation.table
    k_mount = float(res.truth["scale_factor_through_mount_counts_per_deg"])
    k_cal = float(rep.results.scale_factor.value)
    term = deg_to_arcsec((k_mount / k_cal - 1.0) * pts["position_deg"].to_numpy(float))
    got = pts["E_arcsec"].to_numpy(float) - np.asarray(truth["angle_deviation"]["points"])
    assert np.abs(term).max() > 1e-3                             # the check has something to see
    np.testing.assert_allclose(got, term, atol=1e-6)
    # never through an estimator: breaking them leaves the truth as it was
    import gonio.specs.ogam_draft.items as items_mod

    def broken(*a, **k):
        raise AssertionError("the truth called an estimator")
    for name in ("scale_factor", "scale_factor_nonlinearity", "zero_stability",
                 "angle_deviation", "compute_characteristics"):
        monkeypatch.setattr(items_mod, name, broken)
    assert get("ogam-draft").truth(bench, proto) == truth


def _triad_noise_free():
    from gonio.specs.triad_alignment.bench import load_triad_bench, load_triad_protocol, run_alignment_session
    from gonio.specs.triad_alignment.readings import TriadReadings

    b = load_triad_bench("mems-triad")
    b = replace(b, arw_deg_sqrt_h=(0.0,) * 3, bias_instability_dph=(0.0,) * 3,
                rate_random_walk_dph_sqrt_h=(0.0,) * 3)
    p = load_triad_protocol("triad-alignment")
    s = run_alignment_session(p, b, 0)
    df = s.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    return b, p, get("triad-alignment").calibrate(TriadReadings(df, s.metadata, None))


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_triad_truth_is_what_a_noise_free_calibration_finds(monkeypatch):
    b, p, result = _triad_noise_free()
    truth = get("triad-alignment").truth(b, p)
    alignment = {k: t for k, t in truth.items() if k.split("_")[0] in ("M", "b", "S", "L")
                 and k.count("_") == 1}
    assert len(alignment) == 9 + 3 + 6 + 6
    # the thermal values of the programme's one gyro (up +z): K, b at 8 set points × 3
    # supply levels, ARW at the 8 set points
    assert len(truth) == len(alignment) + 8 * 3 * 2 + 8
    for key, t in alignment.items():
        assert result.items[key].value == pytest.approx(t["value"], rel=1e-11, abs=1e-13), key
    assert truth["M_xy"]["value"] != 0 and truth["b_y"]["value"] != 0
    import gonio.specs.triad_alignment.analysis as an

    def broken(*a, **k):
        raise AssertionError("the truth called the estimator")
    monkeypatch.setattr(an, "estimate_alignment", broken)
    assert get("triad-alignment").truth(b, p) == truth


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_triad_thermal_truth_is_what_a_noise_free_identification_finds(monkeypatch):
    """SPEC.truth holds K and b at the programme's set points and supply levels (closed form
    from the bench's polynomials in the die's temperature,
    :func:`gonio.specs.triad_alignment.bench.true_thermal_coefficients`); the built-in chamber programme with
    settled soaks on a noise-free bench, identified with the bench's orders or with the
    orders BIC chooses, finds every one to 1e-9 (the model, fed with the sensor's reading,
    evaluated where the sensor reads the soaked set point); a noise-free record has no white
    noise, so ARW is checked on the noisy bench in the coverage study."""
    from gonio.specs.triad_alignment.bench import load_triad_bench, load_triad_protocol, run_thermal_session
    from gonio.specs.triad_alignment.readings import TriadReadings
    from gonio.specs.triad_alignment.calibration import thermal_items
    from gonio.specs.triad_alignment.thermal_model import identify_thermal_model

    b = load_triad_bench("mems-triad")
    b = replace(b, arw_deg_sqrt_h=(0.0,) * 3, bias_instability_dph=(0.0,) * 3,
                rate_random_walk_dph_sqrt_h=(0.0,) * 3,
                thermal=replace(b.thermal, sensor_noise_c=0.0))
    p = load_triad_protocol("triad-alignment")
    # soaks of 24 τ_th: settled to e⁻²⁴ (the built-in 1800 s = 6 τ leaves the die drifting
    # by ~e⁻⁶ of the step during the dwells: a real, 1e-5-relative error of the programme)
    settled = replace(p, thermal=dict(p.thermal, soak_s=7200.0))
    s = run_thermal_session(settled, b, 0)
    r = TriadReadings(s.readings.assign(line=np.arange(len(s.readings)) + 2), s.metadata, None)
    truth = get("triad-alignment").truth(b, p)
    for fixed in ({"scale": (2, 1), "bias": (3, 1)}, None):
        th = identify_thermal_model(r, fixed_orders=fixed, ramps=False)
        items = {k: it for k, it in thermal_items(th, "").items() if not k.startswith("ARW")}
        assert len(items) == 8 * 3 * 2
        for key, it in items.items():
            assert it.value == pytest.approx(truth[key]["value"], rel=1e-9, abs=1e-12), key
            assert it.details["setpoint_c"] == sorted(p.thermal["setpoints_c"])[
                int(key.split("_")[2][1:]) - 1], key
    # the points differ: the truth is no constant the estimate could match by accident
    assert len({round(truth[f"b_z_t{i}_v2"]["value"], 9) for i in range(1, 9)}) == 8
    import gonio.specs.triad_alignment.thermal_model as tm

    def broken(*a, **k):
        raise AssertionError("the truth called the estimator")
    monkeypatch.setattr(tm, "identify_thermal_model", broken)
    monkeypatch.setattr(tm, "fit_polynomial", broken)
    assert get("triad-alignment").truth(b, p) == truth
