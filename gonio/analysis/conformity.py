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
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal, localcontext

from gonio.errors import GonioError
from gonio.formats.lab import (DECISION_RULES, check_guard_factor, check_interval,
                              check_limit_unit, check_nonnegative, check_one_limit_per_item,
                              check_symmetric)
from gonio.result.model import Conformity
from gonio.result.statement import (K_SOURCE_BOUND_CHI2, decimals_for_sig, given_text,
                                    is_magnitude_statement, item_statement, p_text, stated_nu,
                                    chi2_nu)

__all__ = ["RULES", "OUTCOMES", "DecisionRule", "Limits", "Conformity", "normal_cdf",
           "conformance_probability", "acceptance_interval", "decide", "limits_of",
           "rule_of", "check_one_limit_per_item", "decide_items", "decide_result",
           "DEFAULT_LIMITS_ORIGIN"]

#: ``limits_from`` of an item decided on a specification's default tolerance
#: (``SPEC.default_limits``), where the laboratory file gives no limit for it.
DEFAULT_LIMITS_ORIGIN = "specification default"

_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")

#: Decision rules a laboratory file may name (``[decision_rule] rule = ...``).
RULES: tuple[str, ...] = DECISION_RULES
#: Outcomes, in the words of ILAC-G8:09/2019 4.2.3.
OUTCOMES: tuple[str, ...] = ("pass", "conditional pass", "conditional fail", "fail")


@dataclass(frozen=True)
class DecisionRule:
    """A decision rule: ``kind`` in :data:`RULES`, guard band w = ``guard_factor`` · U.

    ``guard_factor`` is ignored by ``simple`` (w = 0); a rule with a guard band needs r ≥ 1
    (:func:`gonio.formats.lab.check_guard_factor`).
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
        try:
            check_guard_factor(self.kind, self.guard_factor)
        except GonioError as exc:
            raise GonioError(exc.message, key="decision_rule.guard_band_factor") from None

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
                             "decided on its {p} % interval")


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
    # compared exactly on the decimal numbers given (a printed value on a printed limit is
    # on it, never 1e-11 beside it by the float arithmetic of T_U − w)
    with localcontext() as ctx:
        ctx.prec = 80
        D = (lambda x: None if x is None else Decimal(repr(float(x))))  # noqa: E731
        yD, wD = D(y), (D(0.0) if rule.kind == "simple" else
                        D(rule.guard_factor) * D(U))
        wloD = wD if U_lower is None else (D(0.0) if rule.kind == "simple" else
                                           D(rule.guard_factor) * D(max(float(U_lower), 0.0)))
        T_L, T_U = D(limits.lower), D(limits.upper)
        a_loD = None if T_L is None else T_L + wloD
        a_hiD = None if T_U is None else T_U - wD
        in_tol = _inside(yD, T_L, T_U)
        in_acc = _inside(yD, a_loD, a_hiD)
        below = (T_L - yD) if T_L is not None else None
        above = (yD - T_U) if T_U is not None else None
    a_lo = None if a_loD is None else float(a_loD)
    a_hi = None if a_hiD is None else float(a_hiD)
    if rule.kind == "non-binary":
        if in_acc:
            outcome = "pass"
        elif in_tol:
            outcome = "conditional pass"
        else:
            below = below if below is not None else Decimal("-Infinity")
            above = above if above is not None else Decimal("-Infinity")
            # outside the tolerance, "conditional" where the interval reaches back in: below
            # the lower limit by its reach above the value (w), above the upper limit by its
            # reach below it (w_lo)
            outcome = ("conditional fail" if (below <= wD if below >= above else above <= wloD)
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
NOT_NORMAL_PROBABILITY_MODEL = ("not given: its {p} % interval ({source}) is not that of a "
                                "normal or chi-square distribution; the outcome is decided on "
                                "its {p} % interval")


def extreme_of_magnitudes(key: str, it, declared=()) -> bool:
    """Whether item ``it`` (key ``key``) is an extreme of magnitudes max_i |x_i| (the optical
    draft's E, 7.4: E = ± max|E_i|; the rate gyros' largest magnitudes): its specification
    declares it so (``declared``: its ``Specification.magnitude_extremes``), or its statement
    is of that kind (``k_source`` one of
    :data:`~gonio.result.statement.MAGNITUDE_K_SOURCES`,
    :func:`~gonio.result.statement.is_magnitude_statement`), whichever specification computed
    it. Such a value is compared with a symmetric limit only
    (:func:`gonio.formats.lab.check_symmetric`) and accepted on its upper end only: the
    declaration also covers the draft's own max|E_i| ± U (k given), which carries no marker.

    >>> from gonio.result.model import Item, Uncertainty
    >>> it = Item("E", "E", "7.4", "″", 0.4)
    >>> extreme_of_magnitudes("E", it, ("E",)), extreme_of_magnitudes("E", it)
    (True, False)
    >>> from gonio.result.statement import K_SOURCE_MAX_MAGNITUDE
    >>> it.uncertainty = Uncertainty([], 0.05, 0.1, None, None, None, 0.95,
    ...                              K_SOURCE_MAX_MAGNITUDE, (0.3, 0.5))
    >>> extreme_of_magnitudes("B_g", it)
    True
    """
    return bool(key in declared or is_magnitude_statement(it.uncertainty))


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


def check_nonnegative_limit(key: str, item, bounds: Limits, where: str) -> None:
    """An item that cannot be negative (``item.nonnegative``: a range, a dispersion, a noise
    level) with an upper limit below zero: no value of it can conform, so the limit is a
    mistake of the file (a sign, a unit), a GonioError naming the entry ``where`` and the
    item, never a "fail" on the certificate (:func:`gonio.formats.lab.check_nonnegative`,
    which the laboratory file's and the records' checks run on the items a specification
    declares so before any work; here it guards the items its result marks non-negative).

    >>> from gonio.result.model import Item
    >>> it = Item("B_s", "zero stability", "7.3", "deg/h", 0.1, nonnegative=True)
    >>> check_nonnegative_limit("B_s", it, Limits(None, 0.01), "specification_limits[0]")
    >>> check_nonnegative_limit("B_s", it, Limits(None, -0.01), "specification_limits[0]")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key specification_limits[0].upper: B_s cannot be negative, so its upper limit -0.01 below zero can never be met; check the limit's sign and unit
    """
    if getattr(item, "nonnegative", False):
        check_nonnegative(key, bounds.upper, key=f"{where}.upper")


#: ``probability_model`` of an item whose U has a coverage factor from a non-normal combined
#: distribution (JCGM 101 convolution, :func:`decide_items`): N(y, U/k) is not the
#: distribution whose 95 % half-width is U, so no probability is given; the outcome is
#: decided on y against the acceptance interval: under a guard band (guarded, non-binary) y
#: within the tolerance narrowed by r·U, "decided on y ± U"; under simple acceptance (w = 0)
#: y alone within the tolerance (:data:`NON_NORMAL_K_DECIDED`, by rule).
NON_NORMAL_K_PROBABILITY_MODEL = ("not given: its k = {k} is the 95 % coverage factor of a "
                                  "non-normal combined distribution ({source}), not of "
                                  "N(y, U/k); the outcome is decided on {decided}")
#: What the outcome of :data:`NON_NORMAL_K_PROBABILITY_MODEL` is decided on, by rule kind.
NON_NORMAL_K_DECIDED: dict[str, str] = {
    "simple": "y alone (simple acceptance, no guard band)",
    "guarded": "y ± U", "non-binary": "y ± U"}

#: ``k_source`` of a k that is the 95 % coverage factor of a non-normal combined distribution
#: (the optical draft's JCGM 101 convolution of its budget, ``K_SOURCE_COMBINED`` there): the
#: normal model N(y, (U/k)²) of JCGM 106 7.3 does not hold for it (:func:`_decided`).
NON_NORMAL_K_SOURCES: tuple[str, ...] = ("jcgm101-convolution",)


def decidable(unc) -> bool:
    """Whether an item's uncertainty states something to decide with: an item stated by its
    interval alone (no k) an interval of positive, finite width — its value may sit on an
    end, as a rule outcome on its grid does, so its U (the reach above the value) may be 0 —;
    an item stated y ± U a positive, finite U.

    >>> from gonio.result.model import Uncertainty
    >>> decidable(Uncertainty([], 0.01, 0.0, None, None, None, 0.98, "rule-outcome",
    ...                       (0.02, 0.05)))
    True
    >>> decidable(Uncertainty([], 0.0, 0.0, None, None, None, 0.95, "chi-square", (0.0, 0.0)))
    False
    >>> decidable(Uncertainty([], 0.05, 0.1, 2.0, None)), decidable(None)
    (True, False)
    """
    if unc is None:
        return False
    if unc.k is None:
        if unc.interval is None:
            return False
        lo, hi = (float(x) for x in unc.interval)
        return math.isfinite(lo) and math.isfinite(hi) and hi > lo
    return unc.U is not None and math.isfinite(unc.U) and unc.U > 0


def _decided(key: str, it, bounds: Limits, rule: DecisionRule, origin: str,
             magnitude: bool) -> Conformity:
    """The decision of a measured item with U (:func:`decide_items`)."""
    unc = it.uncertainty
    if (unc.k is None and unc.interval is not None) or item_statement(it).interval is not None:
        # stated by an interval (its own, or a non-negative quantity whose U reaches below
        # zero, stated "≤ b" with the interval [0, b]): decided on that one statement, never
        # on a value ± U the certificate does not print
        c = _decided_interval(key, it, bounds, rule, magnitude)
    else:
        no_p = None
        if unc.k_source in NON_NORMAL_K_SOURCES:
            no_p = NON_NORMAL_K_PROBABILITY_MODEL.format(
                k=f"{float(unc.k):.3g}", source=unc.k_source,
                decided=NON_NORMAL_K_DECIDED.get(rule.kind, "y ± U"))
        # ν as stated (integer part, stated_nu): the ν of the χ² interval beside the value
        nu_chi2 = (stated_nu(unc.nu_eff) if unc.interval is not None and no_p is None
                   and unc.nu_eff is not None and math.isfinite(unc.nu_eff)
                   and unc.nu_eff > 0 and it.value > 0 else None)
        y, U, dec, _ = stated_value_of(it)
        c = decide(key, float(y), float(U), float(unc.k), bounds, rule,
                   chi2_nu=nu_chi2, no_probability=no_p)
        raw = decide(key, float(it.value), float(unc.U), float(unc.k), bounds, rule,
                     chi2_nu=nu_chi2, no_probability=no_p)
        c = replace(stricter_of(c, raw, it.value),
                    **_acceptance_texts(c.acceptance_lower, c.acceptance_upper, bounds, dec))
    c = replace(c, limits_from=origin)
    lo, hi = c.acceptance_lower, c.acceptance_upper
    return replace(c, acceptance_empty=bool(
        (lo is not None and hi is not None and lo > hi)
        or (it.nonnegative and hi is not None and hi < 0)))


#: Outcomes from the least to the most strict (:func:`stricter_of`).
OUTCOME_STRICTNESS: tuple[str, ...] = ("pass", "conditional pass", "conditional fail", "fail")


def stricter_of(printed: Conformity, measured: Conformity, value: float) -> Conformity:
    """The decision on what the certificate prints (``printed``), made no less strict by the
    decision on the measured value before rounding (``measured``; ILAC-G8:09/2019 4.2 decides
    on the measurement result, not on its rounded text). Rounding a value to its printed
    digits moves it by up to half a unit of the last digit, towards or away from a limit: a
    printed value above a printed limit never passes (the printed decision), and a measured
    value beyond a limit never passes because its printed value rounds back inside (the
    measured decision). Where the measured decision is the stricter, its outcome is stated
    and ``decided_on_measured`` holds the measured value that decided it
    (:func:`measured_value_text`, the text every output prints),
    so that the certificate can say why a printed value inside the limit does not pass;
    everything else (acceptance limits, probabilities) stays the printed decision's.

    >>> from gonio.analysis.conformity import decide, Limits, DecisionRule
    >>> r = DecisionRule("simple")
    >>> a = decide("K", 76434.846, 0.011, 2.0, Limits(None, 76434.8462), r)
    >>> b = decide("K", 76434.8464, 0.0105, 2.0, Limits(None, 76434.8462), r)
    >>> c = stricter_of(a, b, 76434.8464)
    >>> a.outcome, b.outcome, c.outcome, c.accepted, c.decided_on_measured
    ('pass', 'fail', 'fail', False, '76434.8464')
    >>> stricter_of(b, a, 76434.846).decided_on_measured is None
    True
    """
    rank = OUTCOME_STRICTNESS.index
    if (printed.outcome is None or measured.outcome is None
            or rank(measured.outcome) <= rank(printed.outcome)):
        return printed
    p_c = printed.conformance_probability
    limits = (printed.lower, printed.upper, printed.acceptance_lower, printed.acceptance_upper,
              measured.lower, measured.upper, measured.acceptance_lower,
              measured.acceptance_upper)
    return replace(printed, outcome=measured.outcome, accepted=measured.accepted,
                   decided_on_measured=measured_value_text(value, limits),
                   decided_on_measured_acceptance=measured_acceptance_text(
                       measured.acceptance_lower, measured.acceptance_upper, value),
                   false_accept_probability=(None if not measured.accepted or p_c is None
                                             else 1.0 - p_c),
                   false_reject_probability=None if measured.accepted else p_c,
                   false_accept_bound=None)


#: The fewest significant digits :func:`measured_value_text` prints.
MEASURED_TEXT_MIN_DIGITS = 10


def measured_acceptance_text(lower: float | None, upper: float | None, value: float
                             ) -> str | None:
    """The acceptance interval a measured decision used (:func:`stricter_of`), as the
    statement names it: "≤ b", "≥ a" or "[a, b]" (minus signs as "−"), each end printed with
    :func:`measured_value_text` against the measured value, so that the text shows on which
    side of it the value lies; None where both ends are open. An empty interval (a > b) is
    printed as it is.

    >>> measured_acceptance_text(None, 783.94479, 786.4851027)
    '≤ 783.94479'
    >>> measured_acceptance_text(-0.0757, 0.49, -0.07566)
    '[−0.0757, 0.49]'
    """
    def end(x: float) -> str:
        return measured_value_text(float(x), (value,)).replace("-", "−")

    lo = None if lower is None or not math.isfinite(float(lower)) else float(lower)
    hi = None if upper is None or not math.isfinite(float(upper)) else float(upper)
    if lo is None and hi is None:
        return None
    if lo is None:
        return f"≤ {end(hi)}"
    if hi is None:
        return f"≥ {end(lo)}"
    return f"[{end(lo)}, {end(hi)}]"


def measured_value_text(value: float, limits) -> str:
    """The measured value that decided an outcome (:func:`stricter_of`), as printed: at least
    :data:`MEASURED_TEXT_MIN_DIGITS` significant digits, and as many more as it takes for the
    printed text to lie on the same side of every given limit (tolerance and acceptance
    limits; ``None`` ends skipped) as the value itself, so that a reader can check from the
    certificate that the value lies beyond the limit (a value 76434.85092592593 beyond a limit
    76434.85093 is never printed "76434.85093"). At 17 digits the text is the float's own.

    >>> measured_value_text(76434.85092592593, (76434.85093, None))
    '76434.850926'
    >>> measured_value_text(76434.8464, (None, 76434.8462))
    '76434.8464'
    """
    v = float(value)
    ends = [float(x) for x in limits if x is not None and math.isfinite(float(x))]
    for d in range(MEASURED_TEXT_MIN_DIGITS, 18):
        t = f"{v:.{d}g}"
        if all((float(t) > L) == (v > L) and (float(t) < L) == (v < L) for L in ends):
            return t
    return repr(v)


def _acceptance_texts(a_lo: float | None, a_hi: float | None, bounds: Limits,
                      decimals: int) -> dict:
    """The acceptance limits as printed, decided once here (the renderer prints these
    texts): a limit equal to the tolerance limit as given; any other at ``decimals`` places
    rounded inward (upper end down, lower end up), so that a stated number on that decimal
    grid lies inside the printed acceptance interval exactly when it lies inside the decided
    one (:func:`stated_interval_of` states interval ends on that grid).

    >>> _acceptance_texts(None, 0.4709, Limits(None, 0.5), 2)
    {'acceptance_lower_text': None, 'acceptance_upper_text': '0.47'}
    >>> _acceptance_texts(-0.5, 0.5, Limits(-0.5, 0.5), 2)["acceptance_upper_text"]
    '0.5'
    """
    def text(v, lim, rounding):
        if v is None:
            return None
        if v == lim:
            return given_text(v)
        return _plain(Decimal(repr(float(v))).quantize(Decimal(1).scaleb(-decimals),
                                                        rounding=rounding), keep=True)
    return {"acceptance_lower_text": text(a_lo, bounds.lower, ROUND_CEILING),
            "acceptance_upper_text": text(a_hi, bounds.upper, ROUND_FLOOR)}


def stated_interval_of(it) -> tuple[Decimal, Decimal, Decimal, int, tuple[str, str, str]]:
    """The interval of an item stated by its 95 % interval alone, as its statement prints it
    (:func:`gonio.result.statement.item_statement`: lower end rounded down, upper end up, at
    the statement's decimal place), and the value as stated: (value, lower end, upper end,
    decimal place, the three as printed). A non-negative quantity whose estimate fell below zero is stated by its
    upper bound alone ("the estimate fell below zero", the interval [0, upper]): its stated
    value is the interval's lower end, 0, the least value the statement admits.

    The decision is taken on these numbers (what the certificate states), never on the
    unrounded ends or an unprinted bias-corrected estimate, so the printed interval and the
    printed acceptance limit never contradict the outcome.

    >>> from gonio.result.model import Item, Uncertainty
    >>> it = Item("C_g", "C_g", "7.7", "%", -1.58e-5, nonnegative=True,
    ...           uncertainty=Uncertainty([], 1e-6, 2.98e-5, None, None, None, 0.95, "belt",
    ...                                   (0.0, 1.4e-5)))
    >>> [str(x) for x in stated_interval_of(it)[:3]], stated_interval_of(it)[4]
    (['0.000000', '0.000000', '0.000014'], ('0', '0', '0.000014'))
    """
    st = item_statement(it)
    scale = Decimal(1).scaleb(st.exponent)
    lo, hi = (Decimal(x.replace("−", "-")) * scale for x in st.interval)
    value = lo if st.below_zero else Decimal(st.value.replace("−", "-")) * scale
    ends = tuple("0" if x == 0 else t for x, t in zip((lo, hi), st.interval_ends))
    return value, lo, hi, int(st.decimals), (ends[0] if st.below_zero else st.value_text,
                                              ends[0], ends[1])


def stated_value_of(it) -> tuple[Decimal, Decimal, int, str]:
    """The value and U of an item stated y ± U, as its statement prints them
    (:func:`gonio.result.statement.item_statement`, at its decimal place): (value, U, decimal
    place, the value as printed). A non-negative quantity stated by its upper bound alone
    ("≤ b", U above the value) is the interval [0, b]: the printed value, U = b − value
    (the guard band reaches the printed bound); one whose estimate fell below zero: 0 and
    U = b.

    The decision is taken on these numbers, as :func:`stated_interval_of` does for an item
    stated by its interval: the printed value against the limit as given, exactly, so a
    printed value above a printed limit never passes (K = 76434.847 printed fails an upper
    limit 76434.8468, whatever the unrounded 76434.84675).

    >>> from gonio.result.model import Item, Uncertainty
    >>> it = Item("K", "K", "7.1", "counts/deg", 76434.84675,
    ...           uncertainty=Uncertainty([], 0.005, 0.0105, 2.1, 40.0, None, 0.95))
    >>> v, U, dec, txt = stated_value_of(it)
    >>> str(v), str(U), dec, txt
    ('76434.847', '0.011', 3, '76434.847')
    """
    st = item_statement(it)
    scale = Decimal(1).scaleb(st.exponent)
    num = (lambda t: Decimal(t.replace("−", "-")) * scale)  # noqa: E731
    dec = int(st.decimals) if st.decimals is not None else \
        decimals_for_sig(float(it.uncertainty.U), 2)
    if st.below_zero:
        hi = num(st.interval[1])
        return Decimal(0), hi, dec, "0"
    value = num(st.value)
    if st.U is not None:
        return value, num(st.U), dec, st.value_text
    hi = num(st.upper)
    return value, max(hi - value, Decimal(0)), dec, st.value_text


def interval_guard_U(lo: Decimal, hi: Decimal, value: Decimal | None = None) -> Decimal:
    """U of the guard band w = r·U of an item stated by its 95 % interval [lo, hi] alone: the
    interval's half-width (hi − lo)/2; for the one-sided χ² upper bound [0, b] of a standard
    deviation (``value``: its stated estimate s, given only for such an item) the reach of
    the bound above the estimate, b − s.

    A χ² bound is the interval of σ's own distribution about s (s·√(ν/χ²₀.₀₅,ν), the U of
    :func:`gonio.result.gum.std_dev_uncertainty`), not a centre ± U: its half-width b/2 would
    be, for a large ν, many times the statement's reach above s (ARW ≤ 1.826 with s = 1.808:
    b/2 = 0.913, b − s = 0.018), and r > 1 would then reject an item whose bound lies well
    within the limit while its χ² probability of conformance is 100 %. Both b and s are
    printed (s·√(ν/χ²) fixes b/s), so the same printed statement still gets the same
    decision.

    Such an item has no k (its distribution is not symmetric about its estimate), so the only
    U its statement gives is the one that states the same interval as centre ± U:
    [lo, hi] = (lo + hi)/2 ± (hi − lo)/2. ILAC-G8:09/2019 4.2.2 sets w = r·U with U the
    expanded uncertainty of the result as stated, and JCGM 106:2012 8.3.2 the acceptance
    interval [T_L + w, T_U − w] for the stated result: applied to that centre, r = 1 accepts
    exactly when the whole stated interval lies within the tolerance, and r > 1 moves each
    end in by (r − 1)·U. A dispersion's one-sided bound-condition limit [0, s + a + R]
    (:data:`gonio.result.statement.K_SOURCE_BOUND_CHI2`: a χ² reach beyond its bounded
    lines) is a bound above its estimate as a χ² bound is: U = b − s. Any other one-sided
    bound [0, b] of a non-negative quantity is the same rule as an interval, U = b/2. Being a
    function of the printed numbers alone, the same printed interval always gets the same
    decision (an unprinted bias-corrected estimate no longer enters).

    >>> interval_guard_U(Decimal("0.066"), Decimal("0.205"))
    Decimal('0.0695')
    >>> interval_guard_U(Decimal("0"), Decimal("1.826"), Decimal("1.808"))
    Decimal('0.018')
    """
    if value is not None:
        return max(hi - value, Decimal(0))
    return (hi - lo) / 2


def _decided_interval(key: str, it, bounds: Limits, rule: DecisionRule,
                      magnitude: bool) -> Conformity:
    """The decision of an item stated by its 95 % interval alone, on what its statement
    prints (:func:`stated_interval_of`): the value v, the interval [lo, hi], U its half-width,
    or for a standard deviation's one-sided χ² bound the bound's reach above v
    (:func:`interval_guard_U`).

    * simple (ILAC-G8 4.2.1, w = 0): pass when v lies within the tolerance;
    * guarded (4.2.2, w = r·U, r ≥ 1): pass when hi ≤ T_U − (r − 1)·U and lo ≥ T_L +
      (r − 1)·U (the centre within [T_L + w, T_U − w]; r = 1: the interval within the
      tolerance);
    * non-binary (4.2.3): pass as guarded; else conditional pass when v lies within the
      tolerance; else conditional fail when the interval, widened by (r − 1)·U, still reaches
      into the tolerance (the centre outside by at most w); else fail.

    An extreme of magnitudes (``magnitude``: v, lo, hi ≥ 0 against a symmetric limit ±M) is
    accepted on its upper end only. A probability is given only for the χ² interval of a
    standard deviation (its χ² model, from the estimate s); elsewhere none
    (:data:`NOT_NORMAL_PROBABILITY_MODEL`), and an item accepted under a guard band (r ≥ 1)
    states the bound its rule implies, ``false_accept_bound`` = 1 − p: its stated interval's
    upper end lies within the limit, and the measurand lies above that end with probability
    at most 1 − p (5 % for a one-sided 95 % bound, as the χ² limits and E's extreme are;
    an item stated y ± U with a normal k = 2 at r = 1 has at most 2.5 %).
    """
    unc = it.uncertainty
    v, lo, hi, dec, printed = stated_interval_of(it)
    chi2 = unc.k_source == "chi-square" and unc.nu_eff is not None and it.value > 0 \
        and math.isfinite(unc.nu_eff) and unc.nu_eff > 0
    # a dispersion's one-sided limit above its estimate (χ², or χ² beyond a bound condition):
    # the guard band's U is the limit's reach above the estimate
    reach = chi2 or (unc.k_source == K_SOURCE_BOUND_CHI2 and it.value > 0)
    U = interval_guard_U(lo, hi, v if reach else None)
    r = Decimal(repr(float(rule.guard_factor)))
    T_L = None if bounds.lower is None or magnitude else Decimal(repr(float(bounds.lower)))
    T_U = None if bounds.upper is None else Decimal(repr(float(bounds.upper)))
    if rule.kind == "simple":
        a_lo, a_hi, w = T_L, T_U, Decimal(0)
    else:
        w = r * U
        a_lo = None if T_L is None else T_L + (r - 1) * U
        a_hi = None if T_U is None else T_U - (r - 1) * U

    def outcome_of(v, lo, hi) -> str:
        in_tol = (T_L is None or v >= T_L) and (T_U is None or v <= T_U)
        if rule.kind == "simple":
            return "pass" if in_tol else "fail"
        if (a_lo is None or lo >= a_lo) and (a_hi is None or hi <= a_hi):
            return "pass"
        if rule.kind == "guarded":
            return "fail"
        if in_tol:
            return "conditional pass"
        reach = ((T_U is None or lo - (r - 1) * U <= T_U)
                 and (T_L is None or hi + (r - 1) * U >= T_L))
        return "conditional fail" if reach else "fail"

    outcome = outcome_of(v, lo, hi)
    # the measured value and interval before rounding (stricter_of): a value stated by its
    # bound alone (below zero) is its interval's lower end, as stated_interval_of takes it
    D = (lambda x: Decimal(repr(float(x))))  # noqa: E731
    # an item with U stated by its bound ("≤ b": U reaches below zero) has [0, value + U]
    raw = (unc.interval if unc.interval is not None
           else (0.0, float(it.value) + float(unc.U)))
    raw_lo, raw_hi = (D(x) for x in raw)
    measured = abs(float(it.value)) if magnitude else float(it.value)   # E: max|E_i|
    raw_v = raw_lo if v == lo and measured < float(raw[0]) else D(measured)
    raw_outcome = outcome_of(raw_v, raw_lo, raw_hi)
    if chi2:
        nu = chi2_nu(unc.nu_eff)        # as stated: the ν the interval was computed with
        p_c = conformance_probability_chi2(float(it.value), nu, bounds.lower, bounds.upper)
        model = f"chi-square, nu = {nu:g}"
    else:
        p_c = None
        # the interval's own p (the item's statement: 95.45 % at a p chosen so, p ≈ 98 % for a
        # grid-step interval), never a fixed "95 %"
        pt = p_text(float(unc.coverage_probability or 0.95))
        model = (MAX_ABS_PROBABILITY_MODEL.format(p=pt) if magnitude else
                 NOT_NORMAL_PROBABILITY_MODEL.format(
                     p=pt, source=("[0, value + U]: a non-negative quantity whose U reaches "
                                   "below zero" if unc.interval is None
                                   else unc.k_source or "its own")))
    accepted = outcome in ("pass", "conditional pass")
    p = float(unc.coverage_probability or 0.95)
    bound = (round(1.0 - p, 12) if outcome == "pass" and rule.kind != "simple"
             and p_c is None else None)
    f = (lambda x: None if x is None else float(x))  # noqa: E731
    texts = _acceptance_texts(f(a_lo), f(a_hi), bounds, dec)
    c = Conformity(
        item=key, value=float(v), U=float(U), k=None, lower=bounds.lower, upper=bounds.upper,
        rule=rule.kind, guard_band=float(w), acceptance_lower=f(a_lo),
        acceptance_upper=f(a_hi), outcome=outcome, accepted=accepted,
        conformance_probability=p_c,
        false_accept_probability=(1.0 - p_c) if accepted and p_c is not None else None,
        false_reject_probability=p_c if not accepted else None, source=bounds.source,
        guard_factor=float(rule.guard_factor), probability_model=model,
        acceptance_of="value" if rule.kind == "simple" else "interval",
        stated_interval=printed[1:], stated_value=printed[0],
        false_accept_bound=bound, **texts)
    return stricter_of(c, replace(c, outcome=raw_outcome,
                                  accepted=raw_outcome in ("pass", "conditional pass")),
                       float(raw_v))


def _plain(d: Decimal, keep: bool = False) -> str:
    """A stated Decimal as text: plain where its exponent is moderate, else as the
    certificate's power of ten (mantissa digits kept, never rounded again); ``keep`` keeps
    trailing zeros (the decimal place it was rounded at).

    >>> _plain(Decimal("0.0000140")), _plain(Decimal("0.0000140"), keep=True)
    ('0.000014', '0.0000140')
    >>> _plain(Decimal("1.45E-9"))
    '1.45×10⁻⁹'
    """
    d = d if keep else d.normalize()
    if d == 0 or -7 <= d.adjusted() < 15:
        return format(d, "f")
    e = d.adjusted()
    return f"{format(d.scaleb(-e), 'f')}×10{str(e).translate(_SUP)}"


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
    statement) takes a symmetric limit only (:func:`check_symmetric_limit`). A limit that
    states its ``unit`` is checked against the item's unit here, once the result states it
    (:func:`gonio.formats.lab.check_limit_unit`: the same unit however spelt, else refused,
    never converted). An item stated by its
    95 % interval alone is decided on that interval as stated (:func:`_decided_interval`); its
    acceptance bounds the interval's ends under a guard band, and a probability is given only
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
        check_limit_unit(key, lim, it.unit, key=f"{where}[{i}].unit")
        bounds = limits_of(lim)
        magnitude = extreme_of_magnitudes(key, it, magnitude_extremes)
        if magnitude:
            check_symmetric_limit(key, bounds, f"{where}[{i}]")
        check_nonnegative_limit(key, it, bounds, f"{where}[{i}]")
        unc = it.uncertainty
        if not it.measured or it.value is None:
            c = _undecided(key, bounds, rule, origin, "not measured: " + (it.reason or ""))
        elif not decidable(unc):
            c = _undecided(key, bounds, rule, origin, "no expanded uncertainty to decide with")
        else:
            c = _decided(key, it, bounds, rule, origin, magnitude)
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
