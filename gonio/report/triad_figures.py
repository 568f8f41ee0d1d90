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

from gonio.analysis.thermal_model import ChannelModel, Compensation
from gonio.specs.triad_alignment.analysis import OFFDIAG, AlignmentResult
from gonio.units import dps_to_dph

def alignment_figure(result: AlignmentResult, true_system_matrix=None) -> Figure:
    """Two panels: cross-axis sensitivity / leakage (‰) and the Allan deviation with the
    averaging-time choice (:func:`alignment_panels` on a new Figure)."""
    fig = Figure(figsize=(9.0, 3.6))
    alignment_panels(fig, fig.add_gridspec(1, 1)[0], result, true_system_matrix)
    fig.tight_layout()
    return fig


def alignment_panels(fig, spec, result: AlignmentResult, true_system_matrix=None) -> None:
    """The two panels of :func:`alignment_figure` drawn into ``spec`` (a SubplotSpec) of
    ``fig`` — the form the certificate uses."""
    gs = spec.subgridspec(1, 2, wspace=0.3)
    ax1, ax2 = fig.add_subplot(gs[0]), fig.add_subplot(gs[1])
    x = np.arange(6)
    s = np.asarray(result.derived["cross_axis"]) * 1e3
    u = np.asarray(result.u_derived["cross_axis"]) * 1e3
    k = float(np.max(result.coverage_factor))
    ax1.bar(x - 0.2, s, 0.4, yerr=k * u, label="before: S_ij = M_ij/M_ii", color="tab:blue")
    lu = np.array([result.leakage_u[int("xyz".index(n[0])), int("xyz".index(n[1]))]
                   for n in OFFDIAG]) * 1e3
    if true_system_matrix is not None:
        lk = result.leakage_against(true_system_matrix)
        lv = np.array([lk["xyz".index(n[0]), "xyz".index(n[1])] for n in OFFDIAG]) * 1e3
        ax1.bar(x + 0.2, lv, 0.4, yerr=k * lu, color="tab:orange",
                label="after M⁻¹: true leakage ± 2u")
    else:
        ax1.bar(x + 0.2, np.zeros(6), 0.4, yerr=k * lu, color="tab:orange",
                label="after M⁻¹: 0 ± 2u")
    ax1.set_xticks(x, [f"{n[0]}←{n[1]}" for n in OFFDIAG])
    ax1.set_ylabel("cross-axis sensitivity (‰)")
    ax1.set_title("Cross-axis sensitivity before and after alignment")
    ax1.legend(fontsize=7)
    avg = result.averaging
    if avg is None:
        ax2.text(0.5, 0.5, "no static record", ha="center", transform=ax2.transAxes)
    else:
        for i, a in enumerate(avg.adev_dph):
            ax2.loglog(avg.tau_s, a, marker=".", label=f"gyro {'xyz'[i]}")
        lim = dps_to_dph(avg.noise_limit_dps)
        ax2.axhline(lim, color="k", ls="--", lw=0.8,
                    label=f"limit ω sin ψ_T/10 = {lim:.1f} °/h")
        need = [t for t in avg.tau_needed_s if np.isfinite(t)]
        if need:
            ax2.axvline(max(need), color="tab:red", ls=":", label=f"τ ≥ {max(need):g} s")
        ax2.set_xlabel("τ (s)")
        ax2.set_ylabel("Allan deviation (°/h)")
        ax2.set_title("Averaging time from the Allan deviation")
        ax2.legend(fontsize=7)


def thermal_figure(model: ChannelModel, compensation: Compensation | None = None) -> Figure:
    """Four panels for one gyro: bias(ϑ), scale factor(ϑ), ARW(ϑ) with fits and 2u bands
    at the reference supply; ramp blocks and residuals; compensation before/after."""
    fig = Figure(figsize=(10.0, 6.4))
    gs = fig.add_gridspec(2, 1)
    thermal_model_panels(fig, gs[0], model)
    thermal_check_panels(fig, gs[1], model, compensation)
    fig.tight_layout()
    return fig


def thermal_model_panels(fig, spec, model: ChannelModel) -> None:
    """The top row of :func:`thermal_figure` in ``spec``: b(ϑ, U) and K(ϑ, U) with the fitted
    polynomials and their 2u prediction bands."""
    g = spec.subgridspec(1, 2, wspace=0.3)
    axs = np.array([[fig.add_subplot(g[0]), fig.add_subplot(g[1])], [None, None]])
    pts = model.points
    grid = np.linspace(model.theta_range[0], model.theta_range[1], 100)
    ax = axs[0, 0]
    for uv in sorted(pts["u_v"].unique()):
        sel = pts["u_v"] == uv
        ax.plot(pts.loc[sel, "theta_c"], pts.loc[sel, "bias_dps"], "o", ms=3,
                label=f"U {uv:+.2f} V")
        b = model.bias.predict(grid, uv)
        ub = model.bias.u_predict(grid, uv)
        ax.plot(grid, b, lw=0.8)
        ax.fill_between(grid, b - 2 * ub, b + 2 * ub, alpha=0.2)
    ax.set_xlabel("ϑ (°C from reference)")
    ax.set_ylabel("bias (°/s)")
    ax.set_title(f"gyro {model.channel}: b(ϑ, U), order {model.bias.n_t}/{model.bias.n_u} "
                 f"({model.bias.criterion})")
    ax.legend(fontsize=6)
    ax = axs[0, 1]
    k0 = float(model.scale.predict(0.0, 0.0)[0])
    for uv in sorted(pts["u_v"].unique()):
        sel = pts["u_v"] == uv
        ax.plot(pts.loc[sel, "theta_c"], (pts.loc[sel, "scale"] / k0 - 1) * 1e6, "o", ms=3)
        kk = model.scale.predict(grid, uv)
        uk = model.scale.u_predict(grid, uv)
        ax.plot(grid, (kk / k0 - 1) * 1e6, lw=0.8)
        ax.fill_between(grid, (kk - 2 * uk) / k0 * 1e6 - 1e6, (kk + 2 * uk) / k0 * 1e6 - 1e6,
                        alpha=0.2)
    ax.set_xlabel("ϑ (°C)")
    ax.set_ylabel("K/k0 − 1 (ppm)")
    ax.set_title(f"K(ϑ, U), order {model.scale.n_t}/{model.scale.n_u}")


def thermal_check_panels(fig, spec, model: ChannelModel,
                         compensation: Compensation | None = None) -> None:
    """The bottom row of :func:`thermal_figure` in ``spec``: the ramp blocks against the
    static-soak model, and the before/after compensation residuals (or ARW(ϑ))."""
    g = spec.subgridspec(1, 2, wspace=0.45)
    axs = np.array([[None, None], [fig.add_subplot(g[0]), fig.add_subplot(g[1])]])
    pts = model.points
    grid = np.linspace(model.theta_range[0], model.theta_range[1], 100)
    ax = axs[1, 0]
    if model.ramp is not None:
        r = model.ramp
        ax.plot(r.theta_c, r.bias_dps, ".", ms=2, label="ramp blocks: observed bias")
        ax.plot(r.theta_c, np.asarray(r.bias_dps) - np.asarray(r.residual_dps), lw=0.8,
                label=f"static-soak model (rms error {r.rms_static_model_dps:.2g} °/s)")
        ax.set_title(f"ramps: lag τ fit {r.tau_s:.0f} s, hysteresis {r.hysteresis_dps:.2g} °/s")
        ax.set_xlabel("ϑ (°C)")
        ax.set_ylabel("bias (°/s)")
        ax.legend(fontsize=6)
    elif model.arw is not None:
        ax.set_title("no ramp blocks")
    ax = axs[1, 1]
    if compensation is not None:
        c = compensation.points
        ax.plot(c["theta_c"], c["bias_before_dps"], "o", ms=3,
                label=f"bias before (rms {compensation.rms_bias_before_dps:.2g} °/s)")
        ax.plot(c["theta_c"], c["bias_after_dps"], "s", ms=3,
                label=f"bias after (rms {compensation.rms_bias_after_dps:.2g} °/s)")
        ax2 = ax.twinx()
        ax2.plot(c["theta_c"], c["scale_before_rel"] * 1e6, "^", ms=3, color="tab:green",
                 label="K error before (ppm)")
        ax2.plot(c["theta_c"], c["scale_after_rel"] * 1e6, "v", ms=3, color="tab:red",
                 label="K error after (ppm)")
        ax2.set_ylabel("scale-factor error (ppm)")
        ax2.legend(fontsize=6, loc="lower right")
        ax.set_title("before / after compensation")
        ax.set_xlabel("ϑ (°C)")
        ax.set_ylabel("residual bias (°/s)")
        ax.legend(fontsize=6, loc="upper left")
    elif model.arw is not None:
        ap = pts.dropna(subset=["arw_deg_sqrt_h"])
        ax.plot(ap["theta_c"], ap["arw_deg_sqrt_h"], "o", ms=3)
        a = model.arw.predict(grid)
        ua = model.arw.u_predict(grid)
        ax.plot(grid, a, lw=0.8)
        ax.fill_between(grid, a - 2 * ua, a + 2 * ua, alpha=0.2)
        ax.set_xlabel("ϑ (°C)")
        ax.set_ylabel("ARW (°/√h)")
        ax.set_title(f"ARW(ϑ), order {model.arw.n_t}")
