"""Figures a rate-gyro laboratory expects, drawn on matplotlib Figure objects.

=========================  ===========================================================
:func:`draw_io_line`       input–output line of the scale-factor calibration, residuals below
:func:`draw_cw_ccw`        forward (CW) and reverse (CCW) fits: departure from the mean line
:func:`draw_temperature`   bias and scale factor against temperature
:func:`draw_allan`         Allan deviation with its confidence band and the five-term fit
:func:`draw_frequency`     amplitude (dB) and phase response with the −3 dB and 90° points
=========================  ===========================================================

Each ``draw_*`` takes ``(fig, spec, result, L, truth)`` like the optical certificate's
figures (a Figure, a SubplotSpec, a :class:`~gonio.kit.Result`, labels, the bench truth or
None); an item not measured gives a panel saying so.
:data:`FIGURES` lists them for the certificate.
"""

from __future__ import annotations

import math

import numpy as np

from gonio.report.i18n import display
from gonio.result.statement import item_statement
from gonio.specs import get
from gonio.units import dph_sqrt_hz_from_deg_sqrt_h


#: Figure text, (English, Chinese).
FIG_TEXT: dict[str, tuple[str, str]] = {
    "no_sf": ("scale factor not measured", "未测标度因数"),
    "no_asym": ("asymmetry not measured", "未测不对称度"),
    "no_temp": ("temperature items not measured", "未测温度项目"),
    "no_arw": ("angle random walk not measured", "未测角度随机游走"),
    "no_bw": ("bandwidth not measured", "未测带宽"),
    "F̄_j − F_r": ("F̄_j − F_r", "F̄_j − F_r"),
    "output y_j": ("output y_j", "输出 y_j"),
    "fit_line": ("fitted line, K = {K}", "拟合直线，K = {K}"),
    "fit_line_m1": ("fitted line of calibration m = 1, K_1 = {K}",
                    "第 1 次校准的拟合直线，K_1 = {K}"),
    "output": ("output ({u})", "输出（{u}）"),
    "rate": ("input rate Ω (°/s)", "输入角速率 Ω (°/s)"),
    "residual": ("residual v_j", "残差 v_j"),
    "cw": ("forward (CW)", "正转"), "ccw": ("reverse (CCW)", "反转"),
    "asym": ("asymmetry K_a = {v}", "不对称度 K_a = {v}"),
    "sym": ("symmetry = {v} {u}", "对称性 = {v} {u}"),
    "bias_dph": ("bias (°/h)", "零偏 (°/h)"),
    "temp": ("temperature (°C)", "温度 (°C)"),
    "adev": ("overlapping Allan deviation", "重叠 Allan 偏差"),
    "adev_fit": ("five-term fit: N → {a} °/√h, coefficient B {b} °/h",
                 "五项拟合：N → {a} °/√h，系数 B {b} °/h"),
    "fit_is_cert": (" (N is the certified ARW, {c})", "（N 即证书所给 ARW，{c}）"),
    "fit_not_cert": ("five-term fit, drawn only: N {a} °/√h, B {b} °/h (not certified)",
                     "五项拟合（仅作图）：N {a} °/√h，B {b} °/h（非证书值）"),
    "arw_cert": ("N/√τ at the certified ARW {v} °/√h ({c}, its own estimator)",
                 "N/√τ，证书所给 ARW {v} °/√h（{c}，其自身估计方法）"),
    "bi_cert": ("certified bias instability {v} °/h ({c}, its own estimator)",
                "证书所给零偏不稳定性 {v} °/h（{c}，其自身估计方法）"),
    "eq24": ("eq (24) as printed (not the Allan variance)", "按原文式（24）（非 Allan 方差）"),
    "gain": ("gain (dB)", "增益 (dB)"),
    "m3db": ("−3 dB at {f} Hz", "−3 dB 点 {f} Hz"),
    "p90": ("; 90° lag at {f} Hz", "；相位滞后 90° 点 {f} Hz"),
    "phase": ("phase (°)", "相位 (°)"),
    "freq": ("frequency (Hz)", "频率 (Hz)"),
}


def _t(L: dict, key: str, **kw) -> str:
    """Figure text ``key`` in the certificate's language (``L["_lang"]``)."""
    return FIG_TEXT[key][1 if L.get("_lang") == "zh" else 0].format(**kw)


def _stated(it) -> str:
    """An item's value as every output states it (the one statement rule)."""
    return item_statement(it.to_json() if hasattr(it, "to_json") else it).value_text


def _at_item(x: float, it) -> str:
    """A number drawn beside item ``it`` (e.g. one calibration's K) at the decimal place the
    item is stated to, so a legend never shows more digits than the certificate."""
    st = item_statement(it.to_json() if hasattr(it, "to_json") else it)
    if st.decimals is not None and not st.exponent:
        return display(f"dec{st.decimals}", x)
    return display("sig6", x)


def _near(x: float, it) -> str:
    """A fitted number beside the item it underlies (or 3 significant digits without one),
    at that item's decimal place."""
    return display("sig3", x) if it is None else _at_item(x, it)


def _item(result, *keys):
    for k in keys:
        it = result.items.get(k)
        if it is not None and it.measured:
            return it
    return None


def _role(result, role: str):
    """The measured item a figure draws for ``role``, as the specification names it in its
    certificate content (``FIGURE_ITEMS``: ``bias_temperature``, ``sf_temperature``,
    ``allan``, ``arw``, ``bias_instability``, ``bandwidth``); None when it names none or the item was not
    measured."""
    spec = get(result.spec_key)
    roles = spec.content_value("FIGURE_ITEMS")
    return _item(result, roles[role]) if role in roles else None


def _empty(ax, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="0.4")
    ax.set_xticks([])
    ax.set_yticks([])


def _io_points(it):
    """(rates, mean outputs, K, intercept, residual rows, label) of a scale-factor item, from
    JJF 1535's per-calibration fit (7.2.1: rest-removed means of the first calibration) or
    IEC 62047-20's single fit (5.1.3.1: outputs with the intercept b_BASE); None without.
    Each residual row is ``(rates, residuals)``: a calibration run that lost a point (a
    damaged file) has fewer rates than the first."""
    if it is None:
        return None
    d = it.details
    if "means_m" in d:
        r = np.asarray(d["rates_dps"], float)
        rates_m = d.get("rates_m") or [r] * len(d["residuals_m"])
        rows = [(np.asarray(rm, float), np.asarray(v, float))
                for rm, v in zip(rates_m, d["residuals_m"])]
        return (r, np.asarray(d["means_m"][0], float), float(d["K_m"][0]), float(d["F0_m"][0]),
                rows, "F̄_j − F_r")
    if "x_dps" in d and "y" in d:
        r, y = np.asarray(d["x_dps"], float), np.asarray(d["y"], float)
        K, b = float(it.value), float(d["b_BASE"])
        return r, y, K, b, [(r, y - (K * r + b))], "output y_j"
    return None


def draw_io_line(fig, spec, result, L, truth=None) -> None:
    """Rest-removed mean output against input rate (first calibration), the fitted line, and
    the residuals v_j in a panel below."""
    gs = spec.subgridspec(2, 1, height_ratios=(2, 1), hspace=0.08)
    ax, ax2 = fig.add_subplot(gs[0]), fig.add_subplot(gs[1])
    it = _item(result, "scale_factor")
    line = _io_points(it)
    if line is None:
        _empty(ax, _t(L, "no_sf"))
        ax2.set_visible(False)
        return
    r, y, K, F0, residuals, label = line
    o = np.argsort(r)
    ax.plot(r[o], y[o], "o", ms=3, label=_t(L, label) if label in FIG_TEXT else label)
    ax.plot(r[o], K * r[o] + F0, "-", lw=0.8,     # JJF: the first calibration's own K_1
            label=_t(L, "fit_line_m1" if "means_m" in it.details else "fit_line",
                     K=_at_item(K, it)))
    ax.set_ylabel(_t(L, "output", u=result.metadata.get("output_unit", "")))
    ax.legend(loc="upper left")
    ax.tick_params(which="both", labelbottom=False)   # minor log labels too
    for m, (rm, res) in enumerate(residuals):
        om = np.argsort(rm)
        ax2.plot(rm[om], res[om], "o-", ms=2, lw=0.6, label=f"m = {m + 1}")
    ax2.axhline(0, color="0.5", lw=0.6)
    ax2.set_xlabel(_t(L, "rate"))
    ax2.set_ylabel(_t(L, "residual"))
    ax2.legend(loc="best", ncol=3)


def draw_cw_ccw(fig, spec, result, L, truth=None) -> None:
    """Separate forward and reverse fits: each direction's F̄_j − K̄Ω_j with its own line.
    What differs between specifications (the item, where each direction's scale factor sits
    in its details, whether the null output is taken off, the axis label, the title) is the
    specification's ``CW_CCW`` in its certificate content (:func:`forward_reverse`)."""
    ax = fig.add_subplot(spec)
    line_it = _item(result, "scale_factor")
    line = _io_points(line_it)
    how = forward_reverse(result)
    a = _item(result, how["item"]) if how else None
    if line is None or a is None:
        _empty(ax, _t(L, "no_asym"))
        return
    r, y, K, F0, _, _ = line
    d = a.details
    off = F0 if how["null_output_off"] else 0.0
    for sel, name, (key, i) in ((r > 0, _t(L, "cw"), how["cw"]), (r < 0, _t(L, "ccw"), how["ccw"])):
        kk = d[key] if i is None else d[key][i]
        rr, yy = r[sel], y[sel]
        o = np.argsort(rr)
        p = np.polyfit(rr, yy, 1)
        ax.plot(rr[o], yy[o] - K * rr[o] - off, "o", ms=3,
                label=f"{name}: K = {_at_item(kk, line_it)}")
        ax.plot(rr[o], np.polyval(p, rr[o]) - K * rr[o] - off, "-", lw=0.8)
    ax.axhline(0, color="0.5", lw=0.6)
    ax.set_xlabel(_t(L, "rate"))
    ax.set_ylabel(how["ylabel"])
    ax.legend(loc="best")
    ax.set_title(_t(L, how["title"], v=_stated(a), u=a.unit))


def forward_reverse(result) -> dict | None:
    """The specification's description of its forward/reverse figure, ``CW_CCW`` in its
    certificate content (``Specification.certificate_content``): ``item`` (the key of the
    item whose details hold the directions), ``cw``/``ccw`` ((details key, index or None) of
    each direction's scale factor), ``null_output_off`` (take the fitted null output off the
    points), ``ylabel`` and ``title`` (a :data:`FIG_TEXT` key formatted with the item's
    value ``v`` and unit ``u``). None: the specification has no such figure."""
    spec = get(result.spec_key)
    return spec.content_value("CW_CCW")


def draw_temperature(fig, spec, result, L, truth=None) -> None:
    """Bias (°/h) against temperature, and the scale factor on a second axis."""
    ax = fig.add_subplot(spec)
    b, k = _role(result, "bias_temperature"), _role(result, "sf_temperature")
    if b is None and k is None:
        _empty(ax, _t(L, "no_temp"))
        return
    if b is not None:
        T = np.asarray(b.details["temperatures_c"], float)
        B = np.asarray(b.details["bias_dph"], float)
        o = np.argsort(T)
        ax.plot(T[o], B[o], "o-", ms=4, color="C0", label=_t(L, "bias_dph"))
        ax.set_ylabel(_t(L, "bias_dph"), color="C0")
    if k is not None:
        ax2 = ax.twinx()
        T = np.asarray(k.details["temperatures_c"], float)
        K = np.asarray(k.details["K_i"], float)
        o = np.argsort(T)
        ax2.plot(T[o], K[o], "s--", ms=4, color="C1", label="K")
        ax2.set_ylabel(f"K ({result.metadata.get('output_unit', '')}/(°/s))", color="C1")
        ax2.grid(False)
    ax.set_xlabel(_t(L, "temp"))


def _same(certified, fitted) -> bool:
    """Whether a certified value is the five-term fit's own number (the same estimator)."""
    return fitted is not None and math.isclose(float(certified), float(fitted), rel_tol=1e-9)


def _fit_label(L: dict, f: dict, arw, bi) -> str:
    """The five-term fit's legend: its N and B beside the certified items they are, or
    marked as drawn only when the certified ARW (or bias instability) comes from another
    estimator (IEC 62047-20 5.4.5.2 reads a slope −½ line at 1 h), so that the figure never
    shows a number beside the stated value as if it were the one certified."""
    arw_fit = arw is not None and _same(arw.value, f["arw_deg_sqrt_h"])
    bi_fit = bi is None or _same(bi.value, f.get("bias_instability_dph"))
    if (arw is None or arw_fit) and bi_fit:
        label = _t(L, "adev_fit", a=_near(f["arw_deg_sqrt_h"], arw), b=_near(f["B"], bi))
        return label + (_t(L, "fit_is_cert", c=arw.clause) if arw_fit else "")
    return _t(L, "fit_not_cert", a=_near(f["arw_deg_sqrt_h"], arw), b=_near(f["B"], bi))


def draw_allan(fig, spec, result, L, truth=None) -> None:
    """Overlapping Allan deviation (°/h) with its χ² band and the fitted five-term model."""
    from gonio.analysis.noise import model_adev

    ax = fig.add_subplot(spec)
    it = _role(result, "allan")
    if it is None or "allan" not in it.details:
        _empty(ax, _t(L, "no_arw"))
        return
    a = it.details["allan"]
    tau = np.asarray(a["tau_s"], float)
    adev = np.asarray(a["adev_dph"], float)
    ax.fill_between(tau, np.asarray(a["ci_low"], float), np.asarray(a["ci_high"], float),
                    color="C0", alpha=0.2, lw=0)
    ax.loglog(tau, adev, "o", ms=2.5, color="C0", label=_t(L, "adev"))
    f = it.details["fit"]
    arw, bi = _role(result, "arw"), _role(result, "bias_instability")
    ax.loglog(tau, model_adev(tau, f["Q"], f["N"], f["B"], f["K"], f["R"]), "-", color="C3",
              lw=1, label=_fit_label(L, f, arw, bi))
    if arw is not None and not _same(arw.value, f["arw_deg_sqrt_h"]):
        # the certified ARW comes from another estimator than the fit's N: its own line
        ax.loglog(tau, dph_sqrt_hz_from_deg_sqrt_h(arw.value) / np.sqrt(tau), ":", color="0.2",
                  lw=1.0, label=_t(L, "arw_cert", v=_stated(arw), c=arw.clause))
    else:
        ax.loglog(tau, f["N"] / np.sqrt(tau), ":", color="0.4", lw=0.8, label="N/√τ")
    if bi is not None and not _same(bi.value, f.get("bias_instability_dph")):
        ax.plot([], [], " ", label=_t(L, "bi_cert", v=_stated(bi), c=bi.clause))
    pr = it.details.get("printed_eq22_24_statistic") or {}
    if pr:
        ks = np.array([int(k) for k in pr], float)
        dt = tau[0] / np.asarray(a.get("m", [1]), float)[0] if "m" in a else tau[0]
        pv = np.array([pr[k]["printed_eq24_dph2"] for k in pr], float)
        ax.loglog(ks * dt, np.sqrt(pv), "x", color="C2", ms=4,
                  label=_t(L, "eq24"))
    ax.set_xlabel("τ (s)")
    ax.set_ylabel("σ(τ) (°/h)")
    ax.legend(loc="best")


def draw_frequency(fig, spec, result, L, truth=None) -> None:
    """Gain (dB, 0 dB at the lowest frequency) and phase against frequency; −3 dB point."""
    gs = spec.subgridspec(2, 1, hspace=0.18)
    ax = fig.add_subplot(gs[0])
    ax2 = fig.add_subplot(gs[1], sharex=ax)
    it = _role(result, "bandwidth")
    if it is None:
        _empty(ax, _t(L, "no_bw"))
        ax2.set_visible(False)
        return
    f = np.asarray(it.details["freq_hz"], float)
    ax.semilogx(f, np.asarray(it.details["gain_db"], float), "o-", ms=3)
    ax.axhline(-3.0, color="C3", lw=0.7, ls="--")
    f3 = it.details.get("minus3db_hz", it.value)     # the −3 dB point, not the band's value
    p90 = it.details.get("phase90_hz", it.details.get("phase90_hz_iec"))
    ax.axvline(f3, color="C3", lw=0.7)
    ax.set_ylabel(_t(L, "gain"))
    title = _t(L, "m3db", f=_at_item(f3, it))       # at the item's decimal place
    if p90 is not None and math.isfinite(p90):
        title += _t(L, "p90", f=_at_item(p90, it))
    ax.set_title(title)
    ax.tick_params(which="both", labelbottom=False)   # minor log labels too
    ax2.semilogx(f, np.asarray(it.details["phase_deg"], float), "s-", ms=3, color="C1")
    ax2.axhline(-90.0, color="C3", lw=0.7, ls="--")
    if p90 is not None and math.isfinite(p90):
        ax2.axvline(p90, color="C1", lw=0.7)
    ax2.set_ylabel(_t(L, "phase"))
    ax2.set_xlabel(_t(L, "freq"))


#: (key, caption en, caption zh, draw function) in the certificate's order.
FIGURES = (
    ("io_line", "Input–output line of the scale-factor calibration, residuals below",
     "标度因数输入输出直线及残差", draw_io_line),
    ("cw_ccw", "Forward (CW) and reverse (CCW) fits", "正反转分别拟合", draw_cw_ccw),
    ("temperature", "Bias and scale factor against temperature", "零偏与标度因数随温度变化",
     draw_temperature),
    ("allan", "Allan deviation of the static record with the five-term fit",
     "静态数据的Allan偏差及五项拟合", draw_allan),
    ("frequency", "Amplitude and phase response; −3 dB and 90° lag points",
     "幅频与相频特性及 −3 dB 点、相位滞后 90° 点",
     draw_frequency),
)


def figures_of(result) -> tuple:
    """The :data:`FIGURES` a specification's certificate draws: those whose role it has — the
    input–output line where its results have a ``scale_factor`` item, the forward/reverse
    figure where its content gives ``CW_CCW``, the others where its ``FIGURE_ITEMS`` names
    their role (temperature: ``bias_temperature`` or ``sf_temperature``; ``allan``;
    ``bandwidth``). A figure of a role it has whose item was not measured in this run says
    so; a role it does not have draws no figure at all."""
    spec = get(result.spec_key)
    roles = set(spec.content_value("FIGURE_ITEMS") or {})
    has = {"io_line": "scale_factor" in result.items,
           "cw_ccw": "scale_factor" in result.items and bool(spec.content_value("CW_CCW")),
           "temperature": bool({"bias_temperature", "sf_temperature"} & roles),
           "allan": "allan" in roles, "frequency": "bandwidth" in roles}
    return tuple(f for f in FIGURES if has[f[0]])
