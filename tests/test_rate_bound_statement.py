"""The rate items into which the rate table's relative error enters (JJF 1535 7.2.1 K; IEC
62047-20 5.1.3.1 a_BASE, 5.1.3.2): where the readings state no certificate u for the table,
its Table 2 bound and the other bounded line (the gyro's temperature error at T_BASE, e_TU)
can sit at their bounds at once with one sign, so the statement adds them linearly,
U = a + k·u_rest (the bound condition), not k·u_c of their quadrature; a laboratory that
states ``rate_table_u_rel`` has the table's line as a normal u (JJF K then keeps the GUM
statement; IEC a_BASE and 5.1.3.2 still add e_TU at its bound).

The checks are closed forms computed here from the standard's Table 2 (0.05 %, read off the
standard, not gonio's constant), the measurement model evaluated exactly at both bounds with
the same sign, Student's t from scipy and the Welch–Satterthwaite formula written out.
Mutation (the quadrature back: ``table_bound_statement`` returning the GUM budget) fails
every test here but JJF's stated-u one."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from gonio.specs import get

TABLE2_RATE = 5e-4          # JJF 1535-2015 Table 2: rate accuracy 0.05 % (relative)
BOUND_PREFIX = "U = a + k·u"


def _trial(key: str):
    """One worst-case trial of ``key``'s study programme (the bench states no certificate u
    for its table; the table at +0.05 %, the chamber at its deviation and the gyro at the
    warm end at once): (spec, protocol, readings, truth)."""
    from gonio.analysis.coverage import spawn_seed
    from gonio.pipeline.coverage import case_stream, reduced_protocol, study_bench

    spec = get(key)
    with tempfile.TemporaryDirectory() as d:
        proto = spec.load_protocol(str(reduced_protocol(spec.key, Path(d) / "r.toml")))
    bench = study_bench(spec, None, "worst")
    readings, truth = spec.run_trial(bench, proto, spawn_seed(5, case_stream(spec, "worst"), 0))
    return spec, proto, readings, truth


def _calibrate(spec, proto, readings, **md):
    from gonio.formats.rate_readings import RateReadings
    from gonio.pipeline.dispatch import screen_and_calibrate
    return screen_and_calibrate(spec, RateReadings(readings.data, {**readings.metadata, **md}),
                                proto)


@pytest.fixture(scope="module")
def iec():
    spec, proto, readings, truth = _trial("iec62047-20")
    assert "rate_table_u_rel" not in readings.metadata
    return spec, proto, readings, truth, _calibrate(spec, proto, readings)


@pytest.fixture(scope="module")
def jjf():
    spec, proto, readings, truth = _trial("jjf1535-2015")
    assert "rate_table_u_rel" not in readings.metadata
    return spec, proto, readings, truth, _calibrate(spec, proto, readings)


def _rows(item) -> dict:
    return {c["symbol"]: c for c in item.uncertainty.components}


def _rest(item, bounded) -> tuple[float, float]:
    """u_rest and ν_rest of the lines that are not bounded (Welch–Satterthwaite written out)."""
    rest = [c for s, c in _rows(item).items() if s not in bounded and c["contribution"]]
    u = math.sqrt(sum(c["contribution"] ** 2 for c in rest))
    den = sum(c["contribution"] ** 4 / c["dof"] for c in rest if c["dof"] is not None)
    return u, (u ** 4 / den if den > 0 else math.inf)


def _t95(nu: float) -> float:
    return float(stats.norm.ppf(0.975) if not math.isfinite(nu) or nu > 1000
                 else stats.t.ppf(0.975, max(1, math.floor(nu))))


@pytest.mark.parametrize("key", ["scale_factor", "initial_sf_variation"])
def test_iec_statement_covers_both_bounds_at_one_sign(iec, key):
    """a_BASE and 5.1.3.2: the interval's half-width is the shift that the table at −0.05 %
    and the gyro's temperature error at +its bound give together (the model a·(1 + e_TU)/
    (1 + e_table) evaluated there, exactly), plus t_95(ν_rest)·u_rest of the other lines; the
    quadrature k·u_c of the same budget is shorter than that shift alone, so a statement
    of the quadrature fails here."""
    _, _, readings, truth, res = iec
    it = res.items[key]
    rows = _rows(it)
    h_est = math.sqrt(3.0) * rows["e_TU"]["u"]          # the budget's line: the estimate's
    assert h_est > 1e-4                                 # the gyro 3 °C off at T_BASE: a line
    # the bound takes T_c,SF/a at its 95 % far end, |T_c| + U of 5.1.3.4's own statement
    # (%/°C), times the chamber's deviation bound + half its uniformity (the readings')
    md = readings.metadata
    bound_c = float(md["chamber_deviation_bound_c"]) + float(md["chamber_uniformity_c"]) / 2
    tc = res.items["sf_temperature_coefficient"]
    h_tu = bound_c * (abs(tc.value) + tc.U) / 100
    assert h_tu > h_est
    a_base = res.items["scale_factor"].value
    shifted = a_base * (1 + h_tu) / (1 - TABLE2_RATE)   # both bounds, one sign
    shift = abs(shifted - a_base) if key == "scale_factor" else \
        100 * abs(shifted - a_base) / res.items["initial_sf_variation"].details["a_TYP"]
    u_rest, nu_rest = _rest(it, ("e_table", "e_TU"))
    u = it.uncertainty
    assert u.k is None and u.k_source.startswith(BOUND_PREFIX)
    assert u.U == pytest.approx(shift + _t95(nu_rest) * u_rest, rel=1e-3)
    assert u.interval == pytest.approx((it.value - u.U, it.value + u.U), rel=1e-12)
    assert u.nu_eff == pytest.approx(nu_rest, rel=1e-9)          # the ν printed: the rest's
    # the quadrature of the same lines falls short of the two bounds' sum alone
    assert 1.96 * u.u_c < shift
    # this trial's truth (the table at +0.05 %, the gyro warm) is inside
    t = truth["items"][key]["value"]
    assert u.interval[0] <= t <= u.interval[1]
    bc = it.details["bound_condition"]
    assert bc["U"] == u.U and bc["k_rest"] == pytest.approx(_t95(nu_rest), rel=1e-12)


def test_jjf_k_statement_adds_the_table_bound(jjf):
    """JJF 7.2.1 K: the table's Table 2 bound moves K̄ by K̄·(1/(1 − 0.0005) − 1) at most; the
    statement is that plus t_95(ν_rest)·u_rest of the acquisition and the repeatability
    (ν_rest that of s(K_m)/√Q, not the ν_eff the table's line inflated)."""
    *_, truth, res = jjf
    it = res.items["scale_factor"]
    shift = it.value * (1 / (1 - TABLE2_RATE) - 1)
    u_rest, nu_rest = _rest(it, ("e_table",))
    u = it.uncertainty
    assert u.k is None and u.k_source.startswith(BOUND_PREFIX)
    assert u.U == pytest.approx(shift + _t95(nu_rest) * u_rest, rel=1e-3)
    assert u.U > shift + 1.96 * u_rest
    assert u.nu_eff == pytest.approx(nu_rest, rel=1e-9)
    t = truth["items"]["scale_factor"]["value"]
    assert u.interval[0] <= t <= u.interval[1]


def test_a_stated_certificate_u_keeps_the_gum_statement(jjf):
    """JJF K with ``rate_table_u_rel`` stated (its certificate's u): the table's line is
    normal with that u, the budget holds no other bound, and K keeps U = k·u_c,
    k = t_95(ν_eff) (no bound condition)."""
    spec, proto, readings, _, _ = jjf
    res = _calibrate(spec, proto, readings, rate_table_u_rel="0.00025")
    it = res.items["scale_factor"]
    u = it.uncertainty
    assert _rows(it)["e_table"]["u"] == pytest.approx(2.5e-4, rel=1e-12)
    assert u.k is not None and u.interval is None and "bound_condition" not in it.details
    assert u.k_source == "welch-satterthwaite"
    assert u.U == pytest.approx(u.k * u.u_c, rel=1e-12)
    assert u.k == pytest.approx(_t95(u.nu_eff), rel=1e-12)


@pytest.mark.parametrize("key", ["scale_factor", "initial_sf_variation"])
def test_iec_stated_table_u_still_bounds_the_chamber(iec, key):
    """IEC a_BASE and 5.1.3.2 with ``rate_table_u_rel`` stated: the table's line is normal
    with that u (among the rest), but the gyro's temperature error at T_BASE is still a
    bound the procedure allows (the chamber anywhere within its deviation), so it is added
    linearly: U = shift(e_TU at its bound) + t_95(ν_rest)·u_rest, u_rest with the table's
    line. The quadrature (e_TU rectangular) covers as little as 84 % with the chamber at
    its bound; mutation (a stated u returning the GUM budget) fails here."""
    spec, proto, readings, truth, _ = iec
    res = _calibrate(spec, proto, readings, rate_table_u_rel="0.00025")
    it = res.items[key]
    rows = _rows(it)
    assert rows["e_table"]["u"] == pytest.approx(2.5e-4, rel=1e-12)
    md = readings.metadata
    bound_c = float(md["chamber_deviation_bound_c"]) + float(md["chamber_uniformity_c"]) / 2
    tc = res.items["sf_temperature_coefficient"]
    h_tu = bound_c * (abs(tc.value) + tc.U) / 100
    a_base = res.items["scale_factor"].value
    shifted = a_base * (1 + h_tu)
    shift = abs(shifted - a_base) if key == "scale_factor" else \
        100 * abs(shifted - a_base) / res.items["initial_sf_variation"].details["a_TYP"]
    u_rest, nu_rest = _rest(it, ("e_TU",))
    u = it.uncertainty
    assert u.k is None and u.k_source.startswith(BOUND_PREFIX)
    assert sorted(it.details["bound_condition"]["a_lines"]) == ["e_TU"]
    assert u.U == pytest.approx(shift + _t95(nu_rest) * u_rest, rel=1e-3)
    assert u.U > it.details["bound_condition"]["U_quadrature"]
    assert u.nu_eff == pytest.approx(nu_rest, rel=1e-9)


def test_the_certificate_states_the_bound_condition_once(iec):
    """The results table states a_BASE and 5.1.3.2 by their interval with p and the ν of
    the rest (no U, no k), the legend says how (en and zh), and the budget's U row gives
    a, u_rest and the k and ν of the rest, k = t_95(ν printed)."""
    from gonio.report.i18n import labels
    from gonio.report.rate_certificate import rate_certificate_blocks
    from gonio.result.statement import nu_text

    *_, res = iec
    for lang, word in (("en", "bound-condition interval"), ("zh", "界限条件区间")):
        blocks = rate_certificate_blocks(res, labels(lang), lang, lab=None)["blocks"]
        tables = [b.data[1] for b in blocks if b.kind == "table"]
        results = next(b.data[1] for b in blocks if b.kind == "table"
                       and isinstance(b.extra, dict) and b.extra.get("id") == "results")
        legend = next(str(x) for b in blocks if b.kind == "p" for x in b.data if word in str(x))
        after = legend[legend.index(word):]
        assert "5.1.3.1, 5.1.3.2" in after[:after.index("5.1.3.2") + 8]
        for key, clause in (("scale_factor", "5.1.3.1"), ("initial_sf_variation", "5.1.3.2")):
            it = res.items[key]
            row = next(r for r in results if len(r) > 2 and str(r[2]) == clause)
            assert str(row[4]) == "—" and str(row[5]) == "—"          # no U, no k
            assert str(row[6]) == nu_text(it.uncertainty.nu_eff)
            assert "p = 95 %" in "".join(map(str, row[3]))
            urow = next(r for t in tables for r in t
                        if len(r) == 5 and str(r[0]) == clause and str(r[1]) == "U")
            cell = "".join(map(str, urow[2]))
            k = _t95(it.uncertainty.nu_eff)
            assert cell.startswith("U = a + k·u_rest") and f"k = {k:.2f}" in cell
            assert f"ν_eff = {nu_text(it.uncertainty.nu_eff)}" in cell


def test_the_statement_function_is_first_order_exact():
    """:func:`table_bound_statement` on a model whose bounded lines are linear: a = Σ|c_i|a_i
    exactly, u_rest of the other lines, k of their ν (Student's t of the integer part)."""
    from uncertainty import from_u, type_b

    from gonio.result.gum import gum
    from gonio.specs._rate_family.rate_records import table_bound_statement

    ins = [from_u("x", 2.0, 0.0), type_b("e1", 0.0, 3e-3, "rectangular"),
           type_b("e2", 0.0, 1e-3, "rectangular"), from_u("n", 0.0, 2e-3, dof=7.6)]
    g = gum(lambda x, e1, e2, n: x + 2 * e1 - 5 * e2 + n, ins)
    s, d = table_bound_statement(g, 2.0, None, {"e1": 3e-3, "e2": 1e-3})
    assert d["a"] == pytest.approx(2 * 3e-3 + 5 * 1e-3, rel=1e-6)
    assert s.U == pytest.approx(0.011 + stats.t.ppf(0.975, 7) * 2e-3, rel=1e-6)
    assert s.nu_eff == pytest.approx(7.6) and s.k is None
    assert s.u_c == g.u_c                           # the budget's u_c kept
    # a stated table u: the table's line is no bound; the other bounded lines still are
    assert table_bound_statement(g, 2.0, 1e-4, {"e_table": 3e-3})[0] is g
    s1, d1 = table_bound_statement(g, 2.0, 1e-4, {"e_table": 3e-3, "e2": 1e-3})
    assert d1["a"] == pytest.approx(5 * 1e-3, rel=1e-6) and list(d1["a_lines"]) == ["e2"]
    u_rest = math.hypot(2 * 3e-3 / math.sqrt(3), 2e-3)       # e1 rectangular, n
    nu_rest = u_rest ** 4 / (2e-3 ** 4 / 7.6)
    assert s1.U == pytest.approx(5e-3 + stats.t.ppf(0.975, math.floor(nu_rest)) * u_rest,
                                 rel=1e-6)
    from gonio.errors import GonioError
    with pytest.raises(GonioError, match="no line 'e9'"):
        table_bound_statement(g, 2.0, None, {"e9": 1.0})
    assert np.isfinite(s.U)


OMEGA_E_DPS = 360.0 / 86164.0989     # IEC 62047-20 5.3.3.1 (the sidereal day, read off the clause)


@pytest.mark.parametrize("key", ["bias", "initial_bias_variation"])
def test_iec_bias_statement_adds_its_bounds(iec, key):
    """The 5.3.3.1 bias and 5.3.3.2: the gyro's temperature error at T_BASE (the chamber's
    deviation bound + half its uniformity, × |β| + U(β) of 5.3.3.6's own statement), the
    input axis's misalignment (the bench file's bound) on the horizontal Earth rate, and
    a_BASE's bounded part (N_bias = (Out,ave − null)/a_BASE − Ω_E,proj: the reading taken
    for eq. (24)) at their bounds with one sign, plus t_95(ν_rest)·u_rest of the other
    lines. The quadrature k·u_c of the same lines covers less than 95 % with those errors
    at their bounds (normal rest of u_rest); the statement covers ≥ 95 % there. Mutation
    (the bias's statement returning the GUM budget) fails here."""
    from gonio.formats.toml import read_toml
    from gonio.resources import resolve

    _, _, readings, truth, res = iec
    it, b = res.items[key], res.items["bias"]
    md = readings.metadata
    bound_c = float(md["chamber_deviation_bound_c"]) + float(md["chamber_uniformity_c"]) / 2
    bt = res.items["bias_temperature_coefficient"]
    h_tu = bound_c * (abs(bt.value) + bt.U)
    align = read_toml(resolve("mems-adxrs610", kind="bench"))["equipment"]["axis_alignment_bound_deg"]
    lat = math.radians(float(md["latitude_deg"]))
    h_al = OMEGA_E_DPS * math.cos(lat) * math.sin(math.radians(align))
    sf = res.items["scale_factor"]
    a_rel = sf.details["bound_condition"]["a"] / abs(sf.value)
    out_rate = b.value + b.details["earth_component_dps"]     # (Out,ave − null)/a_BASE
    shift = h_tu + h_al + abs(out_rate) * a_rel
    rows = _rows(it)
    assert rows["e_TU"]["u"] == pytest.approx(h_tu / math.sqrt(3), rel=1e-9)
    assert rows["e_align"]["u"] == pytest.approx(h_al / math.sqrt(3), rel=1e-9)
    # a_BASE's other lines: u_rest/a_BASE with ν_rest, sensitivity −(Out,ave − null)/a_BASE
    assert rows["e_a"]["c"] == pytest.approx(-out_rate, rel=1e-4)
    assert rows["e_a"]["u"] == pytest.approx(
        sf.details["bound_condition"]["u_rest"] / abs(sf.value), rel=1e-12)
    u_rest, nu_rest = _rest(it, ("e_TU", "e_align", "e_a_bnd"))
    u = it.uncertainty
    assert u.k is None and u.k_source.startswith(BOUND_PREFIX)
    assert sorted(it.details["bound_condition"]["a_lines"]) == ["e_TU", "e_a_bnd", "e_align"]
    assert u.U == pytest.approx(shift + _t95(nu_rest) * u_rest, rel=1e-3)
    assert u.interval == pytest.approx((it.value - u.U, it.value + u.U), rel=1e-12)
    assert u.nu_eff == pytest.approx(nu_rest, rel=1e-9)
    # at the bound: P(|shift + e| ≤ U) with e = u_rest·t_ν (ν_rest), the rest's distribution
    t_nu = stats.t(max(1, math.floor(nu_rest)))
    cover = lambda half: float(t_nu.cdf((half - shift) / u_rest) - t_nu.cdf((-half - shift) / u_rest))
    q = it.details["bound_condition"]["U_quadrature"]
    assert cover(q) < 0.95 <= cover(u.U) + 1e-12
    # this trial's truth (the chamber at its bound, the fixture at its bound) is inside
    t = truth["items"][key]["value"]
    assert u.interval[0] <= t <= u.interval[1]
    if key == "initial_bias_variation":        # the bias's statement shifted by Out,typ
        typ = it.details["nominal_bias_dps"]
        assert u.U == pytest.approx(b.uncertainty.U, rel=1e-9)
        assert u.interval == pytest.approx((b.uncertainty.interval[0] - typ,
                                            b.uncertainty.interval[1] - typ), abs=1e-12)
