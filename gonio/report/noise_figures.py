"""Figures of the noise analysis: deviation with its intervals, the fitted model and
its terms, and the residuals — drawn on a :class:`matplotlib.figure.Figure` (no
pyplot state, no backend switching; saving needs no display).

:func:`noise_figure` builds the figure; :func:`write_noise_figure` writes it
atomically (format from the file suffix).
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

__all__ = ["noise_figure", "write_noise_figure"]

_LABEL = {"overlapping": "σ(τ) overlapping Allan", "modified": "Mod σ(τ)",
          "hadamard": "Hσ(τ) Hadamard", "total": "Tot σ(τ)"}


def noise_figure(allan, fit=None):
    """Log-log deviation with χ² interval bars, the fitted model and each non-zero
    term (its own response for the variance fitted), and the residuals in %.

    >>> from gonio.analysis.noise import AllanResult, fit_noise_model
    >>> tau = 2.0 ** np.arange(6)
    >>> r = AllanResult(tau, 1 / np.sqrt(tau), tau.astype(int), 100 - 2 * tau,
    ...                 np.full(6, 50.0), np.zeros(6, int), 0.9 / np.sqrt(tau),
    ...                 1.1 / np.sqrt(tau), "rate", "overlapping", 1.0, 100, 0.683)
    >>> len(noise_figure(r, fit_noise_model(r)).axes)
    2
    """
    from matplotlib.figure import Figure

    from gonio.analysis.noise import design_matrix

    fig = Figure(figsize=(7, 6))
    ax, axr = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    dev = np.asarray(allan.adev, dtype=np.float64)
    yerr = np.vstack([dev - np.asarray(allan.ci_low, dtype=np.float64),
                      np.asarray(allan.ci_high, dtype=np.float64) - dev])
    ax.errorbar(allan.tau_s, dev, yerr=yerr, fmt="o", ms=3,
                label=_LABEL.get(allan.method, allan.method))
    if fit is not None:
        tt = np.geomspace(allan.tau_s[0], allan.tau_s[-1], 200)
        ax.plot(tt, fit.adev(tt, allan.tau0_s), "k-", label="model")
        coef = fit.coefficients()
        cols = design_matrix(tt, fit.kind, allan.tau0_s)
        for j, name in enumerate(("Q", "N", "B", "K", "R")):
            if coef[j] > 0 and np.any(cols[:, j] > 0):
                ax.plot(tt, np.sqrt(cols[:, j] * coef[j]), "--", lw=0.8, label=name)
        axr.semilogx(fit.tau_s, 100 * fit.residuals, "o", ms=3)
        axr.axhline(0, color="k", lw=0.5)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylabel(f"deviation [{allan.unit}]" if allan.unit else "deviation")
    ax.legend(fontsize=7)
    axr.set_xlabel("τ [s]")
    axr.set_ylabel("residual [%]")
    fig.tight_layout()
    return fig


def write_noise_figure(path, allan, fit=None) -> Path:
    """:func:`noise_figure` written atomically to ``path`` (png, pdf, svg …)."""
    from gonio.atomic import write_bytes

    fig = noise_figure(allan, fit)
    buf = io.BytesIO()
    fmt = Path(path).suffix.lstrip(".") or "png"
    fig.savefig(buf, format=fmt)
    write_bytes(path, buf.getvalue())
    return Path(path)
