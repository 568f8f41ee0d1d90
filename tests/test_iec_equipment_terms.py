"""IEC 62047-20 budget terms for the equipment the coverage study now draws (issue 24): the
chamber's deviation at T_BASE in a_BASE and the bias, and the chamber's fluctuation in the
symmetry. Each is recomputed here by a second route (Monte Carlo over the fluctuation's
phase with numpy.polyfit; the bench's own temperature polynomials), so a mutated term
fails."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.specs.iec62047_20.items import fluctuation_u_rel


def _mc_fluct(x, t, amp, period, n=100_000):
    """sd of (a_CW − a_CCW)/K̄ over a uniform phase, by numpy.polyfit on each half."""
    phi = np.random.default_rng(1).uniform(0, 2 * np.pi, n)
    y = x[:, None] * (1 + amp * np.sin(2 * np.pi * t[:, None] / period + phi[None, :]))
    cw, ccw = x > 0, x < 0
    a_cw = np.polyfit(x[cw], y[cw], 1)[0]
    a_ccw = np.polyfit(x[ccw], y[ccw], 1)[0]
    return float(np.std(a_cw - a_ccw))


def test_fluctuation_term_against_monte_carlo():
    # the built-in programme's order (CCW max → rest → CW max), 40 s per point
    x = np.array([-300, -240, -180, -120, -60, 0, 60, 120, 180, 240, 300], float)
    t = 40.0 * np.arange(x.size)
    for period in (900.0, 300.0, 5000.0):
        mc = _mc_fluct(x, t, 4.5e-5, period)
        assert fluctuation_u_rel(x, t, 4.5e-5, period) == pytest.approx(mc, rel=0.02)
        # without a stated period: a bound over any period
        assert fluctuation_u_rel(x, t, 4.5e-5, None) >= mc
    # small rates (below 1 °/s) count as CW/CCW points too; the bound by hand: Σ|v| = 3
    # for each half of ±1, ±2
    xs = np.array([-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0])
    ts = 40.0 * np.arange(xs.size)
    for period, tt in ((700.0, ts), (260.0, ts), (450.0, ts ** 1.1)):
        assert fluctuation_u_rel(xs, tt, 1e-4, period) == pytest.approx(
            _mc_fluct(xs, tt, 1e-4, period), rel=0.02)
    assert fluctuation_u_rel(np.array([-2.0, -1.0, 1.0, 2.0]), ts[:4], 1e-4, None) == \
        pytest.approx(6e-4 / math.sqrt(2), rel=1e-12)
    assert fluctuation_u_rel(x, t, 0.0, 900.0) == 0.0
    assert math.isnan(fluctuation_u_rel(np.array([-1.0, 0.0, 1.0]), t[:3], 1e-4, 900.0))


@pytest.fixture(scope="module")
def iec_noise_free(tmp_path_factory):
    from gonio.formats.rate_readings import RateReadings
    from gonio.pipeline.coverage import reduced_protocol
    from gonio.specs._rate_family.simulate import study_bench
    from gonio.specs.iec62047_20 import calibrate
    from gonio.specs.iec62047_20.simulate import simulate

    p = str(reduced_protocol("iec62047-20", tmp_path_factory.mktemp("eq") / "p.toml",
                             {"noise": {"samples": 600}, "power_on": {"samples": 300}}))
    b = study_bench(draw_equipment=False)
    res = simulate(b, p, seed=3, noise=False)
    keep = res.data["test"].isin(["scale_factor", "sf_temperature", "bias", "bias_temperature",
                                  "static"])
    rd = RateReadings(res.data[keep], {k: str(v) for k, v in res.metadata.items()})
    return calibrate(rd, p), b, res, p


def _comp(item, symbol):
    return next(c for c in item.uncertainty.components if c["symbol"] == symbol)


def test_chamber_deviation_at_t_base_in_a_base_and_bias(iec_noise_free):
    """e_T of a_BASE: ±2 °C rectangular × (LS slope of K(T_i) / mean K(T_i)) of the bench's
    polynomial at the protocol's temperatures; e_T of the bias: ±2 °C × the LS slope of the
    bench's b(T) there (noise-free, ideal equipment: the estimates are the polynomials')."""
    r, b, res, _ = iec_noise_free
    g = b.gyro
    T = np.array(sorted({s["temperature_c"] for s in res.truth["segments"]
                         if s["test"] == "sf_temperature"}), float)
    K = g.scale_factor_at(T, g.supply_nominal_v)
    k_rel = np.polyfit(T, K, 1)[0] / K.mean()
    assert r.metadata["chamber_deviation_bound_c"] == "2.0"
    assert r.metadata["chamber_uniformity_c"] == "0.0"       # the ideal chamber: e_TU = ±2 °C
    assert _comp(r.items["scale_factor"], "e_TU")["u"] == pytest.approx(
        2.0 / math.sqrt(3) * abs(k_rel), rel=2e-3)
    assert _comp(r.items["initial_sf_variation"], "e_TU")["u"] == pytest.approx(
        2.0 / math.sqrt(3) * abs(k_rel), rel=2e-3)
    Tb = np.array([s["temperature_c"] for s in res.truth["segments"]
                   if s["test"] == "bias_temperature"], float)
    b_tc = np.polyfit(Tb, g.bias_at(Tb, g.supply_nominal_v), 1)[0]
    # the bias's bound takes β at its 95 % far end, |β| + U(β) of 5.3.3.6's own statement
    # (the estimate alone is no bound); noise-free, the estimate is the polynomial's slope
    bt = r.items["bias_temperature_coefficient"]
    assert bt.value == pytest.approx(b_tc, rel=2e-2)
    assert _comp(r.items["bias"], "e_TU")["u"] == pytest.approx(
        2.0 / math.sqrt(3) * (abs(b_tc) + bt.U), rel=2e-2)
    # both enter u_c: the scale factor's relative u_c holds the chamber term in quadrature
    sf = r.items["scale_factor"]
    others = [c["u"] for c in sf.uncertainty.components if c["symbol"] in ("e_table", "e_acq")]
    assert (sf.uncertainty.u_c / sf.value) ** 2 >= sum(u * u for u in others) \
        + (2.0 / math.sqrt(3) * k_rel) ** 2 * 0.999


def test_symmetry_budget_holds_the_fluctuation(iec_noise_free):
    """The fluctuation term of 5.1.3.8 against a Monte Carlo over the phase, with the
    amplitude and period the readings state (the noise-free run's ideal chamber states 0;
    the bench file's chamber, ±0.3 °C over 900 s, is stated here instead)."""
    from gonio.formats.rate_readings import RateReadings
    from gonio.specs.iec62047_20 import calibrate

    r0, b, res, p = iec_noise_free
    eq = b.equipment
    assert r0.metadata["chamber_fluctuation_c"] == "0.0"
    assert _comp(r0.items["symmetry"], "fluct")["u"] == 0.0
    md = {k: str(v) for k, v in res.metadata.items()}
    md.update(chamber_fluctuation_c=repr(eq.chamber.fluctuation_c),
              chamber_fluctuation_period_s=repr(eq.chamber.fluctuation_period_s))
    keep = res.data["test"].isin(["scale_factor", "sf_temperature"])
    r = calibrate(RateReadings(res.data[keep], md), p)
    c = _comp(r.items["symmetry"], "fluct")
    sf = res.data[(res.data["test"] == "scale_factor") & (res.data["run"] == 0)]
    pts = sf.groupby("step").agg(x=("rate_dps", "first"), t=("time_s", "first"))
    T = np.array(sorted({s["temperature_c"] for s in res.truth["segments"]
                         if s["test"] == "sf_temperature"}), float)
    K = b.gyro.scale_factor_at(T, b.gyro.supply_nominal_v)
    amp = abs(np.polyfit(T, K, 1)[0] / K.mean()) * eq.chamber.fluctuation_c
    mc = _mc_fluct(pts["x"].to_numpy(float), pts["t"].to_numpy(float), amp,
                   eq.chamber.fluctuation_period_s)
    a_base = r.items["scale_factor"].value
    assert c["u"] == pytest.approx(mc * a_base, rel=0.03)


def test_chamber_uniformity_in_a_base(iec_noise_free):
    """Review finding (coverage 0.900, a constant 4.5e-5 left): the gyro's place in the
    chamber's volume, ± half the stated uniformity, rectangular × T_c,SF/a of the bench's
    polynomial; the draw puts the gyro uniformly in that range."""
    from gonio.bench.equipment import Chamber, Equipment, draw_equipment

    from gonio.formats.rate_readings import RateReadings
    from gonio.specs.iec62047_20 import calibrate

    r0, b, res, p = iec_noise_free
    u0 = _comp(r0.items["scale_factor"], "e_TU")["u"]    # the ideal chamber: ±2 °C alone
    md = {k: str(v) for k, v in res.metadata.items()}
    md.update(chamber_uniformity_c=repr(b.equipment.chamber.uniformity_c))   # the bench's 0.4
    keep = res.data["test"].isin(["scale_factor", "sf_temperature"])
    r = calibrate(RateReadings(res.data[keep], md), p)
    g = b.gyro
    T = np.array(sorted({s["temperature_c"] for s in res.truth["segments"]
                         if s["test"] == "sf_temperature"}), float)
    K = g.scale_factor_at(T, g.supply_nominal_v)
    k_rel = np.polyfit(T, K, 1)[0] / K.mean()
    half = 0.2
    # the deviation's ±2 °C and the place's ±0.2 °C: both bounded, allowed at once, so one
    # rectangular line of the summed half-width (not their quadrature)
    for item in ("scale_factor", "initial_sf_variation"):
        assert _comp(r.items[item], "e_TU")["u"] == pytest.approx(
            (2.0 + half) / math.sqrt(3) * abs(k_rel), rel=2e-3)
        assert _comp(r.items[item], "e_TU")["u"] > \
            math.hypot(2.0, half) / math.sqrt(3) * abs(k_rel) * 1.05
    assert u0 == pytest.approx(2.0 / math.sqrt(3) * abs(k_rel), rel=2e-3)
    eq = Equipment(chamber=Chamber(uniformity_c=0.4))
    pos = np.array([draw_equipment(eq, s).chamber.position_offset() for s in range(3000)])
    assert np.abs(pos).max() <= 0.2 and np.var(pos) == pytest.approx(0.2 ** 2 / 3, rel=0.08)
    assert Chamber(uniformity_c=0.4).position_offset() == 0.2       # not drawn: the far corner


def test_chamber_uniformity_in_the_bias(iec_noise_free):
    """Review of stop 30: the place in the volume moves the gyro's temperature, hence its
    bias by place × b'(T); the bias (and the initial bias variation, which reuses it)
    carries it in e_TU = ±(deviation bound + half the uniformity), rectangular × the bench's
    b(T) slope over the 5.3.3.6 visits. Mutation: the uniformity taken out fails here."""
    from gonio.formats.rate_readings import RateReadings
    from gonio.specs.iec62047_20 import calibrate

    r0, b, res, p = iec_noise_free
    u0 = _comp(r0.items["bias"], "e_TU")["u"]                     # the ideal chamber: ±2 °C
    md = {k: str(v) for k, v in res.metadata.items()}
    md.update(chamber_uniformity_c="4.0")
    keep = res.data["test"].isin(["scale_factor", "bias", "bias_temperature", "static"])
    r = calibrate(RateReadings(res.data[keep], md), p)
    g = b.gyro
    Tb = np.array([s["temperature_c"] for s in res.truth["segments"]
                   if s["test"] == "bias_temperature"], float)
    b_tc = np.polyfit(Tb, g.bias_at(Tb, g.supply_nominal_v), 1)[0]
    reach0 = abs(b_tc) + r0.items["bias_temperature_coefficient"].U   # |β| + U(β), 5.3.3.6
    reach = abs(b_tc) + r.items["bias_temperature_coefficient"].U
    assert u0 == pytest.approx(2.0 / math.sqrt(3) * reach0, rel=2e-2)
    assert _comp(r.items["bias"], "e_TU")["u"] == pytest.approx(
        (2.0 + 2.0) / math.sqrt(3) * reach, rel=2e-2)
    assert r.items["bias"].uncertainty.u_c > r0.items["bias"].uncertainty.u_c
    assert r.items["initial_bias_variation"].uncertainty.u_c == r.items["bias"].uncertainty.u_c


def _ratio_run(b, p, phase_deg):
    """The IEC programme on ``b`` with every noise and equipment error off except the
    chamber's fluctuation (the bench file's ±0.3 °C over 900 s, at ``phase_deg``), the gyro
    following the chamber (τ = 1 s): the 5.1.3.1, 5.1.3.4 and 5.1.3.5 runs calibrated."""
    from dataclasses import replace

    from gonio.bench.equipment import Chamber
    from gonio.formats.rate_readings import RateReadings
    from gonio.specs.iec62047_20 import calibrate
    from gonio.specs.iec62047_20.simulate import simulate

    ch = b.equipment.chamber
    quiet = b.without_noise()
    eq = replace(quiet.equipment, chamber=Chamber(
        fluctuation_c=ch.fluctuation_c, fluctuation_period_s=ch.fluctuation_period_s,
        fluctuation_phase_deg=phase_deg))
    res = simulate(replace(quiet, equipment=eq), p, seed=3, noise=True)
    keep = res.data["test"].isin(["scale_factor", "sf_temperature", "ratiometric"])
    r = calibrate(RateReadings(res.data[keep], {k: str(v) for k, v in res.metadata.items()}),
                  p, findings=[])
    return r, res


def test_ratiometric_budget_holds_the_fluctuation(iec_noise_free):
    """5.1.3.5: the supply runs follow one another at the one set point, so the chamber's
    fluctuation moves K by T_c,SF between them, and eq (7)'s a_Vi/a_BASE with it; the
    readings log the set point only, so it is budgeted ("fluct", relative, on a_Vi).
    Checked three ways: the term against a Monte Carlo over the phase (numpy.polyfit on each
    run's points, K(t) of the bench's polynomial); on the bench at eight phases the error of
    the estimate against the truth of the bench's parameters (K(V)/K(V_BASE) − V/V_BASE)
    never exceeds the largest the term allows (√2·u), and its rms over the phases is about
    the term's u. The ideal chamber (amplitude 0) gives 0; without the term (the old budget)
    the error was 0.8 u_c on average over the coverage study's 200 trials."""
    _, b, _, p = iec_noise_free
    g, ch = b.gyro, b.equipment.chamber
    errs, us = [], []
    for phase in np.arange(8) * 45.0:
        r, res = _ratio_run(b, p, phase)
        it = r.items["ratiometric_error"]
        i = int(np.argmax(np.abs(it.details["R_pct"])))
        ib = int(np.argmin(np.abs(it.details["V"] - g.supply_nominal_v)))
        u_fl = _comp(it, "fluct")["u"]
        q = it.details["a_V"][i] / it.details["a_V"][ib]
        errs.append(it.value - res.truth["items"]["ratiometric_error"]["value"])
        us.append(100 * q * u_fl)
        assert abs(errs[-1]) <= math.sqrt(2) * us[-1] * 1.02
    # the term does not know the phase (it moves only with T_c,SF, which the fluctuation
    # disturbs in the 5.1.3.4 runs) ...
    assert np.ptp(us) <= 1e-2 * us[0]
    # ... and it is the rms of the error over the phase (eight equal steps: exact for a
    # sine), up to the bench holding the gyro at the chamber's mean during each point's
    # settling delay (the point means then see about 12 % less of the fluctuation)
    rms = math.sqrt(np.mean(np.square(errs)))
    assert 0.8 * us[0] <= rms <= 1.02 * us[0]
    # Monte Carlo over the phase: each run's slope by numpy.polyfit of x·K(T(t))
    d = res.data[res.data["test"] == "ratiometric"]
    runs = [d[d["run"] == k].groupby("step").agg(x=("rate_dps", "first"), t=("time_s", "first"))
            for k in sorted(set(d["run"]))]
    T = np.array(sorted({s["temperature_c"] for s in res.truth["segments"]
                         if s["test"] == "sf_temperature"}), float)
    K = g.scale_factor_at(T, g.supply_nominal_v)
    amp = abs(np.polyfit(T, K, 1)[0] / K.mean()) * ch.fluctuation_c
    phi = np.random.default_rng(2).uniform(0, 2 * np.pi, 50_000)

    def slope(pts):
        x, t = pts["x"].to_numpy(float), pts["t"].to_numpy(float)
        y = x[:, None] * (1 + amp * np.sin(2 * np.pi * t[:, None] / ch.fluctuation_period_s
                                           + phi[None, :]))
        return np.polyfit(x, y, 1)[0]

    mc = float(np.std(slope(runs[i]) / slope(runs[ib])))
    assert u_fl == pytest.approx(mc, rel=0.02)
    r0 = iec_noise_free[0]
    assert "ratiometric_error" not in r0.items or not r0.items["ratiometric_error"].measured \
        or _comp(r0.items["ratiometric_error"], "fluct")["u"] == 0.0


def test_sf_temperature_coefficient_carries_correlated_deviations(iec_noise_free):
    """5.1.3.4: the chamber's set-point deviations in any pattern within ±2 °C (Table 2 bounds
    each, not their correlation): the line's half-width is the largest slope change over
    every sign pattern (enumerated here with numpy.polyfit on the item's own K_i(T_i)),
    rectangular; the independent reading stays in the details, smaller."""
    import itertools

    r, _, _, _ = iec_noise_free
    it = r.items["sf_temperature_coefficient"]
    T, K = np.asarray(it.details["temperatures_c"], float), np.asarray(it.details["K_i"], float)
    slope = np.polyfit(T, K, 1)[0]
    h = max(abs(np.polyfit(T, K + slope * 2.0 * np.array(s), 1)[0] - slope)
            for s in itertools.product((-1.0, 1.0), repeat=T.size))
    ib = int(np.argmin(np.abs(T - 22.5)))
    assert _comp(it, "dT")["u"] == pytest.approx(h / math.sqrt(3), rel=1e-6)
    assert it.details["u_dT_independent"]["u"] < 0.7 * h / math.sqrt(3)
    # the item (in %/°C) holds it: u_c ≥ the line's 100·u/a_BASE
    assert it.uncertainty.u_c >= 100 * h / math.sqrt(3) / K[ib] * 0.999


def test_sf_temperature_coefficient_carries_the_place_in_the_volume(iec_noise_free):
    """5.1.3.4 and 5.3.3.6: the gyro's temperature error at each set point is the chamber's
    deviation AND its place in the volume (± half the uniformity, bounded at each set point
    and free to follow it), in any pattern, as a_BASE and the bias take them (δ + U/2):
    the slope line's half-width is the largest slope change over every sign pattern at
    ±(δ + U/2), enumerated with numpy.polyfit on the item's K_i(T_i) (5.1.3.4) and on the
    visits' bias polynomial b′(T) (5.3.3.6). Mutation: δ alone (the uniformity dropped)
    fails both."""
    import itertools

    from gonio.formats.rate_readings import RateReadings
    from gonio.specs.iec62047_20 import calibrate

    _, b, res, p = iec_noise_free
    md = {k: str(v) for k, v in res.metadata.items()}
    md.update(chamber_deviation_bound_c="2.0", chamber_uniformity_c="2.0")
    keep = res.data["test"].isin(["scale_factor", "sf_temperature", "bias",
                                  "bias_temperature", "static"])
    r = calibrate(RateReadings(res.data[keep], md), p)
    it = r.items["sf_temperature_coefficient"]
    T, K = np.asarray(it.details["temperatures_c"], float), np.asarray(it.details["K_i"], float)
    slope = np.polyfit(T, K, 1)[0]
    bound = 2.0 + 2.0 / 2
    h = max(abs(np.polyfit(T, K + slope * bound * np.array(s), 1)[0] - slope)
            for s in itertools.product((-1.0, 1.0), repeat=T.size))
    assert _comp(it, "dT")["u"] == pytest.approx(h / math.sqrt(3), rel=1e-6)
    # 5.3.3.6: the visits' set points, b′ from a quadratic through the visits' biases
    bt = r.items["bias_temperature_coefficient"]
    Tv = np.asarray(bt.details["temperatures_c"], float)
    Bv = np.asarray(bt.details["bias_dps"], float)
    c2 = np.polyfit(Tv, Bv, 2)
    s0 = np.polyfit(Tv, Bv, 1)[0]
    Tu = np.unique(Tv)
    hb = 0.0
    for sg in itertools.product((-1.0, 1.0), repeat=Tu.size):
        d = {t: g * bound for t, g in zip(Tu, sg)}
        moved = Bv + np.array([np.polyval(np.polyder(c2), t) * d[t] for t in Tv])
        hb = max(hb, abs(np.polyfit(Tv, moved, 1)[0] - s0))
    assert _comp(bt, "dT_set")["u"] == pytest.approx(hb / math.sqrt(3), rel=1e-6)


def test_noise_items_carry_the_chamber_fluctuation(iec_noise_free):
    """5.4.5.1 b), c): the fluctuation's amplitude × the bias temperature coefficient (here
    the bench's b(T) slope over the 5.3.3.6 visits) through the in-band Welch estimate; 0 where
    the readings state no fluctuation. The in-band line against a Welch estimate of the
    sinusoid at 37 phases (scipy.signal.welch); proportional to the stated amplitude."""
    from scipy import signal

    from gonio.formats.rate_readings import RateReadings
    from gonio.specs.iec62047_20 import calibrate

    from gonio.specs.iec62047_20.simulate import simulate

    _, b, _, p = iec_noise_free
    res = simulate(b, p, seed=3, noise=True)        # the bench file's chamber (0.3 °C)
    md = {k: str(v) for k, v in res.metadata.items()}
    md.update(chamber_fluctuation_c="1.0", chamber_fluctuation_period_s="900.0")
    keep = res.data["test"].isin(["scale_factor", "sf_temperature", "bias", "bias_temperature",
                                  "static"])
    r = calibrate(RateReadings(res.data[keep], md), p)
    g = b.gyro
    Tb = np.array([s["temperature_c"] for s in res.truth["segments"]
                   if s["test"] == "bias_temperature"], float)
    amp = abs(np.polyfit(Tb, g.bias_at(Tb, g.supply_nominal_v), 1)[0]) * 1.0
    st = res.data[res.data["test"] == "static"]
    t = st["time_s"].to_numpy(float)
    dt = float(np.median(np.diff(t)))
    n = t.size
    nper = min(4096, n)
    tt = np.arange(n) * dt
    band = []
    for ph in np.linspace(0, np.pi, 37):
        f, ps = signal.welch(amp * np.sin(2 * np.pi * tt / 900.0 + ph), fs=1 / dt, nperseg=nper)
        sel = (f > 0) & (f <= 1.0)
        band.append(float(np.trapezoid(ps[sel], f[sel])))
    it = r.items["inband_noise"]
    rms = it.value
    h = rms - math.sqrt(max(rms ** 2 - max(band), 0.0))
    assert _comp(it, "fluct")["u"] == pytest.approx(h / math.sqrt(3), rel=0.02)
    assert _comp(it, "fluct")["u"] > 0
    md.update(chamber_fluctuation_c="0.0")
    r0 = calibrate(RateReadings(res.data[keep], md), p)
    assert _comp(r0.items["inband_noise"], "fluct")["u"] == 0.0
    assert _comp(r0.items["broadband_noise"], "fluct")["u"] == 0.0
