"""An item's uncertainty from its budget: the GUM propagation of a budget into the one
:class:`~gonio.result.model.Uncertainty` an item states (JCGM 100, with k from ν_eff), its
JCGM 101 Monte Carlo validation when a calibration asks for it, and the uncertainty of a
standard deviation (a repeatability, a noise level) stated by its one-sided χ² interval
(:func:`std_dev_uncertainty` from ν, :func:`dispersion_uncertainty` from a budget), and
the interval of a magnitude max_i |x_i| (:func:`max_magnitude_statement`).

The kit re-exports :func:`gum`, :func:`monte_carlo_validation`,
:func:`std_dev_uncertainty` and :func:`dispersion_uncertainty` (``gonio.kit``; docs/kit.md#uncertainty-the-gum-model-contract);
every specification whose items carry such budgets, built in or a plug-in, calls these.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from dataclasses import replace

import numpy as np

from gonio.result.model import Uncertainty
from gonio.result.statement import K_SOURCE_MAX_MAGNITUDE as _K_SOURCE_MAX_MAGNITUDE
from gonio.result.statement import stated_gum
from uncertainty import monte_carlo, propagate, validate_gum


def _f(x):
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


_MC = contextvars.ContextVar("item_monte_carlo", default=(0, 0))


@contextlib.contextmanager
def monte_carlo_validation(trials: int, seed: int = 0):
    """Within this block every :func:`gum` budget is also propagated by JCGM 101 Monte Carlo
    with ``trials`` draws and the GUM interval validated against it (JCGM 101 8)."""
    token = _MC.set((int(trials), int(seed)))
    try:
        yield
    finally:
        _MC.reset(token)


def gum(value_fn, inputs, *, p: float | None = 0.95, k: float = 2.0) -> Uncertainty:
    """Propagate ``inputs`` (uncertainty.InputQuantity) through ``value_fn`` (a callable of
    the inputs in order, or a sympy expression) with the GUM engine (JCGM 100): by default
    k = t_95(ν_eff) (Welch–Satterthwaite), since an item may rest on as few as 3 repeats, of
    the ν_eff as stated (:func:`gonio.result.statement.coverage_k`: its integer part, ∞ above
    1000); ``p=None`` uses the fixed ``k``."""
    r = stated_gum(propagate(value_fn, inputs, k=None if p is not None else k, p=p))
    comps = [{"symbol": c.symbol, "source": c.source, "type": c.type, "u": _f(c.u_xi),
              "c": _f(c.c_i), "contribution": _f(c.contribution), "dof": _f(c.dof)}
             for c in r.contributions]
    mc = None
    trials, seed = _MC.get()
    if trials > 0 and r.u_c > 0:
        m = monte_carlo(value_fn, inputs, trials, seed=seed, p=p or 0.95)
        v = validate_gum(r, m)
        mc = {"trials": trials, "u": m.u, "low": m.low, "high": m.high,
              "gum_low": v.gum_interval[0], "gum_high": v.gum_interval[1],
              "d_low": v.d_low, "d_high": v.d_high, "delta": v.delta, "validated": v.passed}
    return Uncertainty(comps, r.u_c, r.U, r.k, r.dof, mc, p,
                       "welch-satterthwaite" if p is not None else "fixed")


def std_upper_half_width(s: float, nu: int, p: float = 0.95) -> float:
    """Expanded uncertainty of a standard deviation ``s`` with ν degrees of freedom (a
    repeatability, the RMS of a noise): the distance from s to the one-sided χ² upper limit
    s·√(ν/χ²_{1−p,ν}) of σ, so that P(σ ≤ s + U) = p exactly for normal data. For ν ≤ 5
    (p = 0.95) s − U < 0: the item is non-negative, the interval [0, s + U] is the statement
    and its coverage is p; above, s ± U covers p less P(σ < s − U), below 4·10⁻⁴ up to
    ν = 20 (ν = 6: s − U = 0.08·s, P ≈ 10⁻¹⁷⁷).

    Not the upper end of the two-sided interval, s·√(ν/χ²_0.025,ν): there
    P(σ ≤ s + U) = 0.975 under a label of 95 %.

    >>> round(std_upper_half_width(1.0, 2), 3)       # √(2/χ²_0.05,2) − 1 = √(2/0.1026) − 1
    3.415
    """
    from scipy.stats import chi2
    return float(s * (math.sqrt(nu / chi2.ppf(1.0 - p, nu)) - 1.0))


def std_dev_uncertainty(s: float, nu: int, what: str) -> Uncertainty:
    """Uncertainty of a standard deviation ``s`` of ν + 1 values (a repeatability, the
    standard deviation of a resolution's readings): u_c = s/√(2ν), the GUM's standard
    uncertainty of an experimental standard deviation (JCGM 100 E.4.3; type A, ν degrees of
    freedom), and the one-sided χ² 95 % interval of σ, [0, s·√(ν/χ²_0.05,ν)]
    (P(σ ≤ upper end) = 95 %), which is the item's statement
    (:func:`gonio.result.statement.state_interval`): no k (σ's distribution is not symmetric
    about s, so no coverage factor exists; k = U/u_c, 6.83 for ν = 2, was one). U is the
    distance from s to the upper end (:func:`std_upper_half_width`), the guard band of the
    decision rule, so a guarded upper limit is the upper end.

    Two readings this rule replaces: the χ² half-width entered as a normal type-B term with
    k = 2 and expanded again by t₉₅ (u_c = 2.64·s for ν = 2, 5.3× the GUM's s/2; the coverage
    study's sd z 0.17), and U reaching the two-sided limit s·√(ν/χ²_0.025,ν), which σ stays
    below 97.5 % of the time, under a label of 95 % (for ν = 2, U 5.285·s → 3.415·s).

    >>> u = std_dev_uncertainty(1.0, 2, "K_r")
    >>> round(u.u_c, 3), round(u.U, 3), u.k, [round(x, 3) for x in u.interval]
    (0.5, 3.415, None, [0.0, 4.415])
    """
    u_c = float(s / math.sqrt(2.0 * nu))
    U = std_upper_half_width(s, nu)
    row = {"symbol": f"s({what})", "source": f"sampling of a standard deviation of "
           f"{nu + 1} values, s/√(2ν) (GUM E.4.3); U to the one-sided χ² 95 % upper limit",
           "type": "A", "u": u_c, "c": 1.0, "contribution": u_c, "dof": float(nu)}
    return Uncertainty([row], u_c, U, None, float(nu), None, 0.95,
                       "chi-square", interval=(0.0, s + U))



def dispersion_uncertainty(s: float, u: Uncertainty, p: float = 0.95) -> Uncertainty:
    """A dispersion ``s`` (a standard deviation, a root mean square of noise) whose standard
    uncertainty comes from its own budget ``u`` (JJF 1535 7.2.10's bias stability: a mean of
    records' block-mean spreads with their effective ν; IEC 62047-20 5.4.5.1's in-band and
    broadband rms: a Welch estimate's scatter and the chamber's fluctuation), stated as a
    standard deviation is (:func:`std_dev_uncertainty`): by its one-sided χ² 95 % interval
    [0, s·√(ν/χ²_0.05,ν)] alone, with ν = ½ (s/u_c)² (JCGM 100 E.4.3, u(s)/s = 1/√(2ν), read
    backwards: the ν of a standard deviation whose χ² spread is u_c). ν is stated as its
    integer part with no ∞ cap (:func:`gonio.result.statement.chi2_nu`), and the limit is
    computed from that stated ν, so the ν printed beside it reproduces it. No k; U is the distance
    to the upper limit (the guard band of the decision,
    :func:`gonio.analysis.conformity.decide_items`, which takes σ's χ² distribution with that
    ν). The budget's rows and u_c are kept. ``s`` not above 0 or no u_c: ``u`` as it is.
    ``p``: the interval's probability, where a certificate states another p for every item
    (the triad's 95.45 %): [0, s·√(ν/χ²_{1−p},ν)].

    >>> u = dispersion_uncertainty(48.0, Uncertainty([], 3.1, 13.3, 4.3, 2.0, None, 0.95))
    >>> round(u.nu_eff, 1), u.k, [round(x, 2) for x in u.interval], u.k_source
    (119.9, None, [0.0, 53.78], 'chi-square')
    """
    from gonio.result.statement import chi2_nu

    if not (s > 0 and u.u_c > 0):
        return u
    nu = 0.5 * (s / u.u_c) ** 2
    U = std_upper_half_width(s, chi2_nu(nu), p)
    return Uncertainty(u.components, u.u_c, U, None, nu, None, p, "chi-square",
                       interval=(0.0, s + U))


#: What a dispersion stated by its one-sided bound condition keeps in
#: ``details.bound_condition.basis`` (:func:`dispersion_bound_statement`).
DISPERSION_BOUND_BASIS = (
    "bound condition of a dispersion: the relative errors that scale the reading, each at its "
    "bound g_i with the sign that lowers it, and the one-sided χ² limit of the other lines, "
    "[0, (s + R)/∏(1 − g_i)], R = s·(√(ν_rest/χ²_{1−p,ν_rest}) − 1), ν_rest = ½(s/u_rest)² "
    "(JCGM 100 4.3.7, E.4.3); holds at least p at every condition within the bounds, exactly "
    "p at the bound")


def dispersion_bound_statement(s: float, u: Uncertainty, bounded_rel: dict, p: float = 0.95,
                               basis: str = DISPERSION_BOUND_BASIS) -> tuple[Uncertainty, dict]:
    """The one statement of a dispersion ``s`` (a noise rms, an ARW) whose reading bounded
    relative errors scale (``bounded_rel``: {budget symbol: g_i}, the reading is
    σ·∏(1 − e_i) with |e_i| ≤ g_i < 1; IEC 62047-20 5.4.5's gyro temperature during the
    static record, which Table 2's chamber lets sit at its bound for the whole record): its
    one-sided bound-condition limit

        [0, (s + R)/∏(1 − g_i)] = [0, s + a + R],  R = s·(√(ν_rest/χ²_{1−p,ν_rest}) − 1),

    u_rest the root sum square of the budget's other lines, ν_rest = ½(s/u_rest)² (JCGM 100
    E.4.3 read backwards, as :func:`dispersion_uncertainty` takes ν; stated as its integer
    part, :func:`gonio.result.statement.chi2_nu`, and R computed from that stated ν). The
    χ² limit of the rest holds the reading's own dispersion σ·∏(1 − e_i) below s + R with
    p, and σ·∏(1 − e_i) ≥ σ·∏(1 − g_i) for every error within the bounds, so
    P(σ ≤ (s + R)/∏(1 − g_i)) ≥ p there, = p at the bound (JCGM 100 4.3.7 for the bounds;
    a root-sum-square line of a bounded error at its bound covers less: IEC 5.4.5.2 with the
    gyro at the chamber's cold bound, 5 of 8 trials). a = (s + R)·(1/∏(1 − g_i) − 1), each
    line's share (s + R)·g_i/(1 − g_i) in ``a_lines`` (a holds their cross products too), g =
    1 − ∏(1 − g_i) the combined bound (the upper end is (s + R)/(1 − g)). No
    k; U is the reach a + R above s (the guard band of the decision, as for a χ² bound); u_c
    and the budget's rows are kept beside (the GUM budget, the bounded lines rectangular),
    not stated (:func:`gonio.result.statement.u_c_certified`). ``bounded_rel`` empty or all
    0, or no rest: :func:`dispersion_uncertainty` (the χ² statement), and no parts. Returns
    the statement and its parts for the item's ``details.bound_condition``.

    >>> from uncertainty import from_u, type_b
    >>> ins = [from_u("N", 1.0, 0.01, dof=5000), type_b("dT", 0.0, 0.005, "rectangular")]
    >>> g = gum(lambda n, t: n + t, ins)
    >>> st, d = dispersion_bound_statement(1.0, g, {"dT": 0.008})
    >>> d["nu_rest"], round(d["reach_rest"], 5), round(d["a"], 7), st.k, st.interval[0]
    (5000.0, 0.01675, 0.0081996, None, 0.0)
    >>> round(st.interval[1], 6) == round((1.0 + d["reach_rest"]) / (1 - 0.008), 6)
    True
    >>> round(std_upper_half_width(1.0, 5000), 5)    # the rest's χ² reach alone
    0.01675
    >>> dispersion_bound_statement(1.0, g, {})[0].k_source
    'chi-square'
    """
    from gonio.errors import GonioError
    from gonio.result.statement import K_SOURCE_BOUND_CHI2, chi2_nu

    bounded = {sym: float(g) for sym, g in bounded_rel.items() if float(g) > 0.0}
    if not bounded or not s > 0:
        return dispersion_uncertainty(s, u, p), {}
    rows = {str(c.get("symbol")): c for c in u.components}
    missing = sorted(set(bounded) - set(rows))
    if missing:
        raise GonioError(f"bound-condition statement: budget has no line {missing[0]!r}")
    big = sorted(sym for sym, g in bounded.items() if not g < 1.0)
    if big:
        raise GonioError(f"bound-condition statement: line {big[0]!r} bounds a relative error "
                         f"of {bounded[big[0]]:g}, not below 1: the dispersion has no upper "
                         f"limit")
    u_rest = rest_of(u, bounded)[0]
    if not u_rest > 0:
        return dispersion_uncertainty(s, u, p), {}
    nu_rest = 0.5 * (s / u_rest) ** 2
    reach = std_upper_half_width(s, chi2_nu(nu_rest), p)
    upper = (s + reach) / math.prod(1.0 - g for g in bounded.values())
    a = upper - s - reach
    a_lines = {sym: (s + reach) * g / (1.0 - g) for sym, g in bounded.items()}
    parts = {"a": a, "a_lines": a_lines, "g_rel": bounded,
             "g": 1.0 - math.prod(1.0 - g for g in bounded.values()), "u_rest": u_rest,
             "nu_rest": nu_rest, "reach_rest": reach, "U": upper - s, "upper": upper,
             "basis": basis}
    return Uncertainty(u.components, u.u_c, upper - s, None, nu_rest, None, p,
                       K_SOURCE_BOUND_CHI2, interval=(0.0, upper),
                       u_c_of="the GUM budget (the bounded lines as rectangular "
                              "distributions); the bound-condition limit is the statement"), parts


def rest_of(u: Uncertainty, symbols) -> tuple[float, float]:
    """(u_rest, ν_rest) of ``u``'s budget less the lines ``symbols`` (a bound condition's
    bounded lines, stated at their bound beside it): u_rest the root sum square of the other
    lines' contributions |c_i|·u(x_i) (JCGM 100 5.1.2, the lines independent), ν_rest their
    Welch–Satterthwaite ν (JCGM 100 G.4.1, eq. (G.2b); a line without ν infinite; ∞ where
    none has a finite ν or u_rest is 0). The same numbers as the model evaluated without
    those inputs: the other lines' sensitivity coefficients are taken at the inputs' values.

    >>> u = Uncertainty([{"symbol": "a", "contribution": 3.0, "dof": 2.0},
    ...                  {"symbol": "dT", "contribution": 12.0, "dof": None},
    ...                  {"symbol": "b", "contribution": 4.0, "dof": None}],
    ...                 13.0, 26.0, None, 2.0, None, 0.95)
    >>> ur, nr = rest_of(u, ("dT",))
    >>> ur, round(nr, 3)                       # 5⁴ / (3⁴/2)
    (5.0, 15.432)
    """
    from uncertainty import welch_satterthwaite

    drop = set(symbols)
    rows = [(float(c.get("contribution") or 0.0),
             math.inf if c.get("dof") is None else float(c["dof"]))
            for c in u.components if str(c.get("symbol")) not in drop]
    u_rest = math.sqrt(sum(c * c for c, _ in rows))
    if not u_rest > 0:
        return 0.0, math.inf
    return u_rest, welch_satterthwaite(u_rest, [c for c, _ in rows], [n for _, n in rows])


def budget_nu(u: Uncertainty) -> float:
    """ν_eff of the combined standard uncertainty u_c of ``u``'s budget, by
    Welch–Satterthwaite over its lines (JCGM 100 G.4.1, eq. (G.2b): u_c⁴ / Σ u_i(y)⁴/ν_i,
    a line without ν infinite): the ν an item computed from this one carries with u_c.

    Not ``u.nu_eff`` where the statement is not U = k·u_c of the whole budget (a bound
    condition's ν_eff is its rest's, ν_rest; a χ² or extreme interval states none): the
    lines are what u_c is made of. ∞ where no line has a finite ν or u_c is 0.

    >>> u = Uncertainty([{"contribution": 3.0, "dof": 2.0}, {"contribution": 4.0,
    ...                   "dof": None}], 5.0, 10.0, None, 2.0, None, 0.95)
    >>> round(budget_nu(u), 3)                 # 5⁴ / (3⁴/2) = 625/40.5
    15.432
    """
    from uncertainty import welch_satterthwaite

    rows = [(float(c.get("contribution") or 0.0),
             math.inf if c.get("dof") is None else float(c["dof"])) for c in u.components]
    if not (u.u_c and u.u_c > 0) or not rows:
        return math.inf
    return welch_satterthwaite(u.u_c, [r[0] for r in rows], [r[1] for r in rows])


#: ``k_source`` of a magnitude max_i |x_i| stated by the interval of the extreme of
#: magnitudes (:func:`max_magnitude_statement`; defined with the statement rule).
K_SOURCE_MAX_MAGNITUDE = _K_SOURCE_MAX_MAGNITUDE


def max_magnitude_statement(u: Uncertainty, x, points: list[Uncertainty],
                            value: float, bounded: dict | None = None
                            ) -> tuple[float, Uncertainty, dict]:
    """The one statement of a characteristic that is the largest magnitude max_i |x_i| of
    signed points (IEC 62047-20 5.1.3.5 and 5.3.3.3: the largest |R_Vi|; 5.1.3.6, 5.2,
    5.3.3.8; JJF 1535 7.2.12's B_g = max |B_g,axis|, 7.2.2, 7.2.3, 7.2.5, 7.2.14), and its
    stated value.

    GUM's linearisation of |x| at the largest point states value ± U, an interval reaching
    below zero for a magnitude and holding θ = max_i |μ_i| with less than 95 % where the
    points are near zero or compete (|x| is not linear there). Stated instead, as the
    optical draft's E (7.4), by the 95 % interval of the extreme of magnitudes,
    [max(0, max_i(|x_i| − c_L u_i)), max_i(|x_i| + c_H u_i)]
    (:func:`uncertainty.extreme.max_abs_interval`: ≥ 95 % for every pattern of the true
    values and any correlation; the points' own u_i and ν_i from ``points``, their signed
    GUM results). No k and no ν: the interval is the statement, and U is the reach from the
    value to its upper end (the decision rule's guard band). ``u``: the budget of the value
    (its components and u_c are kept, for the budget table); ``value``: the estimate (a
    reading less its selection midpoint), never taken below the interval's lower end (a
    point measured with a smaller u shows that the extreme is at least that). The third
    element: the interval's figures and its points (x_i, u_i, ν_i) for the item's details.

    ``bounded`` ({"symbol": s, "b": [b_i], "basis": text}): a bounded error of each point at
    its bound, the bound condition of an extreme (JCGM 100 4.3.7;
    :func:`uncertainty.extreme.max_abs_interval`'s ``bound``): the interval is
    [max(0, max_i(|x_i| − c_L u_i − b_i)), max_i(|x_i| + c_H u_i + b_i)] with u_i, ν_i those of
    each point's other lines (:func:`rest_of`: its budget less the line ``s``), which holds
    max_i |μ_i| for every error within the bounds, where a root-sum-square line at its bound
    does not (JJF 1535 7.2.5 with the gyro cold at the hot set point: 24 of 40). Its parts go
    to the details' ``bound_condition``
    ({"a_lines": {s: max b_i}, "b": [b_i], "u_rest": [u_i], "nu_rest": [ν_i], "basis"}): the
    u_c of ``u`` (the line rectangular) is then kept beside, not stated
    (:func:`gonio.result.statement.u_c_certified`)."""
    from uncertainty.extreme import max_abs_interval

    b = [0.0] * len(points) if not bounded else [float(v) for v in bounded["b"]]
    if len(b) != len(points):
        raise ValueError("max_magnitude_statement: one bound per point")
    # each point's (u, ν): its other lines' where a line is bounded, else its own result's
    pairs = [rest_of(q, (bounded["symbol"],)) if bounded else (float(q.u_c), q.nu_eff)
             for q in points]
    us = [float(p_[0]) for p_ in pairs]
    nu = [math.inf if p_[1] is None or not math.isfinite(p_[1]) else max(1.0, float(p_[1]))
          for p_ in pairs]
    r = max_abs_interval(np.asarray(x, dtype=float), us, nu, bound=b)
    if not r.upper > r.lower:       # no uncertainty at all (a noise-free bench): no interval
        return float(value), u, {}
    value = min(max(float(value), r.lower), r.upper)
    figures = {"max_abs_interval": {**r.to_dict(), "x": [float(v) for v in x],
                                    "u": us, "nu": nu}}
    if bounded and any(v > 0 for v in b):
        figures["bound_condition"] = {
            "a_lines": {bounded["symbol"]: max(b)}, "b": b,
            "u_rest": us, "nu_rest": nu,
            "U": r.upper - value, "upper": r.upper, "basis": bounded["basis"]}
    return value, replace(u, U=r.upper - value, k=None, nu_eff=None,
                          coverage_probability=r.p, k_source=K_SOURCE_MAX_MAGNITUDE,
                          interval=(r.lower, r.upper)), figures
