"""The optical draft's standalone pages: the figure of an equal-division analysis (the table's
and the goniometer's error curves) that ``gonio eda --plot`` writes."""

from __future__ import annotations

from matplotlib.figure import Figure

from gonio.specs.ogam_draft.equal_division import EdaResult


def equal_division_figure(res: EdaResult) -> Figure:
    """Table error against position and goniometer error against angle turned, with ±u bars.

    >>> from gonio.specs.ogam_draft.equal_division import simulate_eda_matrix, equal_division_analysis
    >>> sim = simulate_eda_matrix({1: 1.0}, {2: 0.2}, 8, 8, 1, 0.05, 0)
    >>> fig = equal_division_figure(equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg))
    >>> len(fig.axes)
    2
    """
    fig = Figure(figsize=(7, 6), layout="constrained")
    a1, a2 = fig.subplots(2, 1)
    a1.errorbar(res.table_position_deg, res.table_error_arcsec, yerr=res.table_u_arcsec,
                fmt="o-", capsize=3, label="table error ± u (k = 1)")
    a1.set(xlabel="table position / °", ylabel="table error / ″",
           title=f"rotary table (gauge: {res.gauge})")
    a2.errorbar(res.gonio_angle_deg, res.gonio_error_arcsec, yerr=res.gonio_u_arcsec,
                fmt="s-", capsize=3, color="C1", label="goniometer error ± u (k = 1)")
    a2.set(xlabel="angle turned since zeroing / °", ylabel="goniometer error / ″",
           title="goniometer")
    for a in (a1, a2):
        a.axhline(0, color="0.6", lw=0.8)
        a.grid(alpha=0.3)
        a.legend(loc="best", fontsize=8)
    return fig
