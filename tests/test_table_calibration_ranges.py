"""A calibrated rotary table for K_l (7.2), C_v (7.6) and C_g (7.7): their readings corrected by
the same per-round correction as K (e(stop) − e(zero) at each round's positions, angles read
with the table-corrected K) and their table draws the calibration's in place of the MPE.

Checked against truths outside the estimator: on a noise-free, untilted bench whose table has
a periodic error, with an exact calibration, the draft's functionals of the corrected readings
equal the items' truths computed from the bench's physical parameters (the instrument's own
K_i, :func:`scale_factor_truth`; the noise-free deviations of the bench's rerun read with the
7.1 K's truth), while the uncorrected are off by the table's error; a calibration with its
errors' sign flipped moves them further off; a calibration that lacks one position C_v and C_g
use keeps their MPE lines (and says so) while K_l is corrected. The propagated table draws are
checked against a Monte Carlo of the correction itself."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from gonio.formats.toml import read_toml
from gonio.resources import resolve
from gonio.specs.ogam_draft.bench import TableConfig, load_bench, run_session
from gonio.specs.ogam_draft.bench.config import Harmonic
from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.item_coverage import scale_factor_truth
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.study import table_positions_deg, tilted
from gonio.specs.ogam_draft.table_calibration import TableCalibration

HARMONICS = (Harmonic(1, 0.04, 30.0), Harmonic(3, 0.05, 70.0))
RANGES = (("scale_factor_nonlinearity", None, None), ("rate_consistency", "rate_dps", 1e6),
          ("pointing_consistency", "orientation", 100.0))
#: |corrected − truth| allowed, and the least |uncorrected − truth| (the table's error shows),
#: per item in its unit (%, ppm, %): K_l 1 ppb of K (the table moves it 0.3 ppm); C_v 0.002 ppm
#: (2.6 mas over 360°; the table moves it 0.04 ppm); C_g 1e-9 % (0.013 mas; the table moves it
#: 1.1e-8 %, the orientations differing only by the Earth rate's axis component).
TIGHT = {"scale_factor_nonlinearity": 1e-7, "rate_consistency": 0.002,
         "pointing_consistency": 1e-9}
OFF = {"scale_factor_nonlinearity": 1e-5, "rate_consistency": 0.02,
       "pointing_consistency": 5e-9}


def _protocol():
    raw = read_toml(resolve("ogam-draft", "protocol"))
    for key in ("zero_stability", "tilt_estimate"):
        raw.pop(key, None)
    return parse_protocol(raw, resolve("ogam-draft", "protocol"))


@pytest.fixture(scope="module")
def setup():
    """The protocol (7.1, 7.2, 7.4–7.7), a noise-free untilted bench whose table has the
    test's harmonics, its session, and an exact calibration (u 0.02″) at every position."""
    p = _protocol()
    base = replace(load_bench("rlg"), sample_rate_hz=5.0)
    clean = tilted(replace(base.random_off(), table=TableConfig(
        accel_dps2=base.table.accel_dps2, mpe_arcsec=0.1, positioning_harmonics=HARMONICS)),
        0.0, 0.0)
    res = run_session(p, clean, seed=0)
    x = table_positions_deg(p)
    cal = TableCalibration(x, harmonic_sum_arcsec(x, HARMONICS), np.full(x.size, 0.02), "tc.csv")
    return p, res, cal


def _analyse(p, res, cal=None):
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    return analyse(Readings(df, dict(res.metadata)), p, table_calibration=cal)


@pytest.fixture(scope="module")
def runs(setup):
    p, res, cal = setup
    x = cal.table_deg
    flip = TableCalibration(x, -cal.error_arcsec, cal.u_arcsec, "flip.csv")
    return {"raw": _analyse(p, res), "cal": _analyse(p, res, cal),
            "flip": _analyse(p, res, flip)}


def _truths(res, rep) -> dict:
    """Each item's truth from the bench's parameters: K_l of the instrument's own K_i
    (:func:`scale_factor_truth`); C_v, C_g the spread of the noise-free per-condition extremes
    at the result's points, each deviation read with the 7.1 K's truth (as the items read
    their angles with the 7.1 K), over the reference angle."""
    _, k_i = scale_factor_truth(res.truth)
    out = {"scale_factor_nonlinearity": float((k_i.max() - k_i.min()) / k_i.mean() * 100.0)}
    for name, col, scale in RANGES[1:]:
        e = list(_truth_e_v(res, rep, name, col).values())
        ref = getattr(rep.results, name).details["reference_angle_arcsec"]
        out[name] = float((max(e) - min(e)) / ref * scale)
    return out


def _measured(rep, name) -> float:
    """The draft's functional of the readings the stated value is built from: the corrected
    readings' (results.json ``details.table_calibration.measured_value``) where corrected."""
    d = rep.result().to_json()["items"][name]["details"]
    tc = d.get("table_calibration")
    return float(tc["measured_value"]) if tc else float(d["estimates"]["draft"]["value"])


def test_ranges_noise_free_exact_calibration(setup, runs):
    """The corrected K_l, C_v, C_g (the draft's functional of the corrected readings) equal the
    bench's truths within TIGHT, the uncorrected are off by more than OFF; the stated budget's
    lines are the calibration's (no K_tab, no MPE), and the draft's reading at the MPE is kept
    beside, unchanged by the calibration."""
    _, res, _ = setup
    raw, rep = runs["raw"], runs["cal"]
    truth = _truths(res, rep)
    for name, _, _ in RANGES:
        got, before = _measured(rep, name), _measured(raw, name)
        assert abs(got - truth[name]) < TIGHT[name], (name, got, truth[name])
        assert abs(before - truth[name]) > OFF[name], (name, before, truth[name])
        b, b_raw = rep.item_uncertainty[name], raw.item_uncertainty[name]
        # the stated value is built from that range (its line's Monte Carlo names it, 4 digits)
        stated_from = float(re.search(r"measured range (\S+) ", b.components[0].source)[1])
        assert stated_from == pytest.approx(got, rel=1e-3, abs=1e-12)
        assert [c.symbol for c in b.components][0] in ("K_rng", "C_rng")
        assert "K_tab" not in [c.symbol for c in b.components]
        assert "table calibration, tc.csv" in b.components[0].source
        assert "table calibration" not in " ".join(c.source for c in b_raw.components)
        assert b.beside.value == b_raw.beside.value and b.beside.U == b_raw.beside.U
        d = rep.result().to_json()["items"][name]["details"]
        assert d["stated"] == "table_corrected" and d["table_calibration"]["source"] == "tc.csv"
        assert d["table_calibration"]["uncorrected_value"] == pytest.approx(
            raw.result().to_json()["items"][name]["details"]["estimates"]["draft"]["value"])
    assert any(n.startswith("C_g corrected by the table calibration") for n in rep.budget_notes)


def test_ranges_sign_flipped_calibration_worse(setup, runs):
    """A calibration with its errors' sign flipped applies the table's error twice: each item
    is off its truth by at least as much as uncorrected (a range: the doubled error may move
    an extreme, so by at least 0.9 of it), far beyond the exact calibration's miss; K_l by
    1.5 times the uncorrected miss (nearly twice: its extreme rounds keep their places)."""
    _, res, _ = setup
    truth = _truths(res, runs["cal"])
    for name, _, _ in RANGES:
        miss_raw = abs(_measured(runs["raw"], name) - truth[name])
        miss_flip = abs(_measured(runs["flip"], name) - truth[name])
        assert miss_flip > max(OFF[name], 0.9 * miss_raw), (name, miss_flip, miss_raw)
        assert miss_flip > 20 * abs(_measured(runs["cal"], name) - truth[name])
    kl = "scale_factor_nonlinearity"
    assert _measured(runs["flip"], kl) - truth[kl] > 1.5 * (_measured(runs["raw"], kl) - truth[kl])


def test_ranges_position_missing_keeps_mpe(setup, runs):
    """A calibration without 330° (a 7.6/7.7 point, none of K's): K and K_l are corrected, C_v
    and C_g keep their MPE readings exactly (as without a calibration) and say so in the
    notes, results.json and summary.txt."""
    from gonio.specs.ogam_draft.outputs import summary

    p, res, cal = setup
    keep = ~np.isclose(cal.table_deg, 330.0)
    part = TableCalibration(cal.table_deg[keep], cal.error_arcsec[keep], cal.u_arcsec[keep],
                            "part.csv")
    rep, raw = _analyse(p, res, part), runs["raw"]
    d = rep.result().to_json()
    assert d["items"]["scale_factor_nonlinearity"]["details"]["stated"] == "table_corrected"
    for name in ("rate_consistency", "pointing_consistency"):
        b, b_raw = rep.item_uncertainty[name], raw.item_uncertainty[name]
        assert b.value == b_raw.value and b.U == b_raw.U and b.interval == b_raw.interval
        det = d["items"][name]["details"]
        assert "table_calibration" not in det
        assert "part.csv does not cover 330 deg" in det["table_calibration_not_used"]
        sym = "C_v" if name == "rate_consistency" else "C_g"
        assert any("part.csv does not cover 330 deg" in n and f"{sym} keeps the MPE line" in n
                   for n in rep.budget_notes)
    text = summary(rep.result())
    assert "K_l too" in text and "C_v and C_g keep the table's MPE lines" in text


def test_calibrated_table_draws_against_monte_carlo(setup, runs):
    """The stated C_v's table draws (:class:`CalibratedTable`: δe(θ) − δe(z) and K's part) for
    correlated calibration errors against the correction itself redone per draw: K_c from
    the 7.1 counts and E at a 7.6 point from its counts, each with drawn calibration errors;
    the sd of E's shift per position agrees with the coefficients' cᵀVc."""
    from gonio.specs.ogam_draft.item_uncertainty import CalibratedTable, table_corrected_k_sensitivity

    p, res, cal0 = setup
    x = cal0.table_deg
    u = np.full(x.size, 0.02) + 0.01 * (np.arange(x.size) % 3)
    v = 0.3 ** np.abs(np.subtract.outer(np.arange(x.size), np.arange(x.size))) * np.outer(u, u)
    cal = TableCalibration(x, cal0.error_arcsec, u, "cov", cov_arcsec2=v)
    df = res.readings
    k_rows = df[df["test"] == "scale_factor"]
    th_k = k_rows["table_deg"].to_numpy(float)
    k_c, c_k, _ = table_corrected_k_sensitivity(k_rows["gyro_counts"] / th_k, th_k, th_k,
                                                np.zeros(th_k.size), cal)
    i_s = cal.lookup(th_k)[0]                       # the Monte Carlo's own look-up
    ct = CalibratedTable(cal, c_k, float(np.mean(k_c)))
    pos = np.array([30.0, 150.0, 330.0, 360.0])
    a = ct.coefficients(pos, 0.0)
    u_lin = np.sqrt(np.einsum("ij,jk,ik->i", a, v, a))
    draws = np.random.default_rng(7).multivariate_normal(cal.error_arcsec, v, 40_000)
    jz = int(cal.lookup([0.0])[0][0])
    kd = np.mean(k_rows["gyro_counts"].to_numpy(float)
                 / (th_k - (draws[:, i_s] - draws[:, [jz]]) / 3600.0), axis=1)
    counts = pos * float(np.mean(k_c))         # the counts of an exact turn read with K_c
    jp = cal.lookup(pos)[0]
    e = 3600.0 * (counts / kd[:, None] - (pos - (draws[:, jp] - draws[:, [jz]]) / 3600.0))
    assert np.std(e, axis=0) == pytest.approx(u_lin, rel=0.03)
    got = ct.draws(np.random.default_rng(8), 40_000) @ a.T
    assert np.std(got, axis=0) == pytest.approx(u_lin, rel=0.03)


def test_ranges_calibration_recorded(tmp_path):
    """``gonio calibrate --table-calibration FILE`` (the pipeline, DCC on) of a noise-free
    built-in session with an exact calibration file: results.json's K_l, C_v, C_g details
    name the file, its SHA-256 (hashlib, here) and the rows used; summary.txt says they are
    corrected; the DCC describes each with the file; the certificate cells (en, zh) name it."""
    from gonio.kit.render import labels
    from gonio.specs.ogam_draft.phrases import LABELS
    from gonio.specs.ogam_draft.stated import range_table_note
    from tests.test_table_calibration import _calibrate_with_table

    out, sha, d = _calibrate_with_table(tmp_path, replace(load_bench("rlg"), sample_rate_hz=5.0))
    dcc = next(out.glob("*.xml")).read_text(encoding="utf-8")
    for name, sym in (("scale_factor_nonlinearity", "K_l"), ("rate_consistency", "C_v"),
                      ("pointing_consistency", "C_g")):
        tc = d["items"][name]["details"]["table_calibration"]
        assert tc["sha256"] == sha and tc["source"] == "tc.csv"
        assert 0.0 in tc["positions_used"]["table_deg"]
        if name != "scale_factor_nonlinearity":
            assert 330.0 in tc["positions_used"]["table_deg"]      # a 7.6/7.7 point
        # K_l's K_i are counts over the corrected angle (nothing read with K); C_v's and C_g's
        # angles are read through the 7.1 K here (counts), with its table-corrected value
        what = "the 7.1 rounds" if sym == "K_l" else "readings"
        assert f"{sym} {what} corrected by the table calibration tc.csv" in dcc
        assert tc.get("read_with_table_corrected_k", False) is (sym != "K_l")
        for lang, word, k_word in (("en", "table calibration tc.csv", "table-corrected 7.1 K"),
                                   ("zh", "转台校准 tc.csv", "转台误差修正后的 7.1 K")):
            text = "".join(s if isinstance(s, str) else s.text
                           for s in range_table_note(d, name, labels(lang, LABELS)))
            assert word in text
            assert (k_word in text) is (sym != "K_l"), (lang, sym, text)
            assert "修正后的 K" not in text and "table-corrected K" not in text
        label = tc["label"] + d["items"][name]["details"]["estimates"]["corrected"]["label"]
        assert ("table-corrected 7.1 K" in label) is (sym != "K_l")
        assert "(and read with the table-corrected K)" not in label
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    assert "K_l, C_v and C_g too" in summary and "keep the table's MPE" not in summary


def test_calibrated_table_draws_at_absolute_stops():
    """Rounds zeroed at 90° (7.4's rounds moved, start_deg ≠ 0): a condition's extreme 30°
    turned was read with the table at 120°, 150° turned at 240°. With the calibration poor at
    120° and 240° (u 0.3″) and good elsewhere (0.01″) the stated C_v's ``C_rng`` u is the
    spread of the range redone per draw with the correction at the absolute stops,
    E_v + δe(z + θ_v) − δe(z) (closed form √(0.3² + 0.3²)″ for E_v far apart); the table's
    errors at 30° and 150° (0.01″), where a lookup by the angle turned reads, would give 0.014″.
    The K part (c_K) takes the angle turned: against the per-draw correction of K_c too."""
    from gonio.specs.ogam_draft.item_uncertainty import (CalibratedTable, ConditionDeviation,
                                                         consistency_corrected_budget)

    x = np.arange(0.0, 360.0, 30.0)
    u = np.where(np.isin(x, (120.0, 240.0)), 0.3, 0.01)
    cal = TableCalibration(x, np.zeros(x.size), u, "tc.csv")
    conds = [ConditionDeviation("10 deg/s", 2.0, 30.0, 1e-6, 1, zero_deg=90.0),
             ConditionDeviation("60 deg/s", 0.1, 60.0, 1e-6, 1, zero_deg=90.0),
             ConditionDeviation("100 deg/s", -2.0, 150.0, 1e-6, 1, zero_deg=90.0)]
    ref = 1296000.0
    b = consistency_corrected_budget("rate_consistency", conds, ref, 1e6, table_mpe_arcsec=0.1,
                                     drift_half_width_arcsec=0.0, table_cal=CalibratedTable(cal))
    d = np.random.default_rng(11).normal(0.0, u, (40_000, x.size))
    at = {a: int(np.flatnonzero(x == a)[0]) for a in x}
    e = np.array([c.e_arcsec + d[:, at[(c.zero_deg + c.position_deg) % 360.0]]
                  - d[:, at[c.zero_deg]] for c in conds])
    mc = float(np.std(e.max(axis=0) - e.min(axis=0))) * 1e6 / ref
    got = next(c.u for c in b.components if c.symbol == "C_rng")
    assert got == pytest.approx(mc, rel=0.05)
    assert mc == pytest.approx(np.hypot(0.3, 0.3) * 1e6 / ref, rel=0.05)

    # K's part: rounds 0 → θ for K (zero 0), a 7.4 angle θ turned from 90° read through K_c
    th_k = np.arange(30.0, 390.0, 30.0)
    k_true = 3600.0
    counts_k = k_true * th_k
    from gonio.specs.ogam_draft.item_uncertainty import table_corrected_k_sensitivity
    i_s, i_z = cal.lookup(th_k)[0], cal.lookup(np.zeros(th_k.size))[0]
    k_c, c_k, _ = table_corrected_k_sensitivity(counts_k / th_k, th_k, th_k, np.zeros(th_k.size),
                                                cal)
    ct = CalibratedTable(cal, c_k, float(np.mean(k_c)))
    theta = np.array([30.0, 150.0, 270.0])
    a = ct.coefficients(theta, 90.0)
    kd = np.mean(counts_k / (th_k - (d[:, i_s] - d[:, i_z]) / 3600.0), axis=1)
    stop = [at[(90.0 + t) % 360.0] for t in theta]
    e = 3600.0 * (theta * float(np.mean(k_c)) / kd[:, None]
                  - (theta - (d[:, stop] - d[:, [at[90.0]]]) / 3600.0))
    np.testing.assert_allclose(np.std(e, axis=0),
                               np.sqrt(np.einsum("ij,j,ij->i", a, u ** 2, a)), rtol=0.03)


def test_table_calibration_without_scale_factor_rounds(tmp_path):
    """No 7.1 rounds (K from the file's nominal_scale_factor_counts_per_deg) with
    ``--table-calibration``: ``gonio calibrate`` exits 0 and C_v, C_g are corrected with the
    angles read through the nominal K (none of K's rounds used). A noise-free, untilted bench
    whose table has the test's harmonics, with an exact calibration, gives the C_v and C_g
    (the draft's functional of the corrected readings) of the same bench with a perfect
    table; uncorrected they differ by the table's error."""
    import json

    from gonio.cli import main
    from gonio.specs.ogam_draft.readings import write_readings

    p = _protocol()
    base = replace(load_bench("rlg"), sample_rate_hz=5.0)
    clean, bent = (tilted(replace(base.random_off(), table=TableConfig(
        accel_dps2=base.table.accel_dps2, mpe_arcsec=0.1, positioning_harmonics=h)), 0.0, 0.0)
        for h in ((), HARMONICS))
    out = {}
    x = table_positions_deg(p)
    f = tmp_path / "tc.csv"
    f.write_text("table_deg,error_arcsec,u_arcsec\n" + "".join(
        f"{a:g},{e:.9f},0.02\n" for a, e in zip(x, harmonic_sum_arcsec(x, HARMONICS))),
        encoding="utf-8")
    for key, bench in (("perfect", clean), ("bent", bent)):
        res = run_session(p, bench, seed=0)
        df = res.readings[res.readings["test"] != "scale_factor"]
        rd = tmp_path / f"{key}.csv"
        write_readings(df, rd, dict(res.metadata))
        o = tmp_path / key
        assert main(["calibrate", str(rd), "--table-calibration", str(f), "--out", str(o)]) == 0
        out[key] = json.loads((o / "results.json").read_text(encoding="utf-8"))["items"]
    assert not out["bent"]["scale_factor"]["measured"]
    from gonio.kit.render import labels
    from gonio.specs.ogam_draft.phrases import LABELS
    from gonio.specs.ogam_draft.stated import range_table_note
    for name in ("rate_consistency", "pointing_consistency"):
        tc = out["bent"][name]["details"]["table_calibration"]
        # the angles are read through the nominal K: no claim of a table-corrected 7.1 K
        assert tc["read_with_table_corrected_k"] is False
        d = out["bent"][name]["details"]
        assert "7.1 K" not in tc["label"] + d["estimates"]["corrected"]["label"]
        for lang in ("en", "zh"):
            text = "".join(s if isinstance(s, str) else s.text for s in range_table_note(
                {"items": out["bent"]}, name, labels(lang, LABELS)))
            assert "tc.csv" in text and " K" not in text, (lang, text)
        truth = out["perfect"][name]["details"]["table_calibration"]["uncorrected_value"]
        miss = abs(tc["measured_value"] - truth)
        assert miss < TIGHT[name], (name, tc["measured_value"], truth)
        # the table moves C_v by 0.015 ppm here (its 7.4 points only), C_g by 5.6e-7 %
        assert abs(tc["uncorrected_value"] - truth) > max(OFF[name] / 4, 100 * miss)
    # E too: read through the nominal K, so nothing says it was read with a corrected K
    from gonio.specs.ogam_draft.stated import e_table_note
    e = out["bent"]["angle_deviation"]["details"]
    assert e["table_calibration"]["scale_factor_corrected"] is not True
    assert "table-corrected K" not in e["estimates"]["corrected"]["label"]
    for lang in ("en", "zh"):
        text = "".join(s if isinstance(s, str) else s.text for s in e_table_note(
            {"items": out["bent"]}, labels(lang, LABELS)))
        assert "tc.csv" in text and " K" not in text, (lang, text)
    summary = (tmp_path / "bent" / "summary.txt").read_text(encoding="utf-8")
    assert "E's reference angles are corrected by the table calibration" in summary
    assert "E read with the table-corrected K" not in summary


def _truth_e_v(res, rep, name, col) -> dict:
    """The noise-free E_v per condition from the bench's parameters (as :func:`_truths`)."""
    tr = pd.DataFrame(res.truth["readings"])
    k_m = res.truth["scale_factor_through_mount_counts_per_deg"]
    k71, _ = scale_factor_truth(res.truth)
    c = getattr(rep.results, name)
    pts, out = c.tables["points"], {}
    for row in c.table.itertuples(index=False):
        v, src = getattr(row, col), row.source_test
        rows = tr[(tr["test"] == src) & tr["round"].isin(pts.loc[pts[col] == v, "round"])]
        rows = rows[np.isclose(rows["rate_dps"], float(v))] if col == "rate_dps" else \
            rows[(rows["orientation"] == v) & np.isclose(rows["rate_dps"], 60.0)]
        dev = rows["systematic_deviation_arcsec"] + 3600.0 * rows["true_table_deg"] * (
            k_m / k71 - 1.0)
        m = dev.groupby(rows["round"]).mean().to_numpy()
        out[v] = float(m[np.argmax(np.abs(m))])
    return out


def test_ranges_publish_corrected_tables(setup, runs):
    """With a calibration that corrected C_v and C_g, the published E_v per condition
    (results.json ``details.table``, the tables' CSV), the points and the spread are the
    corrected readings': equal to the bench's noise-free E_v within 3 mas, where the
    uncorrected (published without a calibration) miss by the table's error; the uncorrected
    are kept beside, labelled (``table_uncorrected``, ``points_uncorrected``,
    ``spread_uncorrected_arcsec``) and equal to the run without a calibration. The
    certificate's spread is ``details.spread_arcsec``."""
    _, res, _ = setup
    for name, col, _ in RANGES[1:]:
        d = runs["cal"].result().to_json()["items"][name]["details"]
        d0 = runs["raw"].result().to_json()["items"][name]["details"]
        truth = _truth_e_v(res, runs["cal"], name, col)
        got = {r[col]: r["E_arcsec"] for r in d["table"]}
        raw = {r[col]: r["E_arcsec"] for r in d0["table"]}
        assert max(abs(got[v] - truth[v]) for v in truth) < 0.003, (name, got, truth)
        assert max(abs(raw[v] - truth[v]) for v in truth) > 0.01, (name, raw, truth)
        assert d["spread_arcsec"] == pytest.approx(max(got.values()) - min(got.values()))
        assert d["spread_uncorrected_arcsec"] == d0["spread_arcsec"] != d["spread_arcsec"]
        assert d["table_uncorrected"] == d0["table"] and d["points_uncorrected"] == d0["points"]
        tables = runs["cal"].result().tables
        pts = tables[f"{name}_points.csv"]
        assert np.allclose(pts["E_arcsec"], [p["E_arcsec"] for p in d["points"]])
        assert f"{name}_points_uncorrected.csv" in tables
        assert d["points"] != d0["points"]


def test_ranges_measured_value_is_the_stated_ones_input(setup):
    """With the in-situ tilt estimate (a tilted bench, 0.1° at azimuth 120°) and a calibration,
    results.json's ``details.table_calibration.measured_value`` of K_l, C_v, C_g is the range
    the stated value is built from (the range line's "measured range", table- and
    tilt-corrected), recomputed here from the table-corrected readings by the tilt correction
    (K_i/(1 + δ_i) for K_l; E + δ·θ for C_v, C_g, δ the measured tilt's relative K bias); the
    table-only range is kept beside as ``measured_value_without_tilt_correction``."""
    p0, res0, cal = setup
    p = parse_protocol(read_toml(resolve("ogam-draft", "protocol")),
                       resolve("ogam-draft", "protocol"))
    base = replace(load_bench("rlg"), sample_rate_hz=5.0)
    bench = tilted(replace(base.random_off(), table=TableConfig(
        accel_dps2=base.table.accel_dps2, mpe_arcsec=0.1, positioning_harmonics=HARMONICS)),
        0.1, 120.0)
    res = run_session(p, bench, seed=0)
    rep = _analyse(p, res, cal)
    tc = rep.item_uncertainty["scale_factor"].correction
    assert tc is not None
    d = rep.result().to_json()["items"]
    for name, col, scale in RANGES:
        t = d[name]["details"]["table_calibration"]
        b = rep.item_uncertainty[name]
        line = float(re.search(r"measured range (\S+) ", b.components[0].source)[1])
        assert t["measured_value"] == pytest.approx(line, rel=1e-3, abs=1e-12)
        assert "measured_value_without_tilt_correction" in t
        if name == "scale_factor_nonlinearity":
            continue
        # independent: E_v of the corrected points (published) shifted by δ·θ
        pts = pd.DataFrame(d[name]["details"]["points"])
        e = pts["E_arcsec"] + tc.delta_rel * pts["position_deg"] * 3600.0
        e_v = [g.to_numpy()[np.argmax(np.abs(g.to_numpy()))] for _, g in e.groupby(pts[col])]
        want = (max(e_v) - min(e_v)) / d[name]["details"]["reference_angle_arcsec"] * scale
        assert t["measured_value"] == pytest.approx(want, rel=1e-6, abs=1e-12)
        assert t["measured_value_without_tilt_correction"] == pytest.approx(
            d[name]["details"]["spread_arcsec"] / d[name]["details"]["reference_angle_arcsec"]
            * scale, rel=1e-9)


def test_one_turned_error_for_every_item(setup, runs, monkeypatch):
    """K (7.1), K_l (7.2), E (7.4) and C_v, C_g (7.6, 7.7) take each reading's (each round's)
    table correction e(stop) − e(zero) from the one function
    :func:`~gonio.specs.ogam_draft.table_calibration.turned_error_arcsec`: with the exact
    calibration K, K_l, E per point and C_v meet their truths from the bench's parameters
    (:func:`scale_factor_truth`: the instrument's own K and K_i); with that function alone
    mutated (Δ's sign flipped, the calibration file unchanged) every one leaves them (K by
    more than 0.05 ppm, K_l and C_v by more than OFF, E by more than 0.05″ at some point), so
    a fault in it is noticed on each item."""
    from gonio.specs.ogam_draft import table_calibration as tcal
    from tests.test_table_calibration import _e_truth_71

    p, res, cal = setup
    ok = runs["cal"]
    t_i = _e_truth_71(res)

    def e_miss(rep) -> float:
        e = rep.results.angle_deviation
        return float(np.max(np.abs(e.table["E_arcsec"].to_numpy()
                                   - t_i.reindex(e.table["round"]).to_numpy())))

    cv, kl = "rate_consistency", "scale_factor_nonlinearity"
    truth = _truths(res, ok)
    k_true = scale_factor_truth(res.truth)[0]

    def k_miss(rep) -> float:
        return abs(rep.item_uncertainty["scale_factor"].value / k_true - 1.0)

    assert k_miss(ok) < 0.005e-6
    assert e_miss(ok) < 0.003
    for name in (cv, kl):
        assert abs(_measured(ok, name) - truth[name]) < TIGHT[name]
    real, calls = tcal.turned_error_arcsec, []

    def flipped(calibration, stop_deg, zero_deg):
        calls.append(len(np.atleast_1d(stop_deg)))
        d, i_s, i_z, miss = real(calibration, stop_deg, zero_deg)
        return -d, i_s, i_z, miss

    monkeypatch.setattr(tcal, "turned_error_arcsec", flipped)
    bad = _analyse(p, res, cal)
    assert len(calls) >= 4                          # K's rounds, E, C_v and C_g each called it
    assert k_miss(bad) > 0.05e-6
    assert e_miss(bad) > 0.05
    for name in (cv, kl):
        assert abs(_measured(bad, name) - truth[name]) > OFF[name], name
