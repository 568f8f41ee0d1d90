"""A stored results.json of the optical draft made renderable by the present renderer.

The renderer is a pure function of the stored result (a record re-renders it for an
amendment, a redraft or the other language), so a results.json written before a field was
added must still render, with the numbers the present code would state. Where E's per-point
U carries the table's bound (``extra.uncertainty.U_bound_arcsec``, U = k·u + b), the present
code also writes ``ku_arcsec``, ``nu_without_table``, ``u_c_certified`` and ``u_c_beside``
(:func:`gonio.specs.ogam_draft.budget.e_point_statement`) and the budget figure's ``bound``
(:func:`gonio.specs.ogam_draft.figure_data.budget`). An older results.json lacks them; they are
all functions of what it does hold, so they are derived here by the same functions from the
same stored numbers:

- ``ku_arcsec``, ``nu_without_table``: :func:`e_point_statement` applied again to the stored
  per-point statements ``extra.uncertainty.points`` (each holds ``U_bound_arcsec``,
  ``k_bound``, ``u_without_table_arcsec`` and ``nu_without_table``): the point with the
  largest U_i, k·u of that point, its ν. The derivation is accepted only where that point
  gives the stored ``U_bound_arcsec``, ``k_bound``, ``table_bound_arcsec``,
  ``u_without_table_arcsec`` and ``U_position_deg`` exactly; otherwise the result is refused.
- ``u_c_certified`` False and ``u_c_beside``: the present rule wherever U_bound_arcsec is
  stated (the budget's u_c, the table at MPE/√3, does not hold the corner table).
- ``extra.figures.budget``: ``bound`` (u, k·u, b, U of the stated U = k·u + b),
  ``U_arcsec`` None and ``u_c_stated`` False, as the present figure data writes them.

A result that cannot be completed so is refused in one line (:class:`gonio.errors.GonioError`,
exit 2), never rendered with a guess.
"""

from __future__ import annotations

import copy

from gonio.errors import GonioError

#: The fields of ``extra.uncertainty`` the present code writes beside ``U_bound_arcsec``.
E_BOUND_FIELDS = ("ku_arcsec", "nu_without_table", "u_c_certified", "u_c_beside")
#: The stored fields the re-derived per-point statement must give exactly.
E_BOUND_CHECKED = ("U_bound_arcsec", "k_bound", "table_bound_arcsec", "u_without_table_arcsec",
                   "U_position_deg")


def complete_stored(res: dict) -> dict:
    """``res`` (a results.json dict) with the fields listed in the module's docstring derived
    where they are absent; ``res`` itself where nothing is missing (it is not modified).

    >>> pts = [{"position_deg": 30.0, "U_bound_arcsec": 0.3, "k_bound": 2.0,
    ...         "table_bound_arcsec": 0.1, "u_without_table_arcsec": 0.1,
    ...         "nu_without_table": None}]
    >>> old = {"extra": {"uncertainty": {"points": pts, "U_bound_arcsec": 0.3, "k_bound": 2.0,
    ...        "table_bound_arcsec": 0.1, "u_without_table_arcsec": 0.1,
    ...        "U_position_deg": 30.0}}}
    >>> u = complete_stored(old)["extra"]["uncertainty"]
    >>> u["ku_arcsec"], u["nu_without_table"], u["u_c_certified"]
    (0.2, None, False)
    >>> "ku_arcsec" in old["extra"]["uncertainty"]
    False
    """
    extra = res.get("extra") or {}
    unc = extra.get("uncertainty") or {}
    if unc.get("U_bound_arcsec") is None:
        return res
    fig = (extra.get("figures") or {}).get("budget")
    need = [k for k in E_BOUND_FIELDS if k not in unc]
    fig_old = isinstance(fig, dict) and not fig.get("bound")
    if not need and not fig_old:
        return res
    out = copy.deepcopy(res)
    u = out["extra"]["uncertainty"]
    if need:
        u.update({k: v for k, v in _derived(unc).items() if k in need})
    if fig_old:
        out["extra"]["figures"]["budget"].update(
            U_arcsec=None, u_c_stated=False,
            bound={"u_arcsec": u["u_without_table_arcsec"], "ku_arcsec": u["ku_arcsec"],
                   "b_arcsec": u["table_bound_arcsec"], "U_arcsec": u["U_bound_arcsec"]})
    return out


def _derived(unc: dict) -> dict:
    """:func:`~gonio.specs.ogam_draft.budget.e_point_statement` of the stored points, checked
    against the stored statement (a one-line refusal where it cannot be)."""
    from gonio.specs.ogam_draft.budget import e_point_statement

    what = ("results.json extra.uncertainty: a stored result without "
            f"{', '.join(k for k in E_BOUND_FIELDS if k not in unc)} (written by an earlier "
            "gonio)")
    try:
        st = e_point_statement(unc.get("points"))
    except (KeyError, TypeError, AttributeError):
        st = {}
    if not st or any(st.get(k) != unc.get(k) for k in E_BOUND_CHECKED):
        raise GonioError(f"{what} whose per-point statements do not give them; "
                         "calibrate the readings again to state E", key="extra.uncertainty")
    return st
