"""Decision rules and statements of conformity (ISO/IEC 17025 7.8.6, ILAC-G8:09/2019, JCGM 106).

Contents
========
===============================  ===========================================================
:data:`RULES`                    the decision rules a laboratory file may name
:class:`DecisionRule`            a rule and its guard-band factor r (w = r·U)
:class:`Limits`                  the tolerance interval [T_L, T_U] of one item (either end open)
:class:`Conformity`              the outcome for one item, with its probabilities
:func:`normal_cdf`               Φ(z), the standard normal distribution function
:func:`conformance_probability`  p_c = Φ((T_U − y)/u) − Φ((T_L − y)/u)   (JCGM 106 7.3)
:func:`acceptance_interval`      [T_L + w, T_U − w] of a guarded rule     (JCGM 106 8.3, ILAC-G8 4.2.2)
:func:`decide`                   the statement for one item under one rule
:func:`limits_of`                a ``[[specification_limits]]`` entry as :class:`Limits`
:func:`rule_of`                  a ``[decision_rule]`` table as :class:`DecisionRule`
:func:`decide_items`             every limited item of a result decided, stored in its Item
:func:`decide_result`            a laboratory file's limits and a specification's defaults
===============================  ===========================================================

The measurement model is the normal one of JCGM 106 7.3: given the measured value
y and its standard uncertainty u = U / k, the measurand η is N(y, u²). The
conformance probability p_c is the probability that η lies in the tolerance
interval. For an item that is *accepted* (pass or conditional pass), 1 − p_c is the
**specific false-accept probability** (JCGM 106 9.3.2, "specific consumer's risk");
for an item that is *rejected*, p_c is the specific false-reject probability.

Rules (ILAC-G8:09/2019 clause 4):

``simple``
    simple acceptance (ILAC-G8 4.2.1, w = 0): pass when y is inside [T_L, T_U],
    fail otherwise. The statement must give the specific false-accept probability,
    which may be up to 50 % at a limit.
``guarded``
    binary guarded acceptance (ILAC-G8 4.2.2), w = r·U: pass when y is inside the
    acceptance interval [T_L + w, T_U − w], fail otherwise. With r = 1, k = 2 and a
    normal model the specific false-accept probability of a passed item is at most
    Φ(−2) ≈ 2.3 % (one limit).
``non-binary``
    non-binary statement with guard band w = r·U (ILAC-G8 4.2.3, its figure 5):
    pass inside [T_L + w, T_U − w]; conditional pass inside the tolerance but within
    w of a limit; conditional fail outside the tolerance by at most w; fail
    beyond that.

Without limits there is no statement (:func:`decide` is not called: the
certificate shows no conformity section).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from gonio.errors import GonioError
from gonio.formats.lab import (DECISION_RULES, check_interval, check_one_limit_per_item,
                              check_symmetric)
from gonio.result.model import Conformity
from gonio.result.statement import K_SOURCE_MAX_ABS, stated_nu

__all__ = ["RULES", "OUTCOMES", "DecisionRule", "Limits", "Conformity", "normal_cdf",
           "conformance_probability", "acceptance_interval", "decide", "limits_of",
           "rule_of", "check_one_limit_per_item", "decide_items", "decide_result",
           "DEFAULT_LIMITS_ORIGIN"]

#: ``limits_from`` of an item decided on a specification's default tolerance
#: (``SPEC.default_limits``), where the laboratory file gives no limit for it.
DEFAULT_LIMITS_ORIGIN = "specification default"

#: Decision rules a laboratory file may name (``[decision_rule] rule = ...``).
RULES: tuple[str, ...] = DECISION_RULES
#: Outcomes, in the words of ILAC-G8:09/2019 4.2.3.
OUTCOMES: tuple[str, ...] = ("pass", "conditional pass", "conditional fail", "fail")


@dataclass(frozen=True)
class DecisionRule:
    """A decision rule: ``kind`` in :data:`RULES`, guard band w = ``guard_factor`` · U.

    ``guard_factor`` is ignored by ``simple`` (w = 0).
    """

    kind: str = "simple"
    guard_factor: float = 1.0

    def __post_init__(self):
        if self.kind not in RULES:
            raise GonioError(f"expected one of {', '.join(RULES)}, got {self.kind!r}",
                             key="decision_rule.rule")
        if not (math.isfinite(self.guard_factor) and self.guard_factor >= 0):
            raise GonioError(f"expected a finite number ≥ 0, got {self.guard_factor!r}",
                             key="decision_rule.guard_band_factor")

    def guard_band(self, U: float) -> float:
        """w: 0 for simple acceptance, r·U otherwise (ILAC-G8 4.2.2)."""
        return 0.0 if self.kind == "simple" else self.guard_factor * U


@dataclass(frozen=True)
class Limits:
    """Tolerance interval of one item in the item's unit; ``None`` = open on that side."""

    lower: float | None
    upper: float | None
    source: str = ""

    def __post_init__(self):
        check_interval(self.lower, self.upper)


def normal_cdf(z: float) -> float:
    """Φ(z) of the standard normal distribution, via the complementary error function.

    >>> round(normal_cdf(0.0), 12), round(normal_cdf(-2.0), 6)
    (0.5, 0.02275)
    """
    if z == math.inf:
        return 1.0
    if z == -math.inf:
        return 0.0
    return 0.5 * math.erfc(-z / math.sqrt(2.0))


def conformance_probability(y: float, u: float, lower: float | None,
                            upper: float | None) -> float:
    """p_c = Φ((T_U − y)/u) − Φ((T_L − y)/u) for η ~ N(y, u²) (JCGM 106 7.3, eq. (9)).

    An open end contributes Φ(+∞) = 1 or Φ(−∞) = 0. ``u`` must be > 0.

    >>> conformance_probability(1.0, 0.5, None, 1.0)
    0.5
    """
    if not (u > 0 and math.isfinite(u)):
        raise ValueError(f"standard uncertainty must be finite and > 0, got {u!r}")
    hi = normal_cdf((upper - y) / u) if upper is not None else 1.0
    lo = normal_cdf((lower - y) / u) if lower is not None else 0.0
    return max(0.0, hi - lo)


def conformance_probability_chi2(s: float, nu: float, lower: float | None,
                                 upper: float | None) -> float:
    """p_c of a standard deviation σ estimated by s with ν degrees of freedom.

    σ is distributed as s·√(ν/χ²_ν) — the distribution whose 95 % interval is the χ²
    interval stated beside such an item's U (JCGM 100 E.4.3; JCGM 106 7.3 with this PDF of
    σ in place of a normal one): P(σ ≤ T) = P(χ²_ν ≥ ν·s²/T²) for T > 0, and 0 for T ≤ 0.
    The normal model N(s, u²) puts far too little probability in the long upper tail:
    s = 0.124, ν = 9 against T_U = 0.3 gives 1 − p_c ≈ 0.31 % here and ≈ 10⁻⁹ there.

    >>> round(1 - conformance_probability_chi2(0.124, 9, None, 0.3), 4)   # = χ²₉.cdf(9·0.124²/0.3²)
    0.0031
    >>> conformance_probability_chi2(0.124, 9, -0.3, None)
    1.0
    """
    from scipy.stats import chi2
    if not (s > 0 and math.isfinite(s) and nu > 0 and math.isfinite(nu)):
        raise ValueError(f"s and nu must be finite and > 0, got s={s!r}, nu={nu!r}")

    def below(t: float | None, open_end: float) -> float:      # P(σ ≤ t)
        if t is None:
            return open_end
        return float(chi2.sf(nu * s * s / (t * t), nu)) if t > 0 else 0.0

    return max(0.0, below(upper, 1.0) - below(lower, 0.0))


def acceptance_interval(limits: Limits, w: float,
                        w_lower: float | None = None) -> tuple[float | None, float | None]:
    """[T_L + w_L, T_U − w]: the acceptance interval of a guard band w (JCGM 106 8.3.2);
    ``w_lower`` (default ``w``) is the band at the lower limit, for an item stated by an
    interval that is not symmetric about its value (the band at each limit is the
    interval's reach on that side).

    An open tolerance end stays open. A guard band that closes the interval
    (T_U − T_L ≤ w + w_L) leaves an empty acceptance interval: nothing can pass.

    >>> acceptance_interval(Limits(-0.5, 0.5), 0.2)
    (-0.3, 0.3)
    >>> acceptance_interval(Limits(-0.5, 0.5), 0.2, 0.1)
    (-0.4, 0.3)
    """
    w_lower = w if w_lower is None else w_lower
    lo = None if limits.lower is None else limits.lower + w_lower
    hi = None if limits.upper is None else limits.upper - w
    return lo, hi


def _inside(y: float, lo: float | None, hi: float | None) -> bool:
    return (lo is None or y >= lo) and (hi is None or y <= hi) and \
        (lo is None or hi is None or lo <= hi)


#: ``probability_model`` of an item stated by the interval of an extreme of magnitudes
#: (max_i |x_i|, E 7.4): no single normal model N(max|x_i|, u) describes it (the extreme of
#: several points), so no probability of conformance is given; the outcome is decided on the
#: interval (its upper end against the limit).
MAX_ABS_PROBABILITY_MODEL = ("not given: the extreme of several points; the outcome is "
                             "decided on its 95 % interval")


def decide(item: str, y: float, U: float, k: float | None, limits: Limits,
           rule: DecisionRule, *, chi2_nu: float | None = None,
           u: float | None = None, U_lower: float | None = None,
           no_probability: str | None = None) -> Conformity:
    """The statement of conformity for one item (ILAC-G8:09/2019 4.2; JCGM 106 8–9).

    Parameters
    ----------
    item : name of the item (as in ``results.json``).
    y : measured value; for the draft's E (7.4) max|E_i|, compared with [−MPE, +MPE]
        with U the reach of its interval above it (:func:`decide_items`, ``k_source``
        :data:`~gonio.result.statement.K_SOURCE_MAX_ABS`): |E_i| ≤ MPE at every position
        is max|E_i| ≤ MPE, and "pass" is the interval's upper end within +MPE.
    U, k : expanded uncertainty and its coverage factor (u = U/k, normal model); for an
        item stated by its χ² interval k is None and U the distance to the interval's upper
        end (the guard band then makes the guarded upper limit the interval's upper end).
    limits, rule : the tolerance interval and the decision rule agreed.
    chi2_nu : for a standard deviation stated with its χ² interval, its degrees of freedom:
        the probabilities come from :func:`conformance_probability_chi2` instead of the
        normal model (``probability_model`` says which).
    u : the standard uncertainty of the normal model where ``k`` is None and no χ² model
        applies (an item stated by another interval, e.g. a half range: its guard band is
        U, the distance to the interval's upper end; the probabilities are the normal
        approximation with u).
    U_lower : for an item stated by an interval, the distance from the value down to the
        interval's lower end (default ``U``): the guard band at a lower limit is
        r·U_lower, so that with r = 1 "pass" is "the stated interval lies inside the
        tolerance" on either side, as at the upper limit.
    no_probability : where the item's distribution is not one whose probabilities gonio
        can give (neither N(y, u²) nor the χ² model), the reason: no probability of
        conformance, false accept or false reject is stated (None), ``probability_model``
        says why; the outcome is decided on the acceptance interval alone.

    A value exactly on a limit of the acceptance interval is accepted (the limits
    are part of the interval, JCGM 106 3.3.9).

    >>> d = decide("E", 0.45, 0.10, 2.0, Limits(-0.5, 0.5), DecisionRule("non-binary"))
    >>> d.outcome, round(d.false_accept_probability, 4)
    ('conditional pass', 0.1587)
    """
    if not (U > 0 and math.isfinite(U)) or (chi2_nu is None and u is None
                                             and no_probability is None and not (
            k is not None and k > 0 and math.isfinite(k))):
        raise ValueError(f"{item}: U and k must be finite and > 0 (U={U!r}, k={k!r})")
    u = U / k if k else u
    if no_probability is not None:
        p_c, model = None, no_probability
    elif chi2_nu is not None and y > 0:
        p_c = conformance_probability_chi2(y, chi2_nu, limits.lower, limits.upper)
        model = f"chi-square, nu = {chi2_nu:g}"
    else:
        p_c = conformance_probability(y, u, limits.lower, limits.upper)
        model = "normal"
    w = rule.guard_band(U)
    w_lo = w if U_lower is None else rule.guard_band(max(float(U_lower), 0.0))
    a_lo, a_hi = acceptance_interval(limits, w, w_lo)
    in_tol = _inside(y, limits.lower, limits.upper)
    in_acc = _inside(y, a_lo, a_hi)
    if rule.kind == "non-binary":
        if in_acc:
            outcome = "pass"
        elif in_tol:
            outcome = "conditional pass"
        else:
            below = (limits.lower - y) if limits.lower is not None else -math.inf
            above = (y - limits.upper) if limits.upper is not None else -math.inf
            # outside the tolerance, "conditional" where the interval reaches back in: below
            # the lower limit by its reach above the value (w), above the upper limit by its
            # reach below it (w_lo)
            outcome = ("conditional fail" if (below <= w if below >= above else above <= w_lo)
                       else "fail")
    else:
        outcome = "pass" if in_acc else "fail"
    accepted = outcome in ("pass", "conditional pass")
    return Conformity(item=item, value=float(y), U=float(U), k=None if k is None else float(k),
                      lower=limits.lower,
                      upper=limits.upper, rule=rule.kind, guard_band=float(w),
                      guard_band_lower=(float(w_lo) if limits.lower is not None
                                        and w_lo != w else None),
                      acceptance_lower=a_lo, acceptance_upper=a_hi, outcome=outcome,
                      accepted=accepted, conformance_probability=p_c,
                      false_accept_probability=(1.0 - p_c) if accepted and p_c is not None
                      else None,
                      false_reject_probability=p_c if not accepted else None,
                      source=limits.source, guard_factor=float(rule.guard_factor),
                      probability_model=model)


def limits_of(lim: dict) -> Limits:
    """A ``[[specification_limits]]`` entry as :class:`Limits` (``mpe`` = symmetric ±mpe).

    >>> limits_of({"item": "bias", "mpe": 0.5})
    Limits(lower=-0.5, upper=0.5, source='')
    """
    if lim.get("mpe") is not None:
        return Limits(-abs(lim["mpe"]), abs(lim["mpe"]), lim.get("source", "") or "")
    return Limits(lim.get("lower"), lim.get("upper"), lim.get("source", "") or "")


def rule_of(table: dict | None) -> DecisionRule:
    """A ``[decision_rule]`` table (``rule``, ``guard_band_factor``) as :class:`DecisionRule`."""
    t = table or {}
    factor = t.get("guard_band_factor")
    return DecisionRule(t.get("rule") or "simple", 1.0 if factor is None else float(factor))


def _undecided(key: str, lim: Limits, rule: DecisionRule, origin: str,
               reason: str) -> Conformity:
    return Conformity(item=key, value=None, U=None, k=None, lower=lim.lower, upper=lim.upper,
                      rule=rule.kind, guard_band=None, acceptance_lower=None,
                      acceptance_upper=None, outcome=None, accepted=None,
                      conformance_probability=None, false_accept_probability=None,
                      false_reject_probability=None, source=lim.source,
                      guard_factor=float(rule.guard_factor), limits_from=origin, reason=reason)


#: ``probability_model`` of an item stated by a 95 % interval that is neither a normal one
#: (U with its k) nor the χ² interval of a standard deviation (a Neyman belt of a range, a
#: half range, the maximum of a folded normal, a pivot, an outcome distribution, an extreme of
#: magnitudes): N(y, u_c²) is not its distribution (the belt's y is bias-corrected and may lie
#: below zero while its interval starts at 0), so a normal probability would contradict the
#: interval stated beside it; none is given, the outcome is decided on the interval.
NOT_NORMAL_PROBABILITY_MODEL = ("not given: its 95 % interval ({source}) is not that of a "
                                "normal or chi-square distribution; the outcome is decided on "
                                "its 95 % interval")


def extreme_of_magnitudes(key: str, it, declared=()) -> bool:
    """Whether item ``it`` (key ``key``) is an extreme of magnitudes max_i |x_i| (the optical
    draft's E, 7.4: E = ± max|E_i|): its specification declares it so (``declared``: its
    ``Specification.magnitude_extremes``), or it is stated by the 95 % interval of such an
    extreme (``k_source`` :data:`~gonio.result.statement.K_SOURCE_MAX_ABS`). Such a value is
    compared with a symmetric limit only (:func:`gonio.formats.lab.check_symmetric`): the
    declaration also covers the draft's own max|E_i| ± U (k given), which carries no marker.

    >>> from gonio.result.model import Item
    >>> it = Item("E", "E", "7.4", "″", 0.4)
    >>> extreme_of_magnitudes("E", it, ("E",)), extreme_of_magnitudes("E", it)
    (True, False)
    """
    unc = it.uncertainty
    return bool(key in declared or (unc is not None and unc.k_source == K_SOURCE_MAX_ABS))


def check_symmetric_limit(key: str, bounds: Limits, where: str) -> None:
    """An extreme of magnitudes (:func:`extreme_of_magnitudes`) takes a symmetric limit
    only (``mpe``, or ``lower`` = −``upper``): any other is a GonioError naming the entry
    ``where`` (the laboratory file's key), never a decision on one side
    (:func:`gonio.formats.lab.check_symmetric`, which the laboratory file's check runs
    before any work; here it guards a limit that did not come through that check).

    >>> check_symmetric_limit("E", Limits(-0.4, 0.6), "specification_limits[0]")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key specification_limits[0]: E is an extreme of magnitudes (max_i |x_i|): its limit must be symmetric (mpe = M, or lower = -M with upper = M); got lower -0.4, upper 0.6
    """
    check_symmetric(key, bounds.lower, bounds.upper, key=where)


def _decided(key: str, it, bounds: Limits, rule: DecisionRule, origin: str) -> Conformity:
    """The decision of a measured item with U (:func:`decide_items`)."""
    unc = it.uncertainty
    by_interval = unc.k is None and unc.interval is not None
    # ν as stated (integer part, gonio.result.statement.stated_nu): the ν the χ² interval of
    # the statement was computed from, so interval and decision agree
    chi2_nu = (stated_nu(unc.nu_eff) if unc.interval is not None
               and unc.nu_eff is not None and math.isfinite(unc.nu_eff) and unc.nu_eff > 0
               and (unc.k is not None or unc.k_source == "chi-square") else None)
    chi2_nu = chi2_nu if chi2_nu is not None and it.value > 0 else None
    u_normal = float(unc.u_c) if unc.k is None and unc.u_c is not None and unc.u_c > 0 \
        else None
    no_p = None
    if by_interval and chi2_nu is None:
        no_p = (MAX_ABS_PROBABILITY_MODEL if unc.k_source == K_SOURCE_MAX_ABS
                else NOT_NORMAL_PROBABILITY_MODEL.format(source=unc.k_source or "its own"))
    # an item stated by its interval alone: the band at a lower limit is the interval's reach
    # below the value (its upper reach is U). An interval of the extreme of magnitudes
    # max_i |x_i| (E, 7.4) is decided at that extreme (interval[1] - U): "pass" only where
    # the whole interval lies inside the limits
    y = (float(unc.interval[1]) - float(unc.U)
         if by_interval and unc.k_source == K_SOURCE_MAX_ABS else float(it.value))
    U_lower = (y - float(unc.interval[0])
               if by_interval and math.isfinite(float(unc.interval[0])) else None)
    c = replace(decide(key, y, float(unc.U), None if unc.k is None else float(unc.k), bounds,
                       rule, chi2_nu=chi2_nu, u=u_normal, U_lower=U_lower,
                       no_probability=no_p), limits_from=origin)
    if by_interval and rule.kind != "simple":
        c = _on_interval(c, bounds, rule, float(unc.U),
                         float(unc.U) if U_lower is None else max(U_lower, 0.0))
        if unc.k_source == K_SOURCE_MAX_ABS:
            # the interval of max_i |x_i| lies at or above 0, inside any −M of its symmetric
            # limit: only its upper end is accepted or not (no lower acceptance end printed)
            c = replace(c, acceptance_lower=None, guard_band_lower=None)
        # decided on the interval's ends, the quantity the acceptance is stated on (one rule
        # for decision and print, ILAC-G8 4.2.2): a value outside its own interval (a
        # bias-corrected y below a non-negative item's interval) is not decided on y
        lo_end = (float(unc.interval[0]) if U_lower is not None
                  else y - float(unc.U))
        c = _decided_on_ends(c, lo_end, y + float(unc.U), y, bounds)
    lo, hi = c.acceptance_lower, c.acceptance_upper
    return replace(c, acceptance_empty=bool(
        (lo is not None and hi is not None and lo > hi)
        or (it.nonnegative and hi is not None and hi < 0)))


def _decided_on_ends(c: Conformity, lo_end: float, hi_end: float, y: float,
                     bounds: Limits) -> Conformity:
    """The outcome of an item stated by its interval [lo_end, hi_end] alone, on the
    acceptance interval :func:`_on_interval` states for those ends: "pass" where both ends
    lie inside it. Otherwise the outcome of :func:`decide` stands (non-binary: "conditional"
    by the value against the tolerance), except that a "pass" of the value whose interval's
    ends are not accepted is "conditional pass" (non-binary, value inside the tolerance) or
    "fail".

    >>> c = decide("C_g", -1.58e-5, 2.98e-5, None, Limits(-1.5e-5, 1.5e-5),
    ...            DecisionRule("guarded"), U_lower=0.0, no_probability="n/a")
    >>> c = _on_interval(c, Limits(-1.5e-5, 1.5e-5), DecisionRule("guarded"), 2.98e-5, 0.0)
    >>> c.outcome, _decided_on_ends(c, 0.0, 1.4e-5, -1.58e-5, Limits(-1.5e-5, 1.5e-5)).outcome
    ('fail', 'pass')
    """
    lo, hi = c.acceptance_lower, c.acceptance_upper
    if (lo is None or lo_end >= lo) and (hi is None or hi_end <= hi):
        outcome = "pass"
    elif c.outcome == "pass":
        outcome = ("conditional pass" if c.rule == "non-binary"
                   and _inside(y, bounds.lower, bounds.upper) else "fail")
    else:
        outcome = c.outcome
    if outcome == c.outcome:
        return c
    accepted = outcome in ("pass", "conditional pass")
    p_c = c.conformance_probability
    return replace(c, outcome=outcome, accepted=accepted,
                   false_accept_probability=(1.0 - p_c) if accepted and p_c is not None
                   else None,
                   false_reject_probability=p_c if not accepted else None)


def _on_interval(c: Conformity, bounds: Limits, rule: DecisionRule, U: float,
                 U_lower: float) -> Conformity:
    """The acceptance interval of an item stated by its 95 % interval [y − U_L, y + U] and
    decided under a guard band (w = r·U above, r·U_L below), restated on the interval's ends:
    y ≤ T_U − r·U is "the interval's upper end ≤ T_U − (r − 1)·U" (T_U itself at r = 1,
    ILAC-G8 4.2.2: the interval lies inside the tolerance), y ≥ T_L + r·U_L is "its lower end
    ≥ T_L + (r − 1)·U_L". The same decision, stated on the quantity the certificate prints:
    never "value ≤ T_U − U", a negative limit where U exceeds T_U for a non-negative item.

    >>> c = decide("K_l", 5.0e-5, 1.2e-4, None, Limits(None, 1e-4), DecisionRule("guarded"),
    ...            u=8e-5, U_lower=5e-5)
    >>> c.acceptance_upper < 0, _on_interval(c, Limits(None, 1e-4), DecisionRule("guarded"),
    ...                                      1.2e-4, 5e-5).acceptance_upper
    (True, 0.0001)
    """
    r = rule.guard_factor
    lo = None if bounds.lower is None else bounds.lower + (r - 1.0) * U_lower
    hi = None if bounds.upper is None else bounds.upper - (r - 1.0) * U
    return replace(c, acceptance_lower=lo, acceptance_upper=hi, acceptance_of="interval")


def decide_items(result, limits: list[dict], rule: DecisionRule | dict | None, *,
                 origin: str = "lab file", where: str = "specification_limits",
                 magnitude_extremes=()) -> list:
    """Decide every item of ``result`` (a :class:`gonio.result.model.Result`) that a limit
    names, and store the :class:`Conformity` in the item (``Item.conformity``).

    ``limits``: ``[[specification_limits]]`` entries (``item``; ``mpe`` or ``lower`` /
    ``upper``; ``source``), from a laboratory file or a specification's default tolerances
    (``origin`` says which; a lab file's limit replaces a default for the same item). A
    limit naming an item the specification does not have is a GonioError naming that
    specification's items; an item not measured, or without U, gets a Conformity with no
    outcome and the ``reason``. An extreme of magnitudes (:func:`extreme_of_magnitudes`:
    ``magnitude_extremes``, the keys its specification declares so, or the marker of its
    statement) takes a symmetric limit only (:func:`check_symmetric_limit`). An item stated by its
    95 % interval alone is decided on that interval; its acceptance interval bounds the
    interval's ends under a guard band (:func:`_on_interval`), and a probability is given only
    where the interval is the χ² one of a standard deviation
    (:data:`NOT_NORMAL_PROBABILITY_MODEL`). Returns the decisions in the order of ``limits``.

    >>> from gonio.result.model import Item, Result, Uncertainty
    >>> r = Result("s", "S", {"bias": Item("bias", "bias", "7.2.8", "°/h", 0.4,
    ...            uncertainty=Uncertainty([], 0.05, 0.1, 2.0, None))}, {}, {})
    >>> [c.outcome for c in decide_items(r, [{"item": "bias", "mpe": 0.5}], {"rule": "simple"})]
    ['pass']
    >>> decide_items(r, [{"item": "K", "mpe": 1}], None)
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key specification_limits[0].item: s has no item 'K' (its items: bias)
    """
    rule = rule if isinstance(rule, DecisionRule) else rule_of(rule)
    check_one_limit_per_item(limits, where)
    out = []
    for i, lim in enumerate(limits or []):
        key = lim.get("item")
        if key not in result.items:
            raise GonioError(f"{result.spec_key} has no item {key!r} (its items: "
                             f"{', '.join(result.items)})", key=f"{where}[{i}].item")
        it = result.items[key]
        bounds = limits_of(lim)
        if extreme_of_magnitudes(key, it, magnitude_extremes):
            check_symmetric_limit(key, bounds, f"{where}[{i}]")
        unc = it.uncertainty
        if not it.measured or it.value is None:
            c = _undecided(key, bounds, rule, origin, "not measured: " + (it.reason or ""))
        elif (unc is None or unc.U is None or not unc.U > 0 or not math.isfinite(unc.U)
              or (unc.k is None and unc.interval is None)):
            c = _undecided(key, bounds, rule, origin, "no expanded uncertainty to decide with")
        else:
            c = _decided(key, it, bounds, rule, origin)
        it.conformity = c
        out.append(c)
    return out


def decide_result(result, lab: dict | None, defaults: list[dict] | None = None,
                  defaults_origin: str = "specification's tolerance", *,
                  magnitude_extremes=()) -> list:
    """Conformity of every item that has limits, stored in the result's items (the pipeline
    calls this for every specification; the report only renders ``Item.conformity``).

    The limits are the laboratory file's ``[[specification_limits]]`` (decided under its
    ``[decision_rule]``) and, for items the lab file does not limit, ``defaults`` (a
    specification's or protocol's tolerances, same entries; decided under the lab file's
    rule, else simple acceptance). No limits: no decision, every ``conformity`` stays None.
    ``magnitude_extremes``: the items the specification declares extremes of magnitudes
    (symmetric limits only, :func:`decide_items`).
    """
    lab = lab or {}
    lab_limits = list(lab.get("specification_limits") or [])
    named = {lim.get("item") for lim in lab_limits}
    rule = rule_of(lab.get("decision_rule"))
    out = decide_items(result, [d for d in defaults or [] if d.get("item") not in named], rule,
                       origin=defaults_origin, where="tolerances",
                       magnitude_extremes=magnitude_extremes)
    out += decide_items(result, lab_limits, rule, origin="lab file",
                        magnitude_extremes=magnitude_extremes)
    return out
