"""k, the printed ν and U agree for every item of both rate specifications, and an item
computed from the scale factor (or from another item) carries that item's ν.

For each rate specification, two calibrations on the virtual bench: the demo's (``gonio
simulate --spec S --seed 3``, the built-in programme) and a short programme (the pin test's
small protocol, seed 7, three calibrations of K, the rate table's certificate u removed from
the readings so that the table enters by its Table 2 bound: K and a_BASE stated by their
bound condition). Over every measured item of results.json, worked out here from its budget
lines alone, not from gonio's statement rule:

- ν_eff is Welch–Satterthwaite over the item's lines, u_c⁴/Σ u_i⁴/ν_i (JCGM 100 G.4.1,
  written out here), for every item stated by U = k·u_c;
- the ν printed in summary.txt is that ν_eff's integer part, or ∞ above 1000 (the
  documented rule, JCGM 100 G.6.4), and k = t_0.975 of the printed ν (scipy; the normal
  quantile for ∞), printed k the same to 3 significant digits; U = k·u_c;
- an item stated by its bound condition: ν_eff is the W–S ν of its lines other than the
  bounded ones, and U = a + t_0.975(⌊ν_rest⌋)·u_rest;
- every budget line that carries the scale factor's relative u_c (u_c(K)/|K|, JJF 7.2.1;
  u_c(a_BASE)/|a_BASE|, IEC 5.1.3.1) has the W–S ν of the scale factor's own lines, not ∞
  (a short programme's K rests on three calibrations); IEC 5.3.3.2's line of the 5.3.3.1
  bias has that bias's ν.

A new item that states a k of another ν, or that carries K's u_c without its ν, fails here.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from scipy import stats

from gonio.cli import main
from gonio.specs import get

ROOT = Path(__file__).resolve().parents[1]
PINS = ROOT / "tests" / "data" / "pins"
SPECS = ("jjf1535-2015", "iec62047-20")
#: The documented threshold above which ν is stated ∞ (docs/validation-rate.md; GUM G.6.4
#: truncation below it).
NU_INFINITE = 1000.0


def _ws(u_c: float, rows) -> float:
    """JCGM 100 eq. (G.2b), written out: rows (contribution u_i(y), ν_i or None for ∞)."""
    den = sum(c ** 4 / d for c, d in rows if d is not None and math.isfinite(d) and c)
    return u_c ** 4 / den if den > 0 else math.inf


def _nu_printed(nu: float) -> str:
    return "∞" if nu > NU_INFINITE else str(max(1, math.floor(nu)))


def _t(nu_text: str) -> float:
    return stats.norm.ppf(0.975) if nu_text == "∞" else stats.t.ppf(0.975, int(nu_text))


def _rows(u: dict, skip=()):
    return [(abs(c["contribution"] or 0.0), c.get("dof")) for c in u["components"]
            if c["symbol"] not in skip]


@pytest.fixture(scope="module", params=[(s, p) for p in ("demo", "short") for s in SPECS],
                ids=lambda x: f"{x[0]}-{x[1]}")
def run(request, tmp_path_factory):
    spec, programme = request.param
    d = tmp_path_factory.mktemp(f"{spec}-{programme}")
    if programme == "demo":
        assert main(["simulate", "--spec", spec, "--seed", "3", "--out", str(d)]) == 0
        protocol = None
    else:
        protocol = str(PINS / f"{spec}-small.toml")
        assert main(["simulate", "--spec", spec, "--protocol", protocol, "--seed", "7",
                     "--out", str(d)]) == 0
        csv = d / "readings.csv"
        text = csv.read_text(encoding="utf-8")
        cut = re.sub(r"(?m)^# rate_table_u_rel:.*\n", "", text)
        assert cut != text                          # the bench stated one: now it is gone
        csv.write_text(cut, encoding="utf-8")
    result = get(spec).calibrate(d / "readings.csv", protocol)
    return {"spec": spec, "programme": programme,
            "res": result.to_json(), "summary": result.summary()}


def _items(run):
    return {k: it for k, it in run["res"]["items"].items()
            if it["measured"] and it.get("uncertainty")}


def _summary_line(run, it) -> str:
    lines = [ln for ln in run["summary"].splitlines()
             if ln.strip().startswith(it["clause"] + " ") and f" {it['title']}:" in ln]
    assert len(lines) == 1, (it["key"], lines)
    return lines[0]


def test_k_is_t_of_the_printed_nu_and_nu_is_welch_satterthwaite(run):
    checked = 0
    for key, it in _items(run).items():
        u = it["uncertainty"]
        if u["k"] is None or u.get("k_source") != "welch-satterthwaite":
            continue
        nu = _ws(u["u_c"], _rows(u))
        assert u["nu_eff"] == pytest.approx(nu, rel=1e-9) or (
            math.isinf(nu) and (u["nu_eff"] is None or u["nu_eff"] > NU_INFINITE)), key
        printed = _nu_printed(nu)
        k = _t(printed)
        assert u["k"] == pytest.approx(k, rel=1e-12), (key, u["k"], printed)
        assert u["U"] == pytest.approx(k * u["u_c"], rel=1e-12), key
        checked += 1
        line = _summary_line(run, it)
        if it.get("upper_bound") is not None:       # U above a non-negative value: the
            assert "upper bound" in line, (key, line)   # interval [0, value + U] is stated
            continue
        m = re.search(r"\(k = ([0-9.]+), ν_eff = ([0-9]+|∞), p = 95 %\)", line)
        assert m, (key, line)
        assert m.group(2) == printed, (key, line, nu)
        assert float(m.group(1)) == float(f"{k:.3g}"), (key, line, k)
    assert checked >= 3, checked


def test_bound_condition_states_k_of_the_rest(run):
    stated = 0
    for key, it in _items(run).items():
        u = it["uncertainty"]
        bc = it["details"].get("bound_condition")
        if not bc or "reach_rest" in bc or "b" in bc:
            # value ± (a + k·u_rest) only: a dispersion's one-sided limit (IEC noise items,
            # tests/test_rate_bound_u_c.py) and the extreme of magnitudes with each point's
            # bound (JJF K_t, B_t, tests/test_jjf_slope_bound.py) state no k
            continue
        rest = _rows(u, skip=set(bc["a_lines"]))
        u_rest = math.sqrt(sum(c * c for c, _ in rest))
        nu_rest = _ws(u_rest, rest)
        assert u["nu_eff"] == pytest.approx(nu_rest, rel=1e-9), key
        k = _t(_nu_printed(nu_rest))
        assert u["k"] is None
        assert u["U"] == pytest.approx(bc["a"] + k * u_rest, rel=1e-12), key
        stated += 1
    # the short programme leaves the table's u unstated: K (JJF) or a_BASE and 5.1.3.2 (IEC)
    assert stated >= (1 if run["programme"] == "short" else 0), stated


def test_items_computed_with_the_scale_factor_carry_its_nu(run):
    items = _items(run)
    sf = items["scale_factor"]
    usf = sf["uncertainty"]
    u_rel = usf["u_c"] / abs(sf["value"])
    nu_k = _ws(usf["u_c"], _rows(usf))
    carried = []
    for key, it in items.items():
        if key == "scale_factor":
            continue
        for c in it["uncertainty"]["components"]:
            if c["symbol"] == "e_K" or (c["u"] and c["u"] == pytest.approx(u_rel, rel=1e-12)):
                assert c["u"] == pytest.approx(u_rel, rel=1e-12), (key, c)
                dof = math.inf if c["dof"] is None else c["dof"]
                assert dof == pytest.approx(nu_k, rel=1e-9), (key, c["symbol"], dof, nu_k)
                carried.append(key)
    want = {"jjf1535-2015": {"bias", "bias_stability", "g_sensitivity", "angle_random_walk"},
            "iec62047-20": {"g_sensitivity"}}[run["spec"]]
    assert want <= set(carried), (want, carried)
    if run["spec"] == "iec62047-20":
        # 5.3.3.2 is the bias's budget shifted by Out,typ: the same lines, each with its ν
        b = items["bias"]["uncertainty"]
        ib = items["initial_bias_variation"]["uncertainty"]
        assert [(c["symbol"], c["u"], c["dof"]) for c in ib["components"]] == \
            [(c["symbol"], c["u"], c["dof"]) for c in b["components"]]
        assert ib["u_c"] == pytest.approx(b["u_c"], rel=1e-12)
