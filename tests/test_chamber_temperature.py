"""The optical bench's temperature model and K's chamber-temperature line, each against a
second calculation: the simulated K at a chamber deviation against the closed form
K·(1 + α_K ΔT), E's independence of it against a session at the reference, the budget's
``K_T`` line against its half-width by hand and a Monte Carlo of the gyro's coefficient and
the chamber, the study's draws against their stated
distributions; where K's coefficient bound comes from (the readings' statement, else the
protocol's default for the gyro type the readings state, never the bench's coefficient); and
coverage of a FOG's K at the chamber's bound with the built-in protocol, which fails with an
RLG's bound and holds with the FOG's."""

from __future__ import annotations

import math
from pathlib import Path
from dataclasses import replace

import numpy as np
import pytest

from gonio.analysis.coverage import clopper_pearson
from gonio.errors import GonioError
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.item_coverage import scale_factor_truth
from gonio.specs.ogam_draft.outputs import summary
from gonio.specs.ogam_draft.item_uncertainty import (chamber_temperature_line,
                                                      scale_factor_budget, without_tilt_u_rel)
from gonio.specs.ogam_draft.readings import Readings
from gonio.specs.ogam_draft.study import (case_bench, draw_type_b, trial_bench,
                                          validation_protocol)
from gonio.specs.ogam_draft.truth import truth_from_session


@pytest.fixture(scope="module")
def proto():
    return validation_protocol()          # 7.1 and 7.4 (10 series)


@pytest.fixture(scope="module")
def base():
    return replace(load_bench("rlg"), sample_rate_hz=5.0)


def _warm(bench, dev_c, alpha_ppm, beta_dph):
    inst = replace(bench.instrument, sf_temperature_coeff_ppm_per_c=alpha_ppm,
                   bias_temperature_coeff_dph_per_c=beta_dph)
    return replace(bench, instrument=inst, chamber_deviation_c=dev_c)


def _calibrate(proto, res):
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    return analyse(Readings(df, dict(res.metadata)), proto, budget="draft")


def test_k_moves_by_its_coefficient_and_e_does_not(proto, base):
    """Noise-free sessions at the reference and 1.5 °C off with α_K = 40 ppm/°C and
    β = 0.5 °/h/°C: the 7.1 counts grow by exactly 1 + α_K ΔT (closed form), the deviation
    E of 7.4 (counts through the K of the same chamber) and its truth do not move (the
    factor divides out, the constant bias goes with the measured Earth-rate compensation),
    and the truth of K stays the reference's."""
    cold = base.random_off()
    warm = _warm(cold, 1.5, 40.0, 0.5)
    r0, r1 = run_session(proto, cold, seed=3), run_session(proto, warm, seed=3)
    sf = (r0.readings["test"] == "scale_factor").to_numpy()
    ratio = r1.readings["gyro_counts"].to_numpy()[sf] / r0.readings["gyro_counts"].to_numpy()[sf]
    assert ratio == pytest.approx(np.full(sf.sum(), 1.0 + 40e-6 * 1.5), rel=1e-10)
    c0, c1 = _calibrate(proto, r0), _calibrate(proto, r1)
    assert c1.results.scale_factor.value / c0.results.scale_factor.value == \
        pytest.approx(1.0 + 40e-6 * 1.5, rel=1e-10)
    e0 = c0.results.angle_deviation.tables["readings"]["E_arcsec"].to_numpy()
    e1 = c1.results.angle_deviation.tables["readings"]["E_arcsec"].to_numpy()
    assert np.abs(e1 - e0).max() < 1e-6
    # the tilt estimate's rests are uncompensated counts: β ΔT moves them by β ΔT × dwell
    s0 = [r["systematic_deviation_arcsec"] for r in r0.truth["readings"]
          if r["test"] != "tilt_estimate"]
    s1 = [r["systematic_deviation_arcsec"] for r in r1.truth["readings"]
          if r["test"] != "tilt_estimate"]
    assert np.abs(np.subtract(s1, s0)).max() < 1e-6
    assert scale_factor_truth(r1.truth)[0] == scale_factor_truth(r0.truth)[0]
    t0 = truth_from_session(r0.truth, proto)["scale_factor"]["value"]
    t1 = truth_from_session(r1.truth, proto)["scale_factor"]["value"]
    assert t1 == pytest.approx(t0, rel=1e-12)
    assert r1.metadata["temperature_c"] == repr(proto.conditions.temperature_c + 1.5)


def test_coefficients_change_nothing_at_the_reference(proto, base):
    """At ΔT = 0 the temperature coefficients leave the session bit for bit as a bench
    without them (the default bench's outputs)."""
    a = run_session(proto, _warm(base, 0.0, 0.0, 0.0), seed=5)
    b = run_session(proto, _warm(base, 0.0, 7.0, 0.3), seed=5)
    assert a.readings.equals(b.readings) and a.metadata == b.metadata


def test_budget_line_is_the_chamber_line_in_its_distribution():
    """K_T: half-width |K| times the chamber line's, in its distribution (rectangular at a
    logged ΔT, the product of two rectangulars at the tolerance); no line at a logged ΔT of
    0; the part of u(K) other items carry (:func:`without_tilt_u_rel`) leaves it out with the
    tilt line."""
    k_i, th = [3600.1, 3600.3, 3600.2, 3600.2, 3600.1, 3600.3], [60, 120, 180, 240, 300, 360]
    plain = scale_factor_budget(k_i, th, 0.1)
    for ch, dist, div in ((chamber_temperature_line(2.0, 1.0), "rectangular-product", 3.0),
                          (chamber_temperature_line(2.0, 1.0, -0.7), "rectangular",
                           math.sqrt(3.0))):
        b = scale_factor_budget(k_i, th, 0.1, chamber=ch)
        (line,) = [c for c in b.components if c.symbol == "K_T"]
        assert line.distribution == dist
        assert line.u == pytest.approx(3600.2 * 2e-6 * (1.0 if div == 3.0 else 0.7) / div,
                                       rel=1e-12)
        assert b.u_c == pytest.approx(math.hypot(plain.u_c, line.u), rel=1e-12)
        assert without_tilt_u_rel(b) == pytest.approx(without_tilt_u_rel(plain), rel=1e-12)
    b = scale_factor_budget(k_i, th, 0.1, chamber=chamber_temperature_line(2.0, 1.0, 0.0))
    assert not [c for c in b.components if c.symbol == "K_T"] and b.u_c == plain.u_c


def test_chamber_line_against_a_monte_carlo_of_the_gyro_and_the_chamber():
    """The chamber line's u against a Monte Carlo of what it models (JCGM 101): α_K uniform
    within ±α_max and, where the temperature is not logged, ΔT uniform within ±ΔT_max,
    independent: std(α_K ΔT) = α_max ΔT_max/3 (not /√3, the single rectangular's); at a
    logged ΔT, α_max |ΔT|/√3. The ``rectangular-product`` sampler of the budget's Monte Carlo
    against the closed-form distribution of |U₁U₂|, P(|U₁U₂| ≤ x) = x(1 − ln x), by a
    Kolmogorov–Smirnov test."""
    from scipy import stats

    from uncertainty import distribution

    rng = np.random.default_rng(20261129)
    n, a_ppm, t_c = 1_000_000, 1.0, 1.0
    alpha = rng.uniform(-a_ppm, a_ppm, n)
    prod = alpha * rng.uniform(-t_c, t_c, n)
    line = chamber_temperature_line(a_ppm, t_c)
    assert line.u_rel / 1e-6 == pytest.approx(np.std(prod), rel=4e-3)
    assert np.std(prod) < 0.6 * a_ppm * t_c / math.sqrt(3.0)     # the single rectangular's u
    logged = chamber_temperature_line(a_ppm, t_c, 0.6)
    assert logged.u_rel / 1e-6 == pytest.approx(np.std(alpha * 0.6), rel=4e-3)
    x = distribution("rectangular-product").sample(np.random.default_rng(7), 2.0, 200_000) / 2.0
    assert np.abs(x).max() <= 1.0 and abs(x.mean()) < 3e-3
    ks = stats.kstest(np.abs(x), lambda v: np.clip(v, 1e-300, 1.0) * (1.0 - np.log(
        np.clip(v, 1e-300, 1.0))))
    assert ks.pvalue > 1e-3, ks
    assert np.std(x) == pytest.approx(1.0 / 3.0, rel=5e-3)


def _fog(bench, dev_c, alpha_ppm=1.0):
    """``bench`` (5 Hz, exact counter) whose instrument is a FOG by type with α_K =
    ``alpha_ppm`` in a chamber ``dev_c`` off the reference."""
    b = _warm(bench, dev_c, alpha_ppm, 0.005)
    return replace(b, instrument=replace(b.instrument, type="fog"))


def _bound(rep):
    return rep.item_details(rep.results.scale_factor)["temperature_coeff_bound"]


def test_the_stated_bound_tolerance_and_logged_temperature_reach_the_certified_k(base):
    """calibrate's K budget takes the bound the readings state for the instrument; with the
    chamber's temperature logged (metadata ``temperature_c``) the logged deviation from the
    protocol's reference, else Table 2's tolerance with ΔT uniform; results.json says which
    bound, which reading and where they came from, summary.txt says it."""
    proto = replace(validation_protocol(),
                    conditions=replace(validation_protocol().conditions,
                                       temperature_tolerance_c=2.5))
    res = run_session(proto, base, seed=1)
    assert res.metadata["temperature_c"] == "20.0"
    res.metadata["sf_temperature_coeff_bound_ppm_per_c"] = "0.4"
    # logged: alpha_K (dT + delta), delta within the protocol's thermometer MPE 0.2 degC:
    # u^2 = (a^2/3)(dT^2 + m^2/3) (closed form); else a dT_max/3
    for logged, div, dev in (("20.6", math.sqrt(3.0 / (1.0 + 0.2 ** 2 / 3.0 / 0.6 ** 2)), 0.6),
                             (None, 3.0, 2.5)):
        md = {k: v for k, v in res.metadata.items() if k != "temperature_c"}
        if logged is not None:
            md["temperature_c"] = logged
        rep = _calibrate(proto, replace(res, metadata=md))
        b = rep.item_uncertainty["scale_factor"]
        (line,) = [c for c in b.components if c.symbol == "K_T"]
        kv = abs(float(rep.results.scale_factor.value))   # the 7.1 mean the line scales
        assert line.u * div == pytest.approx(kv * 0.4e-6 * dev, rel=1e-9)
        d = _bound(rep)
        assert (d["bound_ppm_per_c"], d["source"], d["gyro_type"], d["temperature_tolerance_c"],
                d["reference_temperature_c"]) == (0.4, "metadata", "rlg", 2.5, 20.0)
        assert d["u_ppm"] * 1e-6 * kv == pytest.approx(line.u, rel=1e-9)
        text = summary(rep.result())
        if logged is not None:
            assert (d["basis"], d["logged_temperature_c"]) == ("logged", 20.6)
            assert d["deviation_c"] == pytest.approx(0.6, rel=1e-12)
            assert (d["logged_from"], d["thermometer_mpe_c"], d["thermometer_from"]) == \
                ("metadata", 0.2, "protocol")
            assert d["distribution"] == "rectangular-shifted-product"
            assert "the chamber temperature the readings log, 20.6 °C (+0.60 °C from the " \
                "reference 20 °C; thermometer MPE ±0.2 °C), and |α_K| ≤ 0.4 " \
                "ppm/°C: stated by the readings" in text
        else:
            assert (d["basis"], d["logged_temperature_c"], d["deviation_c"]) == \
                ("tolerance", None, None)
            assert "±2.5 °C of the reference and |α_K| ≤ 0.4 ppm/°C: stated by the " \
                "readings" in text
    # logged at the reference: the thermometer's part alone, alpha_K delta (product of two
    # zero-mean rectangulars, u = a m/3); with a thermometer stated exact, no K_T line
    at_ref = _calibrate(proto, res)
    b = at_ref.item_uncertainty["scale_factor"]
    (line,) = [c for c in b.components if c.symbol == "K_T"]
    assert line.u == pytest.approx(abs(float(at_ref.results.scale_factor.value)) * 0.4e-6
                                   * 0.2 / 3.0, rel=1e-9)
    assert _bound(at_ref)["distribution"] == "rectangular-product"
    # a zero difference is printed unsigned to the thermometer's 0.01 °C, never "+0"
    assert "(0.00 °C from the reference 20 °C;" in summary(at_ref.result())
    assert "chamber temperature logged 0.00 °C from the reference" in line.source
    exact = _calibrate(proto, replace(res, metadata={**res.metadata, "thermometer_mpe_c": "0"}))
    assert not [c for c in exact.item_uncertainty["scale_factor"].components
                if c.symbol == "K_T"]
    assert (_bound(exact)["u_ppm"], _bound(exact)["thermometer_from"]) == (0.0, "metadata")


def test_the_bound_follows_the_gyro_type_never_the_bench(proto, base):
    """Without a stated bound the protocol's default for the gyro type the readings state is
    taken (the bench writes ``gyro_type``, never its coefficients): a FOG gets the FOG
    default even when its true α_K is 50 times larger, an RLG the RLG default; readings
    stating no type get the larger default; a type that is neither is refused."""
    a = proto.annex_a
    fog = run_session(proto, _fog(base, 0.3, alpha_ppm=50.0), seed=2)
    assert fog.metadata["gyro_type"] == "fog"
    assert not any("coeff" in k for k in fog.metadata)
    d = _bound(_calibrate(proto, fog))
    assert (d["bound_ppm_per_c"], d["source"]) == (a.sf_temperature_coeff_bound_fog_ppm_per_c,
                                                   "protocol-fog")
    rlg = run_session(proto, base, seed=2)
    assert _bound(_calibrate(proto, rlg))["source"] == "protocol-rlg"
    md = {k: v for k, v in rlg.metadata.items() if k != "gyro_type"}
    untyped = _calibrate(proto, replace(rlg, metadata=md))
    d = _bound(untyped)
    assert d["source"] == "protocol-larger" and d["bound_ppm_per_c"] == max(
        a.sf_temperature_coeff_bound_rlg_ppm_per_c, a.sf_temperature_coeff_bound_fog_ppm_per_c)
    with pytest.raises(GonioError, match="gyro_type"):
        _calibrate(proto, replace(rlg, metadata={**rlg.metadata, "gyro_type": "mems"}))


def test_fog_k_covers_at_the_chamber_bound_with_the_default_protocol(proto, base):
    """An instrument of type FOG with α_K = 1 ppm/°C in a chamber at Table 2's +1 °C bound,
    calibrated with the built-in protocol and no bound stated: U(K) covers K at the
    reference (Clopper–Pearson reaching 95 %), since the FOG default is taken; the same
    readings labelled RLG (its 0.1 ppm/°C bound) miss in most trials."""
    bench = _fog(base, proto.conditions.temperature_tolerance_c)
    hits = {"fog": 0, "as rlg": 0}
    n = 12
    for s in range(400, 400 + n):
        res = run_session(proto, bench, seed=s)
        k_true = scale_factor_truth(res.truth)[0]
        for key, md in (("fog", res.metadata), ("as rlg", {**res.metadata, "gyro_type": "rlg"})):
            b = _calibrate(proto, replace(res, metadata=md)).item_uncertainty["scale_factor"]
            hits[key] += abs(b.value - k_true) <= b.U
    assert clopper_pearson(hits["fog"], n)[1] >= 0.95, hits
    assert clopper_pearson(hits["as rlg"], n)[1] < 0.95, hits


def test_study_draws_the_chamber_within_its_tolerance_in_typeb_and_worst(proto, base):
    """typeb: ΔT uniform within ±tolerance (variance tol²/3), drawn after the other effects
    (those are the draws without it); worst: the tilt at the A.1 bound and the worst
    azimuth in every trial, the chamber and the table drawn as in typeb (the same draws for
    the same seed), never read from the instrument's coefficient."""
    tol = proto.conditions.temperature_tolerance_c
    d = np.array([draw_type_b(base, proto, s).chamber_deviation_c for s in range(3000)])
    assert np.abs(d).max() <= tol and abs(d.mean()) < 0.03
    assert np.var(d) == pytest.approx(tol ** 2 / 3.0, rel=0.08)
    w = case_bench("worst", base, proto)
    assert w.chamber_deviation_c == 0.0 and w.instrument.tilt_deg == proto.annex_a.tilt_bound_deg
    for s in range(5):
        t, ref = trial_bench("worst", w, proto, s), draw_type_b(base, proto, s)
        assert (t.instrument.tilt_deg, t.instrument.tilt_azimuth_deg) == \
            (w.instrument.tilt_deg, w.instrument.tilt_azimuth_deg)
        assert (t.chamber_deviation_c, t.table) == (ref.chamber_deviation_c, ref.table)
        assert t.instrument.sf_temperature_coeff_ppm_per_c == \
            ref.instrument.sf_temperature_coeff_ppm_per_c


@pytest.mark.parametrize("name, key", [("rlg", "sf_temperature_coeff_bound_rlg_ppm_per_c"),
                                       ("fog", "sf_temperature_coeff_bound_fog_ppm_per_c")])
def test_study_draws_alpha_k_within_the_bound_k_t_takes(proto, base, name, key):
    """typeb and worst draw the gyro's α_K per trial, uniform within ± the bound the
    calibration's K_T line takes for that gyro type (the protocol's default for the type the
    bench's readings state; never the bench file's own coefficient): the draws span the
    bound, their variance is bound²/3 (uniform), their mean ≈ 0; the chamber's draw is the
    one before α_K was drawn (appended last), and the truth of K divides by the trial's own
    1 + α_K ΔT."""
    bench = replace(load_bench(name), sample_rate_hz=5.0)
    bound = getattr(proto.annex_a, key)
    assert bench.instrument.sf_temperature_coeff_ppm_per_c != 0.0     # the file's value
    d = [draw_type_b(bench, proto, s) for s in range(3000)]
    a = np.array([b.instrument.sf_temperature_coeff_ppm_per_c for b in d])
    assert np.abs(a).max() <= bound and np.abs(a).max() > 0.99 * bound
    assert abs(a.mean()) < 0.03 * bound
    assert np.var(a) == pytest.approx(bound ** 2 / 3.0, rel=0.08)
    # appended after the other draws: the chamber's deviation is the same uniform as before
    tol = proto.conditions.temperature_tolerance_c
    for s in range(3):
        rng = np.random.default_rng([s, 0x7B])
        u = rng.uniform(size=5 + len(bench.table.positioning_harmonics) + 2)
        assert d[s].chamber_deviation_c == pytest.approx(-tol + 2 * tol * u[-2], rel=1e-12)
        assert a[s] == pytest.approx(-bound + 2 * bound * u[-1], rel=1e-12)
    if name != "rlg":
        return
    # the truth: K at the reference from the trial's drawn α_K (noise-free, against a session
    # of the same bench at the reference); the file's α_K would leave 1e-8 and more
    s = max(range(50), key=lambda i: abs((a[i] - bench.instrument.sf_temperature_coeff_ppm_per_c)
                                         * d[i].chamber_deviation_c))
    t = d[s].random_off()
    res = run_session(proto, t, seed=0)
    assert res.truth["bench"]["instrument"]["sf_temperature_coeff_ppm_per_c"] == a[s]
    k_ref = truth_from_session(res.truth, proto)["scale_factor"]["value"]
    k0 = truth_from_session(run_session(proto, replace(t, chamber_deviation_c=0.0), seed=0
                                        ).truth, proto)["scale_factor"]["value"]
    assert k_ref == pytest.approx(k0, rel=1e-11)
    off = 1e-6 * (a[s] - bench.instrument.sf_temperature_coeff_ppm_per_c) * t.chamber_deviation_c
    assert abs(off) > 1e-8


def _simulated_stream(tmp_path, dev, name):
    """A 20 Hz virtual RLG session of the small protocol with the chamber ``dev`` °C off
    the reference, written with its stream (CSV); the output folder."""
    from gonio.specs.ogam_draft.simulate import simulate

    proto_file = Path(__file__).parent / "data" / "pins" / "ogam-draft-small.toml"
    rlg = (Path(__file__).parents[1] / "protocols" / "benches" / "rlg.toml").read_text("utf-8")
    assert "deviation_c = 0.0" in rlg
    bench = tmp_path / f"{name}.toml"
    bench.write_text(rlg.replace('table = "table-precision"', 'table = "table-precision"\n'
                                 'sample_rate_hz = 20.0', 1)
                     .replace("sample_rate_hz = 1000.0", "", 1)
                     .replace("deviation_c = 0.0", f"deviation_c = {dev!r}"), "utf-8")
    out = tmp_path / name
    simulate(out, protocol=str(proto_file), bench=str(bench), seed=2, stream=True,
             stream_format="csv")
    return out


def test_stream_logs_the_chamber_and_reduces_to_the_same_readings(tmp_path):
    """A bench whose chamber is 0.6 °C off writes the stream's optional temperature_c column
    (the reference plus the deviation on every sample) and the readings metadata likewise;
    the stream reduces to the readings the session wrote (the column does not disturb it).
    At the reference the stream has no such column (the default bench's stream unchanged)."""
    from pathlib import Path

    from gonio.formats.streams import read_stream
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.readings import read_readings
    from gonio.specs.ogam_draft.reduce import reduce_stream

    proto_file = Path(__file__).parent / "data" / "pins" / "ogam-draft-small.toml"
    for dev, name in ((0.6, "warm"), (0.0, "ref")):
        out = _simulated_stream(tmp_path, dev, name)
        s = read_stream(out / "stream.csv")
        rd = read_readings(out / "readings.csv")
        assert rd.metadata["temperature_c"] == repr(20.0 + dev)
        if not dev:
            assert s.temperature_c is None
            continue
        assert np.all(s.temperature_c == 20.0 + dev)
        red = reduce_stream(s, load_protocol(str(proto_file)))
        assert not [u for u in red.unmatched if u["kind"] == "round"]
        key = ["test", "series", "round", "orientation"]
        m = rd.data.merge(red.readings, on=key + ["rate_dps"], how="outer", indicator=True,
                          suffixes=("_ref", "_got"))
        m = m[m["test"] != "zero_stability"]
        assert (m["_merge"] == "both").all()
        assert np.abs(m["gyro_counts_got"] - m["gyro_counts_ref"]).max() <= 1.0


def test_the_laboratory_files_gyro_type_is_checked_against_the_readings(tmp_path):
    """The laboratory file may state the instrument's type ([instrument] gyro_type); readings
    of another type are a contradiction (refused, or a finding), compared like the serial
    (case ignored); a type that is neither is refused when the file is read."""
    from gonio.formats.lab import load_lab
    from gonio.pipeline.identity import contradictions

    src = (Path(__file__).parents[1] / "protocols" / "lab-example.toml").read_text("utf-8")

    def lab(v):
        f = tmp_path / f"lab-{v}.toml"
        f.write_text(src.replace("[instrument]", f'[instrument]\ngyro_type = "{v}"', 1)
                     if "[instrument]" in src else src + f'\n[instrument]\ngyro_type = "{v}"\n',
                     encoding="utf-8")
        return load_lab(f)

    (c,) = contradictions({"gyro_type": "fog"}, lab("RLG"))
    assert (c["what"], c["readings"], c["lab"], c["lab_key"]) == \
        ("gyro type", "'fog'", "'RLG'", "instrument.gyro_type")
    assert contradictions({"gyro_type": "fog"}, lab("FOG")) == []
    assert contradictions({}, lab("fog")) == []              # the readings silent: nothing
    with pytest.raises(GonioError, match="gyro_type"):
        lab("mems")


@pytest.mark.parametrize("value", ["0", "-0.1", "nan", "inf", "-inf", "1e5"])
def test_a_bound_that_is_not_positive_and_finite_is_refused(tmp_path, capsys, value):
    """The readings' ``sf_temperature_coeff_bound_ppm_per_c`` must be a positive finite
    number (zero would claim an instrument without temperature coefficient): anything else is
    one line naming the key and the file, exit 2 on the command line, nothing written; the
    protocol's defaults likewise."""
    from gonio.cli import main
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.readings import read_readings

    src = Path(__file__).parent / "data" / "full.csv"
    text = src.read_text("utf-8")
    f = tmp_path / "readings.csv"
    f.write_text(f"# sf_temperature_coeff_bound_ppm_per_c: {value}\n" + text, "utf-8")
    with pytest.raises(GonioError) as exc:
        read_readings(f)
    msg = str(exc.value)
    assert "sf_temperature_coeff_bound_ppm_per_c" in msg and "readings.csv" in msg
    assert "(0, 1e4]" in msg and "\n" not in msg
    out = tmp_path / "out"
    assert main(["calibrate", str(f), "--spec", "ogam-draft", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "sf_temperature_coeff_bound_ppm_per_c" in err
    assert not out.exists()
    if value == "1e5":
        return
    for kind in ("rlg", "fog"):
        p = tmp_path / f"protocol-{kind}.toml"
        small = (Path(__file__).parent / "data" / "small-protocol.toml").read_text("utf-8")
        p.write_text(small + f"\n[annex_a]\nsf_temperature_coeff_bound_{kind}_ppm_per_c = "
                     f"{value}\n", "utf-8")
        with pytest.raises(GonioError) as exc:
            load_protocol(p)
        msg = str(exc.value)
        assert f"sf_temperature_coeff_bound_{kind}_ppm_per_c" in msg and p.name in msg, msg
        assert "\n" not in msg


def test_shifted_product_line_against_a_monte_carlo_of_the_gyro_and_the_thermometer():
    """The logged line α_K (ΔT + δ), δ the thermometer's error within ± its MPE m: its u by
    the closed form (α_max²/3)(ΔT² + m²/3) against a Monte Carlo drawing α_K and δ (JCGM 101),
    and the budget's ``rectangular-shifted-product`` sampler against those direct draws
    (two-sample Kolmogorov–Smirnov); at ΔT = 0 the product of two zero-mean rectangulars."""
    from scipy import stats

    from uncertainty import distribution

    rng = np.random.default_rng(20261130)
    n, a_ppm = 400_000, 1.0
    for dev, m in ((0.6, 0.2), (-0.1, 0.3), (0.0, 0.2), (0.45, 0.0)):
        direct = rng.uniform(-a_ppm, a_ppm, n) * (dev + rng.uniform(-m, m, n))
        line = chamber_temperature_line(a_ppm, 1.0, dev, m)
        assert line.u_rel / 1e-6 == pytest.approx(np.std(direct), rel=6e-3), (dev, m)
        assert line.half_width_rel / 1e-6 == pytest.approx(abs(dev) + m, rel=1e-12)
        assert line.half_width_rel / 1e-6 >= np.abs(direct).max()
        drawn = distribution(line.distribution, beta=line.beta).sample(
            np.random.default_rng(11), line.half_width_rel / 1e-6, n)
        assert stats.ks_2samp(drawn, direct).pvalue > 1e-3, (dev, m)
        assert np.std(drawn) == pytest.approx(line.u_rel / 1e-6, rel=6e-3)
    assert chamber_temperature_line(1.0, 1.0, 0.0, 0.2).distribution == "rectangular-product"


def _cli_readings(tmp_path, name, column=None, metadata=None):
    """tests/data/chamber-readings.csv (a virtual RLG session of the small protocol, its
    gyro type and temperature removed: four zero-stability rows, then the three
    7.1 rows) with a ``temperature_c`` column (``column``: {row index: cell}, the rest
    blank) and/or metadata ``temperature_c``."""
    lines = (Path(__file__).parent / "data" / "chamber-readings.csv").read_text(
        "utf-8").splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    if metadata is not None:
        head.append(f"# temperature_c: {metadata}")
    if column is not None:
        body = [body[0] + ",temperature_c"] + [
            row + "," + column.get(i, "") for i, row in enumerate(body[1:])]
    f = tmp_path / f"{name}.csv"
    f.write_text("\n".join(head + body) + "\n", "utf-8")
    return f


def _cli(f, out):
    from gonio.cli import main

    small = Path(__file__).parent / "data" / "pins" / "ogam-draft-small.toml"
    return main(["calibrate", str(f), "--spec", "ogam-draft", "--protocol", str(small),
                 "--out", str(out)])


def _cli_k_t(tmp_path, capsys, f):
    import json

    out = tmp_path / (f.stem + "-out")
    rc = _cli(f, out)
    err = capsys.readouterr().err
    assert rc == 0, err
    res = json.loads((out / "results.json").read_text("utf-8"))
    sf = res["items"]["scale_factor"]
    return sf["details"]["temperature_coeff_bound"], sf["value"], (out / "summary.txt").read_text(
        "utf-8")


def test_calibrate_reads_the_key_the_column_a_sparse_column_or_neither(tmp_path, capsys):
    """From the outside (``gonio calibrate``): the metadata key; a column (its mean over the
    three 7.1 rows, over the key); a sparse column (a slow logger, a value on every third
    row: 19.8, 20.1, 20.7, 21.0 on rows 0, 3, 6, 9; the 7.1 rows 4, 5, 6 interpolated in
    file order to 20.3, 20.5, 20.7: mean 20.5); neither (the tolerance reading). Each line's u is
    checked against the closed form u = |K| α_max √((ΔT² + m²/3)/3), m = 0.2 °C, α_max =
    1 ppm/°C (no gyro type: the larger default)."""
    cases = {
        "key": (None, "20.4", 20.4, "metadata"),
        "column": ({4: "20.3", 5: "20.5", 6: "20.7", 0: "25"}, "19.0", 20.5, "column"),
        "sparse": ({0: "19.8", 3: "20.1", 6: "20.7", 9: "21.0"}, None, 20.5, "column"),
        "neither": (None, None, None, None),
    }
    for name, (col, md, want, src) in cases.items():
        d, k, text = _cli_k_t(tmp_path, capsys, _cli_readings(tmp_path, name, col, md))
        assert (d["logged_temperature_c"], d["logged_from"]) == (want, src), name
        assert d["bound_ppm_per_c"] == 1.0
        if want is None:
            assert d["basis"] == "tolerance" and d["u_ppm"] == pytest.approx(1.0 / 3.0)
            continue
        dev = want - 20.0
        assert d["deviation_c"] == pytest.approx(dev, abs=1e-9)
        assert d["u_ppm"] == pytest.approx(math.sqrt((dev ** 2 + 0.2 ** 2 / 3.0) / 3.0),
                                           rel=1e-9), name
        assert ("(mean over the 7.1 rounds)" in text) == (src == "column"), name
        assert "thermometer MPE ±0.2 °C" in text


@pytest.mark.parametrize("cell", ["warm", "nan", "-300", "1e9"])
def test_a_damaged_temperature_cell_is_one_line_naming_column_and_row(tmp_path, capsys, cell):
    """A ``temperature_c`` cell that is not a temperature: one line naming the column and
    the row's line, exit 2, nothing written."""
    f = _cli_readings(tmp_path, "bad", {4: "20.1", 5: cell, 6: "20.2"})
    line = f.read_text("utf-8").splitlines().index(
        [ln for ln in f.read_text("utf-8").splitlines() if ln.endswith("," + cell)][0]) + 1
    out = tmp_path / "out"
    assert _cli(f, out) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "temperature_c" in err and f"bad.csv:{line}" in err, err
    assert not out.exists()


def test_a_stated_thermometer_mpe_reaches_the_line(tmp_path, capsys):
    """The readings' ``thermometer_mpe_c`` over the protocol's default; a negative one is
    refused naming the key."""
    f = _cli_readings(tmp_path, "mpe", None, "20.4")
    f.write_text("# thermometer_mpe_c: 0.05\n" + f.read_text("utf-8"), "utf-8")
    d = _cli_k_t(tmp_path, capsys, f)[0]
    assert (d["thermometer_mpe_c"], d["thermometer_from"]) == (0.05, "metadata")
    assert d["u_ppm"] == pytest.approx(math.sqrt((0.4 ** 2 + 0.05 ** 2 / 3.0) / 3.0), rel=1e-9)
    f.write_text("# thermometer_mpe_c: -1\n" + f.read_text("utf-8"), "utf-8")
    assert _cli(f, tmp_path / "o") == 2
    assert "thermometer_mpe_c" in capsys.readouterr().err


def test_a_sparse_stream_column_reaches_k_as_the_mean_over_the_rounds(tmp_path, capsys):
    """A stream whose logger writes ``temperature_c`` on every 40th sample only (blank
    cells between), a ramp T(t) = 20.3 + 0.002 °C/s·t, and no metadata temperature:
    ``gonio calibrate`` on the stream gives each 7.1 reading the ramp's mean over its round
    (linear interpolation of a linear ramp is exact: T at the midpoint of zeroing and
    reading) and K's line the mean over the rounds, against the closed form; the reduced
    readings carry the column."""
    import json

    from gonio.formats.streams import read_stream
    from gonio.specs.ogam_draft.protocol import load_protocol
    from gonio.specs.ogam_draft.reduce import reduce_stream

    out = _simulated_stream(tmp_path, 0.6, "warm")
    lines = (out / "stream.csv").read_text("utf-8").splitlines()
    head = [ln for ln in lines if ln.startswith("#") and "temperature_c:" not in ln]
    body = [ln for ln in lines if not ln.startswith("#")]
    cols = body[0].split(",")
    ti, ki = cols.index("time_s"), cols.index("temperature_c")
    rows = []
    for i, ln in enumerate(body[1:]):
        c = ln.split(",")
        c[ki] = repr(20.3 + 0.002 * float(c[ti])) if i % 40 == 0 else ""
        rows.append(",".join(c))
    f = tmp_path / "sparse-stream.csv"
    f.write_text("\n".join(head + [body[0]] + rows) + "\n", "utf-8")
    small = Path(__file__).parent / "data" / "pins" / "ogam-draft-small.toml"
    red = reduce_stream(read_stream(f), load_protocol(str(small)))
    sf = red.readings[red.readings["test"] == "scale_factor"]
    want = 20.3 + 0.002 * 0.5 * (sf["t_zero_s"] + sf["t_read_s"]).to_numpy()
    assert np.abs(sf["temperature_c"].to_numpy() - want).max() < 1e-9
    from gonio.cli import main
    o = tmp_path / "cal"
    assert main(["calibrate", str(f), "--spec", "ogam-draft", "--protocol", str(small),
                 "--out", str(o)]) == 0, capsys.readouterr().err
    d = json.loads((o / "results.json").read_text("utf-8"))["items"]["scale_factor"][
        "details"]["temperature_coeff_bound"]
    assert (d["basis"], d["logged_from"]) == ("logged", "column")
    assert d["logged_temperature_c"] == pytest.approx(want.mean(), abs=1e-8)
    dev = want.mean() - 20.0
    assert d["u_ppm"] == pytest.approx(d["bound_ppm_per_c"] * math.sqrt(
        (dev ** 2 + 0.2 ** 2 / 3.0) / 3.0), rel=1e-7)
