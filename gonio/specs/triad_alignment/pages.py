"""Report pages of the triad calibration: the alignment-matrix table and the
temperature-model page, as one self-contained HTML file (figures inline as SVG).

These are the pages the certificate would carry for the ``triad-alignment``
specification; the optical draft's certificate renderer (its own package) is built around
the draft's items, so the pages are written as their own document (``--report FILE`` of
``gonio align`` and ``gonio thermal-model``). Every value is shown with its expanded
uncertainty U (coverage probability 0.9545, stated 95.45 % as on the certificate, k stated), U to two significant digits and the
value to the same decimal place (JCGM 100 7.2.6, via :mod:`gonio.report.i18n`).
"""

from __future__ import annotations

import html
import math

import numpy as np
from matplotlib.figure import Figure
from scipy import stats

from gonio.specs.triad_alignment.thermal_model import Compensation, ThermalModelResult
from gonio.specs.triad_alignment.analysis import COVERAGE, OFFDIAG, AlignmentResult, cross_axis_table
from gonio.specs.triad_alignment.calibration import (alignment_items, bound_condition, fit_part,
                                                    total_coverage_factor)
from gonio.atomic import write_text
from gonio.report.figure_files import figure_bytes
from gonio.report.i18n import decimals_for_sig, display, display_uncertainty, round_half_up
from gonio.report.stated import item_nums
from gonio.result.statement import p_text

_CSS = ("body{font-family:'DejaVu Sans',sans-serif;font-size:10pt;margin:2em}"
        "table{border-collapse:collapse;margin:0.5em 0 1em}"
        "td,th{border:1px solid #999;padding:2px 6px;text-align:right}"
        "th{background:#eee}h1{font-size:14pt}h2{font-size:12pt;margin-top:1.5em}"
        ".note{color:#555;font-size:9pt}")


def value_with_u(value: float, big_u: float) -> str:
    """'value ± U' with U to 2 significant digits and the value to U's decimal place.

    >>> value_with_u(49.99371, 0.0028)
    '49.9937 ± 0.0028'
    """
    if not (math.isfinite(big_u) and big_u > 0):
        return round_half_up(value, decimals_for_sig(value, 6)) if math.isfinite(value) else "—"
    u_txt = display_uncertainty(big_u)
    dec = len(u_txt.split(".")[1]) if "." in u_txt else 0
    return f"{round_half_up(value, dec)} ± {u_txt}"


def _svg(fig: Figure) -> str:
    text = figure_bytes(fig, "svg").decode("utf-8")
    return text[text.find("<svg"):]


def _table(header, rows) -> str:
    h = "".join(f"<th>{html.escape(str(c))}</th>" for c in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>"
                   for r in rows)
    return f"<table><tr>{h}</tr>{body}</table>"


def certified_cell(item, factor: float = 1.0) -> str:
    """The certificate's cell of an item: "value ± U (k = …)" by the one statement rule
    (:func:`gonio.report.stated.item_nums`, as the certificate's matrix table states it, with
    the item's own k), or "[lo, hi]" for an item stated by its interval (a bound-condition
    statement has no k). ``factor`` scales value and U (‰: 1e3).

    >>> from gonio.result.model import Item, Uncertainty
    >>> u = Uncertainty([], 0.01, 0.0252, 2.52, 6.0, None, 0.9545, "t")
    >>> certified_cell(Item("M_xy", "m", "§4", "1", 0.88099, uncertainty=u))
    '0.881 ± 0.025 (k = 2.52)'
    """
    n = item_nums(item.to_json(), f"items.{item.key}", sig=6, factor=factor)
    if n["interval"] is not None:
        lo, hi = n["interval"]["ends"]
        return f"{n['value']} [{lo}, {hi}]"
    if n["U"] is None:
        return str(n["value"] or "—")
    return f"{n['value']} ± {n['U']} (k = {n['k']})"


#: The bias cell keeps its name (the certificate's renderer and tests use it).
certified_b = certified_cell


def with_k(value: float, big_u: float, k: float) -> str:
    """'value ± U (k = …)': :func:`value_with_u` with the coverage factor of this cell's own
    budget (as the certificate prints k: 3 significant digits, ``display("k", …)``).

    >>> with_k(49.99371, 0.0028, 2.0435)
    '49.9937 ± 0.0028 (k = 2.04)'
    """
    txt = value_with_u(value, big_u)
    return txt if "±" not in txt else f"{txt} (k = {display('k', k)})"


def alignment_page(res: AlignmentResult, figure: Figure | None = None,
                   static_s: float = 0.0) -> str:
    """HTML section: M, b, M⁻¹, scale factors, misalignment angles, cross-axis
    sensitivities (IEC 62047-20 5.2), residual leakage and averaging time. M, S, L and b
    are shown with the U of the certified items (:func:`alignment_items`: the fit and the rate
    table's Type B line, k from the Welch–Satterthwaite ν_eff; b the long-term bias, the
    in-run fit plus the bias instability of a static record of ``static_s`` seconds, with its
    own k), so the page agrees with the certificate; M⁻¹, the scale factors, angles and the
    in-run biases in °/s with the k of their own total (:func:`total_coverage_factor`, the
    smallest ν of the fit)."""
    items = alignment_items(res, 0, static_s)
    unit = res.output_unit or "output"
    m = res.system_matrix
    tb = res.type_b or {}
    nu_min = float(np.min(res.dof))

    def derived_cell(name: str, n: int, value: float, factor: float = 1.0) -> str:
        """Element n of derived quantity ``name``, one statement as the certified items: where
        the rate table enters it (a > 0), the bound-condition interval value ± (a + k·u_fit)
        (:func:`bound_condition`, no k of the whole); else value ± U (k = …), k its own."""
        u = float(np.ravel(res.u_derived[name])[n])
        u_b = float(np.ravel(tb["u_derived"][name])[n]) if tb else 0.0
        a = float(np.ravel(tb["a_derived"][name])[n]) if tb else 0.0
        if a > 0:
            bc = bound_condition(value, a, fit_part(u, u_b), nu_min)
            return f"{value_with_u(value * factor, bc['U'] * factor)} (bound condition)"
        k = total_coverage_factor(u, u_b, nu_min)
        return with_k(value * factor, k * u * factor, k)

    out = [f"<h2>Alignment matrix (p = {p_text(COVERAGE)} %, one statement per cell: where the "
           "rate table enters, the bound-condition interval value ± (a + k·u) — the table's "
           "errors at their bounds, worst combination, a, plus k·u of the fit, no k of the "
           "whole; elsewhere value ± U with the cell's own k)</h2>",
           f"<p>System matrix M ({html.escape(unit)} per °/s) and bias b ({html.escape(unit)}), "
           f"G = M ω + b, from {res.n_dwells} dwells"
           f"{' (robust fit)' if res.robust else ''}; b as the certificate states b_i: "
           f"{html.escape(items['b_x'].details['stated'])}.</p>"]
    rows = [[f"gyro {a}"] + [certified_cell(items[f"M_{a}{b}"]) for b in "xyz"]
            + [certified_cell(items[f"b_{a}"])]
            for a in "xyz"]
    out.append(_table(["", "ω_x", "ω_y", "ω_z", "b"], rows))
    a = res.alignment_matrix
    out.append("<p>Alignment matrix M⁻¹ (°/s per unit output): ω̂ = M⁻¹ (G − b).</p>")
    out.append(_table(["", "G_x", "G_y", "G_z"],
                      [[f"ω_{r}"] + [derived_cell("alignment_matrix", 3 * i + j, a[i, j])
                                     for j in range(3)] for i, r in enumerate("xyz")]))
    sc, ps, bd = res.derived["scale"], res.derived["psi_rad"], res.derived["bias_dps"]
    out.append(_table(["gyro", f"scale factor ({unit}/(°/s))", "misalignment ψ (mrad)",
                       "in-run bias (°/s), this record's fit"],
                      [[a_, derived_cell("scale", i, sc[i]),
                        derived_cell("psi_rad", i, ps[i], 1e3),
                        derived_cell("bias_dps", i, bd[i])]
                       for i, a_ in enumerate("xyz")]))
    tab = cross_axis_table(res)
    out.append("<p>Cross-axis sensitivity S_ij = M_ij/M_ii (IEC 62047-20 5.2), in ‰; "
               "residual leakage after M⁻¹ (stated 0), in ‰; each cell its certified "
               "statement (the bound-condition interval, as on the certificate). The JCGM 100 "
               "U and the Monte Carlo u of these items are in results.json, not certified.</p>")
    rows = []
    for r in tab.itertuples(index=False):
        rows.append([f"gyro {r.gyro} ← ω_{r.about}",
                     certified_cell(items[f"S_{r.gyro}{r.about}"], 1e3),
                     certified_cell(items[f"L_{r.gyro}{r.about}"], 1e3)])
    out.append(_table(["", "S before", "leakage after"], rows))
    if res.averaging is not None:
        av = res.averaging
        out.append(f"<p>Averaging time (Allan deviation): limit {av.noise_limit_dps:.4g} °/s "
                   f"(ω = {av.test_rate_dps:g} °/s, ψ_T = {av.target_deg:g}°, 1/10); τ ≥ "
                   f"{max(av.tau_needed_s):g} s; shortest dwell {av.shortest_dwell_s:g} s — "
                   f"{'sufficient' if av.sufficient else 'NOT sufficient'}.</p>")
    if res.outliers:
        out.append("<p>Down-weighted readings: " + ", ".join(
            f"line {o['line']} ({o['channel']}, weight {o['weight']:.2f})" for o in res.outliers)
            + "</p>")
    if figure is not None:
        out.append(_svg(figure))
    return "\n".join(out)


def thermal_page(res: ThermalModelResult, compensation: dict | None = None,
                 figures: dict | None = None) -> str:
    """HTML section: per gyro the chosen orders, coefficients with U, predictions with U at
    a few temperatures, the ramp analysis and the compensation summary."""
    out = [f"<h2>Temperature and supply model (reference {res.reference_c:g} °C, "
           f"{res.reference_v:g} V; order criterion {html.escape(res.criterion)})</h2>"]
    for ch, m in res.channels.items():
        out.append(f"<h3>gyro {ch} — temperature: {html.escape(m.temperature)}, ϑ "
                   f"{m.theta_range[0]:.1f} … {m.theta_range[1]:.1f} °C</h3>")
        rows = []
        for name, f in (("K", m.scale), ("b (°/s)", m.bias), ("ARW (°/√h)", m.arw)):
            if f is None:
                continue
            kf = stats.t.ppf(0.5 + COVERAGE / 2, f.dof)
            c = f.coefficients()
            for key in c:
                if key.startswith("u_"):
                    continue
                rows.append([name, f"{f.n_t}/{f.n_u}", key, with_k(c[key], kf * c['u_' + key], kf)])
        out.append(_table(["model", "order ϑ/U", "term", "coefficient ± U"], rows))
        g = m.prediction_grid(6)
        kb = stats.t.ppf(0.5 + COVERAGE / 2, m.bias.dof)
        ks = stats.t.ppf(0.5 + COVERAGE / 2, m.scale.dof)
        out.append(_table(["ϑ (°C)", "U (V)", "K ± U", "b (°/s) ± U"],
                          [[f"{r.theta_c:.1f}", f"{r.u_v:+.2f}", with_k(r.scale, ks * r.u_scale, ks),
                            with_k(r.bias_dps, kb * r.u_bias_dps, kb)]
                           for r in g.itertuples(index=False)]))
        if m.ramp is not None:
            ra = m.ramp
            out.append(f"<p>Ramps: static-soak model rms error {ra.rms_static_model_dps:.3g} °/s; "
                       f"with γ·dϑ/dt {ra.rms_with_ramp_term_dps:.3g} °/s (γ = "
                       f"{ra.gamma_dps_per_c_per_s:.3g} (°/s)/(°C/s)); with a lag "
                       f"({ra.lag_text()}) {ra.rms_with_lag_dps:.3g} °/s; hysteresis "
                       f"{ra.hysteresis_dps:.3g} °/s.</p>")
        c: Compensation | None = (compensation or {}).get(ch)
        if c is not None:
            out.append(_table(["residual", "before", "after"], [
                ["bias rms (°/s)", f"{c.rms_bias_before_dps:.3g}", f"{c.rms_bias_after_dps:.3g}"],
                ["scale-factor rms (ppm)", f"{c.rms_scale_before_rel * 1e6:.3g}",
                 f"{c.rms_scale_after_rel * 1e6:.3g}"],
                ["bias on ramps rms (°/s)", f"{c.rms_ramp_before_dps:.3g}",
                 f"{c.rms_ramp_after_dps:.3g}"]]))
        if figures and ch in figures:
            out.append(_svg(figures[ch]))
    return "\n".join(out)


def write_report(path, sections: list[str], title: str) -> None:
    """One self-contained HTML file with the given sections, written atomically."""
    doc = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{_CSS}</style></head><body><h1>{html.escape(title)}</h1>"
           + "\n".join(sections)
           + "<p class='note'>Uncertainties: GUM Type A from the fit residuals (JCGM 100), "
             "Monte Carlo check (JCGM 101); see docs/alignment.md and docs/thermal-model.md."
             "</p></body></html>\n")
    write_text(path, doc)


__all__ = ["alignment_page", "thermal_page", "write_report", "value_with_u", "with_k",
           "certified_cell", "bound_cell", "OFFDIAG"]
