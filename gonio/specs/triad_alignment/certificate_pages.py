"""The certificate of a gyro-triad calibration (``triad-alignment``), rendered by the shared
certificate machinery (:mod:`gonio.report.render` blocks and renderers, the per-item
parts of :mod:`gonio.report.rate_certificate`: header, closing statements, figures, writer).

Its own pages: the **alignment-matrix table** (M and b with each element's U and k, M⁻¹, the
cross-axis sensitivities before and the residual leakage after alignment, the averaging time
chosen from the Allan deviation), the uncertainty of M and b (GUM and Monte Carlo), and — when
the readings include a thermal programme — the **temperature-model page** (the certified
K(ϑ, U), b(ϑ, U) at the programme's set points and supply levels and ARW(ϑ) at the set points,
each with its U and k; the order-selection criterion; the polynomial coefficients as
information; the ramp analysis and the before/after compensation). Every number of an item is a :class:`~gonio.report.stated.Num`
whose ``data-src`` is its path in ``results.json``. The text is data in
:mod:`gonio.specs.triad_alignment.certificate`; this module is the specification's rendering
side (it imports the report), called by :mod:`gonio.specs.triad_alignment.outputs`.
"""

from __future__ import annotations

import math


from gonio.report.header import certificate_id, conformity_section, is_draft
from gonio.report.i18n import (display, display_uncertainty, reason_text, rule_at_U,
                               translator)
from gonio.report.rate_certificate import (closing_blocks, figure_blocks, header_blocks,
                                           screening_blocks, write_spec_certificate)
from gonio.report.provenance import is_virtual
from gonio.report.render import Block
from gonio.report.stated import interval_legend, item_nums, num
from gonio.result.statement import unit_text
from gonio.specs import get
from gonio.specs.triad_alignment import certificate as content
from gonio.specs.triad_alignment.figures import (alignment_panels, thermal_check_panels,
                                                 thermal_model_panels)

AXES = "xyz"
OFFDIAG = ("xy", "xz", "yx", "yz", "zx", "zy")


def _t(lang: str):
    text = content.TEXT
    return lambda key, **kw: text[key][1 if lang == "zh" else 0].format(**kw)


def _why(text: str, L: dict) -> str:
    """A reason (or an item's title) in the certificate's language, by the triad's phrases."""
    return reason_text(text, L, content.PHRASES_ZH)


def _pm(res: dict, key: str, with_k: bool = False) -> list | str:
    """Cell "value ± U" of an item, each number at U's decimal place (JCGM 100 7.2.6);
    ``with_k`` adds the item's own k ("(k = 2.42)") where the table's k column is another's."""
    it = res["items"][key]
    if not it["measured"]:
        return "—"
    n = item_nums(it, f"items.{key}", sig=6)          # the one statement rule
    if n["interval"] is not None:                    # a bound-condition statement: no k
        lo, hi = n["interval"]["ends"]
        return [n["value"], " [", lo, ", ", hi, "]"]
    if n["U"] is None:
        return [n["value"] or "—"]
    return [n["value"], " ± ", n["U"]] + ([" (k = ", n["k"], ")"] if with_k and n["k"] else [])


def _pm_scaled(v: float, U: float, f: float = 1.0) -> str:
    """A derived number (not an item) and its U, scaled by ``f``, at U's decimal place."""
    if v is None or U is None:
        return "—"
    return f"{display(rule_at_U(U * f, 6), v * f)} ± {display_uncertainty(U * f)}"


def alignment_blocks(res: dict, T, L: dict) -> list[Block]:
    """The alignment-matrix page (module docstring)."""
    out: list[Block] = [Block("h", T("h_alignment"))]
    items = res["items"]
    if not items["M_xx"]["measured"]:
        out.append(Block("p", [f"{L['not_measured']}: {_why(items['M_xx']['reason'], L)}"]))
        return out
    al = res["extra"]["alignment"]
    unit = al["output_unit"] or "output"
    out.append(Block("p", [T("alignment_note", unit=unit, n=al["n_dwells"],
                             robust=T("robust") if al["robust"] else "")]))
    rows = []
    for i, a in enumerate(AXES):
        rows.append([f"{T('gyro')} {a}"] + [_pm(res, f"M_{a}{b}", with_k=True) for b in AXES]
                    + [_pm(res, f"b_{a}", with_k=True)])
    out.append(Block("table", (["", "ω_x", "ω_y", "ω_z", f"b ({unit})"], rows),
                     {"widths": (0.08, 0.23, 0.23, 0.23, 0.23), "id": "alignment-matrix"}))
    inv = res["extra"]["alignment_inverse"]

    def inv_cell(n: int) -> list:
        """M⁻¹ element n: its bound-condition interval, as M's cells (``extra.alignment_inverse``,
        decided in the calibration)."""
        return [_pm_scaled(inv[n]["value"], inv[n]["U"]), f" ({T('bound_tag')})"]
    out.append(Block("sub", T("sub_inverse", unit=unit)))
    out.append(Block("table", (["", "G_x", "G_y", "G_z"], [
        [f"ω_{a}"] + [inv_cell(3 * i + j) for j in range(3)]
        for i, a in enumerate(AXES)]), {"widths": (0.1, 0.3, 0.3, 0.3), "id": "alignment-inverse"}))
    out.append(Block("sub", T("sub_cross")))
    out.append(Block("p", [T("cross_note")]))
    crow = []

    def cell(key: str) -> list:
        """S or L by the one statement rule (its interval with the ν_eff its coverage factor
        came from, as summary.txt, the DCC and the records' pages state it; or value ± U
        (k = …))."""
        got = _pm(res, key, with_k=True)
        it = res["items"][key]
        nu = item_nums(it, f"items.{key}", sig=6)["interval_nu"] if it["measured"] else None
        return got + [" (ν_eff = ", nu, ")"] if nu is not None and isinstance(got, list) \
            else got

    for p in OFFDIAG:
        crow.append([f"{p[0]} ← ω_{p[1]}", cell(f"S_{p}"), cell(f"L_{p}")])
    out.append(Block("table", ([T("pair"), T("S_col"), T("L_col")], crow),
                     {"widths": (0.2, 0.4, 0.4), "id": "cross-axis"}))
    av = items["averaging_time"]
    if av["measured"]:
        d = av["details"]
        out.append(Block("p", [T("averaging", tau=num(res, "items.averaging_time.value", "sig3"),
                                 lim=display("sig3", d["noise_limit_dps"]),
                                 w=display("sig3", d["test_rate_dps"]),
                                 psi=display("sig3", d["target_deg"]),
                                 dwell=display("sig3", d["shortest_dwell_s"]),
                                 ok=T("sufficient") if d["sufficient"] else T("insufficient"))]))
    else:
        out.append(Block("p", [f"{_why(av['title'], L)}: {L['not_measured']}: {_why(av['reason'], L)}"]))
    if al["outliers"]:
        out.append(Block("p", [T("outliers", list=", ".join(
            f"line {o['line']} ({o['channel']}, w = {o['weight']:.2f})" for o in al["outliers"]))]))
    # uncertainty of M and b: the certified statement's budget, one row per item
    out.append(Block("sub", T("h_unc")))
    trials = ((items["M_xx"].get("details") or {}).get("not_certified", {})
              .get("monte_carlo") or {}).get("trials")
    tb = al.get("type_b") or {"rate_u_rel": 0.0, "orientation_u_rad": 0.0}
    out.append(Block("p", [T("unc_note", mc=T("mc_trials", n=trials) if trials else T("mc_none"),
                             rate=display("sig3", tb["rate_u_rel"]),
                             bound=display("sig3", math.degrees(tb["orientation_u_rad"])
                                           * math.sqrt(3.0)))]))
    # what each item's interval is (the shared legend), its clauses in the page's language
    legend = interval_legend({k: {**it, "clause": _why(str(it.get("clause") or ""), L)}
                              for k, it in items.items()}, L)
    if legend:
        out.append(Block("p", [legend]))
    if (items["M_xx"].get("details") or {}).get("bound_condition"):
        out.append(Block("p", [T("bound_note", rate_bound=display(
            "sig3", (al.get("type_b") or {}).get("rate_bound_rel", 0.0)),
            bound=display("sig3", math.degrees(tb["orientation_u_rad"]) * math.sqrt(3.0)))]))
    urows = []
    for key in [f"M_{a}{b}" for a in AXES for b in AXES] + [f"b_{a}" for a in AXES]:
        urows.append([key] + _budget_cells(res, key) + [items[key]["unit"]])
    out.append(Block("table", (["", T("a_col"), T("u_col"), T("nu"), "k", "U", L["unit"]],
                               urows),
                     {"widths": (0.08, 0.14, 0.14, 0.08, 0.08, 0.14, 0.34),
                      "id": "uncertainty"}))
    return out


def _budget_cells(res: dict, key: str) -> list:
    """The certified statement's budget of item ``key`` in one row, U = a + k·u: a bound-
    condition item (k None) its table's worst-case offset a, the other lines' u, their ν
    and k (``details.bound_condition``); any other item "—" for a, its u_c, ν_eff, k. Each
    row its own k; the row's U is the item's certified U."""
    it = res["items"][key]
    unc = it["uncertainty"]
    bc = (it.get("details") or {}).get("bound_condition")
    if unc.get("k") is None and bc:     # the interval's half-width as its budget's sum
        base = f"items.{key}.details.bound_condition"
        return [num(res, f"{base}.a_table", "sig2"), num(res, f"{base}.u_rest", "sig2"),
                num(res, f"{base}.nu_rest", "nu"), num(res, f"{base}.k_rest", "k"),
                num(res, f"{base}.U", "U")]
    return ["—", num(res, f"items.{key}.uncertainty.u_c", "sig2"),
            num(res, f"items.{key}.uncertainty.nu_eff", "nu"),
            num(res, f"items.{key}.uncertainty.k", "k"),
            num(res, f"items.{key}.uncertainty.U", "U")]


def thermal_blocks(res: dict, T, L: dict, lang: str) -> list[Block]:
    """The temperature-model page (module docstring); not measured → the reason."""
    out: list[Block] = [Block("h", T("h_thermal"))]
    tm = res["extra"].get("thermal_model")
    if tm is None:
        it = res["items"].get("thermal_model", {})
        out.append(Block("p", [f"{L['not_measured']}: {_why(it.get('reason', ''), L)}"]))
        return out
    crit = T("crit_" + tm["criterion"])
    first = next(iter(tm["channels"].values()))
    out.append(Block("p", [T("thermal_note", tref=display("sig3", tm["reference_c"]),
                             vref=display("sig3", tm["reference_v"]), crit=crit,
                             tsrc=T(first["temperature_source"]),
                             src=tm["source"]["file"] + f" (SHA-256 {tm['source']['sha256'][:16]}…)")]))
    for ch, c in tm["channels"].items():
        th, uv = c["theta_range_c"], c["supply_range_v"]
        out.append(Block("sub", T("sub_channel", ch=ch, lo=f"{th[0]:.1f}", hi=f"{th[1]:.1f}",
                                  ulo=f"{uv[0]:+.2f}", uhi=f"{uv[1]:+.2f}")))
        out += certified_point_blocks(res, ch, c, T, lang)
        rows = []
        for name, part in (("K", "scale"), ("b", "bias"), ("ARW", "arw")):
            f = c.get(part)
            if f is None:
                continue
            cand = sorted(f["candidates"], key=lambda r: r.get(f["criterion"], 0.0)) \
                if f["criterion"] in ("bic", "aic") else []
            if len(cand) > 1:
                out_line = T("orders_line", name=name, nt=f["order_temperature"],
                             nu=f["order_supply"], crit=f["criterion"].upper(),
                             nt2=cand[1]["order_temperature"], nu2=cand[1]["order_supply"],
                             d=display("sig3", cand[1][f["criterion"]] - cand[0][f["criterion"]]))
                out.append(Block("p", [out_line]))
            co = f["coefficients"]
            for term in [t for t in co if not t.startswith("u_")]:
                rows.append([name, f"{f['order_temperature']} / {f['order_supply']}",
                             {"c0": "1"}.get(term, term.replace("theta", "ϑ^").replace("u", "U^")),
                             display(rule_at_U(co["u_" + term], 6), co[term]),
                             display_uncertainty(co["u_" + term])])
        out.append(Block("sub", T("sub_coef")))
        out.append(Block("table", ([T("model"), T("order"), T("term"), T("coef"), "u"], rows),
                         {"widths": (0.1, 0.14, 0.1, 0.36, 0.3), "id": f"thermal-{ch}"}))
        ra = c.get("ramp")
        if ra:
            out.append(Block("p", [T("ramp", rms=display("sig3", ra["rms_static_model_dps"]),
                                     g=display("sig3", ra["gamma_dps_per_c_per_s"]),
                                     rmsg=display("sig3", ra["rms_with_ramp_term_dps"]),
                                     lag=content.lag_phrase(ra, lang,
                                                            lambda v: display("int", v)),
                                     rmsl=display("sig3", ra["rms_with_lag_dps"]),
                                     hys=display("sig3", ra["hysteresis_dps"]))]))
        cp = c.get("compensation")
        if cp:
            out.append(Block("sub", T("sub_comp")))
            out.append(Block("p", [T("comp_note")]))
            out.append(Block("table", ([T("residual"), T("before"), T("after")], [
                [T("r_bias"), display("sig3", cp["rms_bias_before_dps"]),
                 display("sig3", cp["rms_bias_after_dps"])],
                [T("r_scale"), display("sig3", cp["rms_scale_before_rel"] * 1e6),
                 display("sig3", cp["rms_scale_after_rel"] * 1e6)],
                [T("r_ramp"), display("sig3", cp["rms_ramp_before_dps"]),
                 display("sig3", cp["rms_ramp_after_dps"])]]),
                {"widths": (0.46, 0.27, 0.27), "id": f"compensation-{ch}"}))
    return out


def _k_of(res: dict, key: str) -> list | str:
    """The "k (ν)" cell of item ``key``'s column: its own coverage factor and the ν_eff it was
    computed from (k = t_p(⌊ν_eff⌋)), or for a bound-condition statement (no k of the whole)
    the k and ν of the lines beside the table's bound, k_rest = t_p(⌊ν_rest⌋)
    (U = a + k_rest·u_rest, ``details.bound_condition``); "—" where the item has no k."""
    it = res["items"][key]
    if not it["measured"]:
        return "—"
    if it["uncertainty"].get("k") is None and (it.get("details") or {}).get("bound_condition"):
        base = f"items.{key}.details.bound_condition"
        k, nu = f"{base}.k_rest", f"{base}.nu_rest"
    else:
        k, nu = f"items.{key}.uncertainty.k", f"items.{key}.uncertainty.nu_eff"
    k_cell = num(res, k, "k")
    if k_cell == "—":
        return "—"
    nu_cell = num(res, nu, "nu")
    return [k_cell] if nu_cell == "—" else [k_cell, "\u00a0(", nu_cell, ")"]


def certified_point_blocks(res: dict, ch: str, c: dict, T, lang: str = "en") -> list[Block]:
    """The certified values of gyro ``ch``: K and b at every set point (rows) and supply
    level (a value ± U and a k column each), ARW at every set point (a dispersion: its
    value, its one-sided χ² upper bound with p and the ν of that χ², no k) — the items
    ``K_<ch>_t<i>_v<j>``, ``b_<ch>_t<i>_v<j>``, ``ARW_<ch>_t<i>``."""
    items = res["items"]
    pts = [p for p in c.get("certified_points", ()) if p["model"] == "K"]
    temps = sorted({(p["t"], p["setpoint_c"], p["theta_c"]) for p in pts})
    levels = sorted({(p["v"], p["supply_v"]) for p in pts})
    if not temps:
        return []
    first_b = items.get(f"b_{ch}_t1_v1") or {}
    out = [Block("sub", T("sub_points")),
           Block("p", [T("points_note", tref=display("sig3", res["extra"]["thermal_model"]
                                                     ["reference_c"]),
                         bias=T("bias_" + (first_b.get("details") or {}).get("bias", "in-run")))])]
    for name in ("K", "b"):
        unit = (items.get(f"{name}_{ch}_t1_v1") or {}).get("unit", "")
        head = ["T (°C)", "ϑ (°C)"]
        by_interval = (items.get(f"{name}_{ch}_t1_v1") or {}).get(
            "uncertainty", {}).get("k", 0) is None
        for _, v in levels:
            head += [f"{name} ({display('sig3', v)} V) " + (T("interval_head") if by_interval
                                                              else "± U"), "k (ν)"]
        rows = []
        for i, t_set, theta in temps:
            row = [display("sig3", t_set), f"{theta:+.1f}"]
            for j, _ in levels:
                key = f"{name}_{ch}_t{i}_v{j}"
                row += [_pm(res, key), _k_of(res, key)] if key in items else ["—", "—"]
            rows.append(row)
        out.append(Block("p", [T("points_unit", name=name, unit=unit_text(unit))]))
        share = 0.8 / len(levels)
        out.append(Block("table", (head, rows), {
            "widths": (0.1, 0.1) + (share * 0.7, share * 0.3) * len(levels),
            "id": f"points-{name}-{ch}"}))
    arw = [(i, t) for i, t, _ in temps if f"ARW_{ch}_t{i}" in items]
    if arw:
        out.append(Block("table", (["T (°C)", "ARW (°/√h)", T("arw_upper"), T("nu")],
                                   [[display("sig3", t)] + _arw_cells(res, f"ARW_{ch}_t{i}", lang)
                                    for i, t in arw]),
                         {"widths": (0.2, 0.25, 0.4, 0.15), "id": f"points-ARW-{ch}"}))
        # its budget's u_c (the DCC states it beside the interval), one row per set point
        out.append(Block("p", [T("arw_budget")]))
        out.append(Block("table", (["T (°C)", "u_c (°/√h)", T("nu")], [
            [display("sig3", t), num(res, f"items.ARW_{ch}_t{i}.uncertainty.u_c", "sig2"),
             num(res, f"items.ARW_{ch}_t{i}.uncertainty.nu_eff", _nu_rule(res, f"ARW_{ch}_t{i}"))]
            for i, t in arw if res["items"][f"ARW_{ch}_t{i}"]["measured"]]),
            {"widths": (0.3, 0.4, 0.3), "id": f"points-ARW-budget-{ch}"}))
    return out


def _nu_rule(res: dict, key: str) -> str:
    """The display rule of item ``key``'s ν: a χ² interval's is the ν its bound was computed
    with, never ∞ ("nuchi2"); any other ν_eff "nu" (∞ above 1000, as k is computed)."""
    ks = (res["items"][key].get("uncertainty") or {}).get("k_source")
    return "nuchi2" if ks == "chi-square" else "nu"


def _arw_cells(res: dict, key: str, lang: str) -> list:
    """An ARW item's cells by the one statement rule (:func:`item_nums`): its value, its one
    statement ("≤ upper (p = 95.45 %)": the one-sided χ² interval [0, upper] at the certificate's p) and the ν of that
    χ²; an item stated by U (a result written before ARW was a dispersion) gives
    "value ± U (k = …)" and its ν_eff. Its u_c is in the budget table below it."""
    it = res["items"][key]
    if not it["measured"]:
        return ["—", "—", "—"]
    n = item_nums(it, f"items.{key}", sig=6)
    if n["statement"].interval is not None:
        return [n["value"] or "—", n["statement"].interval_text(lang, short=True),
                n["nu"] or "—"]
    return [n["value"] or "—", _pm(res, key, with_k=True), n["nu"] or "—"]


def _figure_series(result) -> dict:
    """``extra.figures`` of a stored triad result (what every figure draws)."""
    return result.extra.get("figures") or {}


def _channel_figure(result, ch: str) -> dict:
    """Gyro ``ch``'s thermal figures' data as stored: its fitted-model series
    (``extra.figures.thermal``) with its ramp analysis and compensation
    (``extra.thermal_model.channels``)."""
    tm = result.extra["thermal_model"]["channels"][ch]
    return {**_figure_series(result)["thermal"][ch], "ramp": tm.get("ramp"),
            "compensation": tm.get("compensation")}


def _draw_alignment(fig, spec, result, L, truth=None) -> None:
    data = _figure_series(result).get("alignment")
    if data is None:
        ax = fig.add_subplot(spec)
        ax.text(0.5, 0.5, L["not_measured"], ha="center", va="center",
                transform=ax.transAxes)
        return
    alignment_panels(fig, spec, data, (truth or {}).get("system_matrix"), L.get("_lang", "en"))


def triad_figures(result) -> list[tuple]:
    """(key, caption en, caption zh, draw) of the certificate's figures: the alignment figure,
    and per modelled gyro its model and its ramp / compensation figure, all drawn from the
    stored series (``extra.figures``, :mod:`gonio.specs.triad_alignment.figure_data`)."""
    text = content.TEXT
    figs = [("alignment", text["fig_alignment"][0], text["fig_alignment"][1], _draw_alignment)]
    for ch in (_figure_series(result).get("thermal") or {}):

        def model(fig, spec, r, L, truth=None, ch=ch):
            thermal_model_panels(fig, spec, _channel_figure(r, ch), L.get("_lang", "en"))

        def check(fig, spec, r, L, truth=None, ch=ch):
            thermal_check_panels(fig, spec, _channel_figure(r, ch), L.get("_lang", "en"))
        figs.append((f"thermal-model-{ch}", text["fig_model"][0].format(ch=ch),
                     text["fig_model"][1].format(ch=ch), model))
        figs.append((f"thermal-check-{ch}", text["fig_check"][0].format(ch=ch),
                     text["fig_check"][1].format(ch=ch), check))
    return figs


def triad_certificate_blocks(result, L: dict, lang: str, *, lab: dict | None) -> dict:
    """The certificate's content: header, alignment-matrix page (then the screening's
    findings and the statements of conformity the pipeline decided), temperature-model page,
    readings taken, signatures, statements, figures."""
    res = result.to_json()
    T = _t(lang)
    tb = (res["extra"].get("alignment") or {}).get("type_b")
    acc = "—" if not tb else T("std_accuracy", rate=display("sig3", tb["rate_u_rel"]),
                                bound=display("sig3", math.degrees(tb["orientation_u_rad"])
                                              * math.sqrt(3.0)))
    blocks = header_blocks(res, get(result.spec_key), L, lang, lab,
                           [T("std_table"), "—", acc, "—"])
    blocks += alignment_blocks(res, T, L)
    blocks += screening_blocks(res, L, content.PHRASES_ZH)
    name = translator(tables=content.PHRASES_ZH) if lang == "zh" else (lambda t: None)
    blocks += conformity_section(                    # the pipeline's decisions, rendered
        res["items"], L, lambda k: name(res["items"][k]["title"]) or res["items"][k]["title"],
        lambda k: unit_text(res["items"][k]["unit"]), lab)
    blocks += thermal_blocks(res, T, L, lang)
    zh = content.READINGS_TAKEN_ZH
    notes = res.get("readings_taken", [])
    if lang == "zh" and len(zh) == len(notes):
        notes = list(zh)
    blocks += closing_blocks(res, L, lab, T("readings_taken"), notes)
    blocks += figure_blocks(triad_figures(result), L, lang)
    return {"id": certificate_id(result, lab), "virtual": is_virtual(res, lab),
            "draft": is_draft(lab),
            "lab_name": lab["laboratory"]["name"] if lab else L["virtual_lab"],
            "blocks": blocks, "results": res}


def write_triad_certificate(result, out, *, truth=None, lab=None, lang: str = "en",
                            dcc: bool = False) -> dict:
    """``certificate.html`` and ``certificate.pdf`` of a triad calibration (with ``dcc`` also
    the DCC 3.3.0 XML of :mod:`gonio.report.item_dcc`), atomically."""
    dcc_fn = None
    if dcc:
        from gonio.report.item_dcc import item_dcc_bytes

        p = (result.extra.get("alignment") or {}).get("coverage_probability")

        def dcc_fn(r, *, lab, cert_id):
            return item_dcc_bytes(r, lab=lab, cert_id=cert_id,
                                  data=content, coverage_probability=p)
    return write_spec_certificate(result, out, triad_certificate_blocks, triad_figures(result),
                                  truth=truth, lab=lab, lang=lang, dcc_fn=dcc_fn)


__all__ = ["write_triad_certificate", "triad_certificate_blocks", "triad_figures",
           "alignment_blocks", "thermal_blocks"]
