"""Figures of the triad alignment and of the extended thermal model (matplotlib Figure
objects; no pyplot state, no backend selection at import).

:func:`alignment_figure` — cross-axis sensitivities before alignment and the residual
leakage after (2u bars; the true leakage when the bench's truth is given), and the Allan
deviation of the static record with the article's noise limit and the chosen averaging
time. :func:`thermal_figure` — bias, scale factor and ARW against temperature with the
fitted polynomials and their 2u prediction bands, the ramp (hysteresis) record, and the
before/after compensation residuals. Files are written with
:func:`gonio.report.figure_files.save_figure` (deterministic bytes, atomic).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from gonio.specs.triad_alignment.certificate import lag_phrase
from gonio.specs.triad_alignment.thermal_model import ChannelModel, Compensation
from gonio.specs.triad_alignment.analysis import OFFDIAG, AlignmentResult
from gonio.specs.triad_alignment.figure_data import alignment_series, channel_figure
from gonio.units import dps_to_dph

#: Figure text, (English, Chinese); each drawing function takes its ``lang``.
FIG_TEXT: dict[str, tuple[str, str]] = {
    "before_S": ("before: S_ij = M_ij/M_ii", "对准前：S_ij = M_ij/M_ii"),
    "after_true": ("after M⁻¹: true leakage ± 2u", "M⁻¹ 对准后：真实残余耦合 ± 2u"),
    "after_0": ("after M⁻¹: 0 ± 2u", "M⁻¹ 对准后：0 ± 2u"),
    "cross": ("cross-axis sensitivity (‰)", "交叉轴灵敏度 (‰)"),
    "cross_title": ("Cross-axis sensitivity before and after alignment", "对准前后的交叉轴灵敏度"),
    "no_static": ("no static record", "无静态记录"),
    "gyro": ("gyro {ch}", "陀螺 {ch}"),
    "limit": ("limit ω sin ψ_T/10 = {v} °/h", "限值 ω sin ψ_T/10 = {v} °/h"),
    "adev": ("Allan deviation (°/h)", "Allan 偏差 (°/h)"),
    "avg_title": ("Averaging time from the Allan deviation", "由 Allan 偏差确定平均时间"),
    "theta_ref": ("ϑ (°C from reference)", "ϑ（相对参考温度，°C）"),
    "bias": ("bias (°/s)", "零偏 (°/s)"),
    "ramp_obs": ("ramp blocks: observed bias", "斜坡段：实测零偏"),
    "soak": ("static-soak model (rms error {v} °/s)", "静态保温模型（均方根误差 {v} °/s）"),
    "ramp_title": ("ramps: lag {lag}\nhysteresis (rising − falling) at equal\n"
                   "chamber temperature {h} °/s",
                   "斜坡：滞后 {lag}\n同一温箱温度下升降温迟滞 {h} °/s"),
    "no_ramp": ("no ramp blocks", "无斜坡段"),
    "b_before": ("bias before (rms {v} °/s)", "补偿前零偏（均方根 {v} °/s）"),
    "b_after": ("bias after (rms {v} °/s)", "补偿后零偏（均方根 {v} °/s）"),
    "k_before": ("K error before (ppm)", "补偿前 K 误差 (ppm)"),
    "k_after": ("K error after (ppm)", "补偿后 K 误差 (ppm)"),
    "sf_err": ("scale-factor error (ppm)", "标度因数误差 (ppm)"),
    "comp_title": ("before / after compensation", "补偿前后"),
    "resid": ("residual bias (°/s)", "残余零偏 (°/s)"),
    "b_title": ("gyro {ch}: b(ϑ, U), order {nt}/{nu}", "陀螺 {ch}：b(ϑ, U)，阶次 {nt}/{nu}"),
    "k_title": ("K(ϑ, U), order {nt}/{nu}", "K(ϑ, U)，阶次 {nt}/{nu}"),
    "arw_title": ("ARW(ϑ), order {nt}", "ARW(ϑ)，阶次 {nt}"),
}


def _t(lang: str, key: str, **kw) -> str:
    """Figure text ``key`` in ``lang`` ("en" or "zh")."""
    return FIG_TEXT[key][1 if lang == "zh" else 0].format(**kw)


def _arr(values) -> np.ndarray:
    """A stored series as floats (null → NaN)."""
    return np.asarray([np.nan if v is None else v for v in values], dtype=float)


def _num(v) -> float:
    return np.nan if v is None else float(v)


def alignment_figure(result: AlignmentResult, true_system_matrix=None,
                     lang: str = "en") -> Figure:
    """Two panels: cross-axis sensitivity / leakage (‰) and the Allan deviation with the
    averaging-time choice (:func:`alignment_panels` on a new Figure)."""
    fig = Figure(figsize=(9.0, 3.6))
    alignment_panels(fig, fig.add_gridspec(1, 1)[0], alignment_series(result),
                     true_system_matrix, lang)
    fig.tight_layout()
    return fig


def alignment_panels(fig, spec, data: dict, true_system_matrix=None,
                     lang: str = "en") -> None:
    """The two panels of :func:`alignment_figure` drawn into ``spec`` (a SubplotSpec) of
    ``fig`` from the stored series ``data`` (``extra.figures.alignment``,
    :func:`~gonio.specs.triad_alignment.figure_data.alignment_series`) — the form the
    certificate uses. With the known ``true_system_matrix`` (the bench's truth) the leakage
    M̂⁻¹ M_true − I is drawn, else 0."""
    gs = spec.subgridspec(1, 2, wspace=0.3)
    ax1, ax2 = fig.add_subplot(gs[0]), fig.add_subplot(gs[1])
    x = np.arange(6)
    s = _arr(data["cross_axis"]) * 1e3
    u = _arr(data["u_cross_axis"]) * 1e3
    k = float(data["k"])
    ax1.bar(x - 0.2, s, 0.4, yerr=k * u, label=_t(lang, "before_S"), color="tab:blue")
    lu = _arr(data["leakage_u"]) * 1e3
    if true_system_matrix is not None:
        lk = np.asarray(data["alignment_matrix"], dtype=float) \
            @ np.asarray(true_system_matrix) - np.eye(3)
        lv = np.array([lk["xyz".index(n[0]), "xyz".index(n[1])] for n in OFFDIAG]) * 1e3
        ax1.bar(x + 0.2, lv, 0.4, yerr=k * lu, color="tab:orange",
                label=_t(lang, "after_true"))
    else:
        ax1.bar(x + 0.2, np.zeros(6), 0.4, yerr=k * lu, color="tab:orange",
                label=_t(lang, "after_0"))
    ax1.set_xticks(x, [f"{n[0]}←{n[1]}" for n in OFFDIAG])
    ax1.set_ylabel(_t(lang, "cross"))
    ax1.set_title(_t(lang, "cross_title"))
    ax1.legend(fontsize=7)
    avg = data["averaging"]
    if avg is None:
        ax2.text(0.5, 0.5, _t(lang, "no_static"), ha="center", transform=ax2.transAxes)
    else:
        tau = _arr(avg["tau_s"])
        for i, a in enumerate(avg["adev_dph"]):
            ax2.loglog(tau, _arr(a), marker=".", label=_t(lang, "gyro", ch="xyz"[i]))
        lim = dps_to_dph(float(avg["noise_limit_dps"]))
        ax2.axhline(lim, color="k", ls="--", lw=0.8,
                    label=_t(lang, "limit", v=f"{lim:.1f}"))
        need = [t for t in _arr(avg["tau_needed_s"]) if np.isfinite(t)]
        if need:
            ax2.axvline(max(need), color="tab:red", ls=":", label=f"τ ≥ {max(need):g} s")
        ax2.set_xlabel("τ (s)")
        ax2.set_ylabel(_t(lang, "adev"))
        ax2.set_title(_t(lang, "avg_title"))
        ax2.legend(fontsize=7)


def thermal_figure(model: ChannelModel, compensation: Compensation | None = None,
                   lang: str = "en") -> Figure:
    """Four panels for one gyro: bias(ϑ), scale factor(ϑ), ARW(ϑ) with fits and 2u bands
    at the reference supply; ramp blocks and residuals; compensation before/after."""
    fig = Figure(figsize=(10.0, 6.4))
    gs = fig.add_gridspec(2, 1)
    data = channel_figure(model, compensation)
    thermal_model_panels(fig, gs[0], data, lang)
    thermal_check_panels(fig, gs[1], data, lang)
    fig.tight_layout()
    return fig


def thermal_model_panels(fig, spec, data: dict, lang: str = "en") -> None:
    """The top row of :func:`thermal_figure` in ``spec`` from one gyro's stored series
    (:func:`~gonio.specs.triad_alignment.figure_data.channel_figure`):
    b(ϑ, U) and K(ϑ, U) with the fitted polynomials and their 2u prediction bands."""
    g = spec.subgridspec(1, 2, wspace=0.3)
    axs = np.array([[fig.add_subplot(g[0]), fig.add_subplot(g[1])], [None, None]])
    pts = {c: _arr(v) for c, v in data["points"].items()}
    grid = _arr(data["grid_c"])
    bo, so = data["bias"], data["scale"]
    ax = axs[0, 0]
    for lv in data["levels"]:
        uv = lv["u_v"]
        sel = pts["u_v"] == uv
        ax.plot(pts["theta_c"][sel], pts["bias_dps"][sel], "o", ms=3,
                label=f"U {uv:+.2f} V")
        b, ub = _arr(lv["bias"]), _arr(lv["u_bias"])
        ax.plot(grid, b, lw=0.8)
        ax.fill_between(grid, b - 2 * ub, b + 2 * ub, alpha=0.2)
    ax.set_xlabel(_t(lang, "theta_ref"))
    ax.set_ylabel(_t(lang, "bias"))
    ax.set_title(_t(lang, "b_title", ch=data["channel"], nt=bo["n_t"], nu=bo["n_u"]) + " "
                 f"({bo['criterion']})")
    ax.legend(fontsize=6)
    ax = axs[0, 1]
    k0 = float(data["k0"])
    for lv in data["levels"]:
        sel = pts["u_v"] == lv["u_v"]
        ax.plot(pts["theta_c"][sel], (pts["scale"][sel] / k0 - 1) * 1e6, "o", ms=3)
        kk, uk = _arr(lv["scale"]), _arr(lv["u_scale"])
        ax.plot(grid, (kk / k0 - 1) * 1e6, lw=0.8)
        ax.fill_between(grid, (kk - 2 * uk) / k0 * 1e6 - 1e6, (kk + 2 * uk) / k0 * 1e6 - 1e6,
                        alpha=0.2)
    ax.set_xlabel("ϑ (°C)")
    ax.set_ylabel("K/k0 − 1 (ppm)")
    ax.set_title(_t(lang, "k_title", nt=so["n_t"], nu=so["n_u"]))


def thermal_check_panels(fig, spec, data: dict, lang: str = "en") -> None:
    """The bottom row of :func:`thermal_figure` in ``spec`` from one gyro's stored series
    (:func:`~gonio.specs.triad_alignment.figure_data.channel_figure`): the ramp blocks
    against the static-soak model, and the before/after compensation residuals (or ARW(ϑ))."""
    g = spec.subgridspec(1, 2, wspace=0.45)
    axs = np.array([[None, None], [fig.add_subplot(g[0]), fig.add_subplot(g[1])]])
    grid = _arr(data["grid_c"])
    ax = axs[1, 0]
    r = data["ramp"]
    if r is not None:
        bias = _arr(r["bias_dps"])
        ax.plot(_arr(r["theta_c"]), bias, ".", ms=2, label=_t(lang, "ramp_obs"))
        ax.plot(_arr(r["theta_c"]), bias - _arr(r["residual_dps"]), lw=0.8,
                label=_t(lang, "soak", v=f"{_num(r['rms_static_model_dps']):.2g}"))
        ax.set_title(_t(lang, "ramp_title", lag=lag_phrase(r, lang),
                        h=f"{_num(r['hysteresis_dps']):.2g}"),
                     fontsize=8)
        ax.set_xlabel("ϑ (°C)")
        ax.set_ylabel(_t(lang, "bias"))
        ax.legend(fontsize=6)
    elif data["arw"] is not None:
        ax.set_title(_t(lang, "no_ramp"))
    ax = axs[1, 1]
    comp = data["compensation"]
    if comp is not None:
        c = {k: _arr(v) for k, v in comp["points"].items()}
        ax.plot(c["theta_c"], c["bias_before_dps"], "o", ms=3,
                label=_t(lang, "b_before", v=f"{_num(comp['rms_bias_before_dps']):.2g}"))
        ax.plot(c["theta_c"], c["bias_after_dps"], "s", ms=3,
                label=_t(lang, "b_after", v=f"{_num(comp['rms_bias_after_dps']):.2g}"))
        ax2 = ax.twinx()
        ax2.plot(c["theta_c"], c["scale_before_rel"] * 1e6, "^", ms=3, color="tab:green",
                 label=_t(lang, "k_before"))
        ax2.plot(c["theta_c"], c["scale_after_rel"] * 1e6, "v", ms=3, color="tab:red",
                 label=_t(lang, "k_after"))
        ax2.set_ylabel(_t(lang, "sf_err"))
        ax2.legend(fontsize=6, loc="lower right")
        ax.set_title(_t(lang, "comp_title"))
        ax.set_xlabel("ϑ (°C)")
        ax.set_ylabel(_t(lang, "resid"))
        ax.legend(fontsize=6, loc="upper left")
    elif data["arw"] is not None:
        ap = {c: _arr(v) for c, v in data["points"].items()}
        keep = ~np.isnan(ap["arw_deg_sqrt_h"])
        ax.plot(ap["theta_c"][keep], ap["arw_deg_sqrt_h"][keep], "o", ms=3)
        a, ua = _arr(data["arw_curve"]["arw"]), _arr(data["arw_curve"]["u_arw"])
        ax.plot(grid, a, lw=0.8)
        ax.fill_between(grid, a - 2 * ua, a + 2 * ua, alpha=0.2)
        ax.set_xlabel("ϑ (°C)")
        ax.set_ylabel("ARW (°/√h)")
        ax.set_title(_t(lang, "arw_title", nt=data["arw"]["n_t"]))
