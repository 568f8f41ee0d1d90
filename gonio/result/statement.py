"""The one statement rule: how every output states a measured value with its uncertainty.

Contents
========
=========================  ================================================================
:func:`round_half_up`      a number to a given decimal place, half up, as text
:func:`decimals_for_sig`   the decimal place that leaves ``sig`` significant digits
:func:`decimals_at_U`      the decimal place of U stated to two significant digits
:func:`rounded`            a number to ``sig`` significant digits, as a float (a budget that
                           carries a stated number on into a later step)
:func:`state`              value, U, k, ν_eff, p and unit → a :class:`Statement`
:func:`state_interval`     value and its coverage interval (a dispersion, range, extreme)
                           → a :class:`Statement` with one interval, no ± U and no k
:func:`numerical_decimals` the last decimal place a Monte Carlo's finite draws leave
                           significant (JCGM 101 7.9)
:func:`item_statement`     the statement of one results.json item (or model ``Item``)
:func:`below_zero_bound`   a non-negative quantity whose estimate fell below zero: stated by
                           its upper bound alone, with a note (the estimate stays in results.json)
:class:`Statement`         the rounded texts every output prints (certificate, summary.txt,
                           CLI, DCC, figure labels)
:func:`k_text`             a coverage factor as stated (3 significant digits; "2" only for k = 2)
:func:`nu_text`            effective degrees of freedom as stated (integer part, or ∞)
:func:`stated_nu`          ν_eff as stated and as k is computed from (integer part; ∞ above
                           :data:`NU_INFINITE`)
:func:`coverage_k`         k = t_p(ν) of the stated ν (so k and the printed ν agree)
:func:`stated_gum`         a GUM result with k and U from :func:`coverage_k`
:func:`p_text`             a coverage probability in per cent as stated
:func:`unit_text`          a results.json unit in its SI (accepted-unit) printed form
:func:`dsi_unit`           a results.json unit in D-SI form (with the factor applied)
=========================  ================================================================

The rule (JCGM 100:2008 (GUM) 7.2.6, 7.2.2; JCGM 101 and EA-4/02 the same):

* the expanded uncertainty U is stated to **two significant digits**, rounded half up
  (0.00316 → 0.0032, 160 → 160, 0.0996 → 0.10);
* the value is stated to **the same decimal place** as U, half up (5.99906 → 5.9991 beside
  0.0032, 786.5 → 790 beside 160: digits left of the point are rounded away when U is that
  large);
* beside U: the coverage factor k (3 significant digits: 1.97414 → 1.97; trailing zeros
  dropped only where k is exactly that number, 2.0 → 2, while a computed t-factor keeps
  them, 1.9955 → 2.00), the effective degrees of freedom ν_eff (the integer part, GUM G.6.4:
  "truncate to the next lower integer"; ∞ where the budget has infinite degrees of
  freedom or more than :data:`NU_INFINITE`) and the coverage probability p in per cent
  (:func:`p_text`: a p chosen by the procedure as chosen, 0.95 → 95, 0.9545 → 95.45; a p
  computed from a distribution to 2 significant digits, 0.99465 → 99);
* a quantity without an uncertainty keeps the specification's number of significant
  digits (``sig``, 3 unless the specification says otherwise);
* U stated to more than six decimal places (or a value of 10¹⁵ or more) is written with a
  power of ten common to value and U, that of the larger one's leading digit, both mantissas
  at U's decimal place ("2.18×10⁻⁵ ± 0.13×10⁻⁵", never "2.2×10⁻⁵ ± 1.3×10⁻⁶");
* k and the printed ν_eff agree: k is computed from the ν_eff as stated
  (:func:`coverage_k`: t_p of the integer part; the normal quantile above
  :data:`NU_INFINITE`), never from the unrounded ν_eff (ν_eff 2.43 is stated "2" with
  k = t_95(2) = 4.30, not k = 3.78);
* units are printed in the SI form of :func:`unit_text` (degree, hour and second of arc are
  units accepted for use with the SI, SI Brochure table 8) and written to a DCC in the
  D-SI form of :func:`dsi_unit`.

**A non-negative quantity whose U exceeds its value** (a noise level, a threshold, a
start-up time, a hysteresis, a bias instability: the interval value ± U reaches below zero,
which the quantity cannot take). Following GUM 4.3.9 / JCGM 101 7.7 (a coverage interval
contains only possible values) and the ISO 80000-1 way of stating a bound, the statement is
**one** coverage interval, the interval value ± U truncated at zero, stated as an **upper
bound**: ``upper`` = value + U rounded *up* at U's decimal place (so the bound is never
understated), printed "≤ upper (interval [0, upper], p = 95 %)"; "± U" and k are not
printed beside it (two statements of one item, one of them holding impossible values).
Its coverage probability is at least the stated p (the part cut away holds no possible
value). The value keeps U's decimal place; ``Statement.U`` and ``k`` are None and
``interval`` is ("0", upper), so every output states it as it states an item stated by its
interval (:func:`state_interval`). **A non-negative
quantity whose whole interval lies at or below zero** (value + U ≤ 0: an estimate below
zero by more than its U) has no coverage interval of possible values at all; the rule
refuses to state it (:class:`~gonio.errors.GonioError`), and a specification reports such
an item as not measured with that reason; it is never printed as a negative bound
("≤ -4.0 s"). **A non-negative quantity whose estimate fell below zero while its interval
does not** (a range or spread corrected for its bias, K_l, C_v, C_g: the correction can take
the estimate below zero when the errors alone would spread the values more than they were
measured to spread) is stated by its **upper bound alone**, "≤ upper (p = 95 %)", with the
note that the estimate fell below zero (:func:`below_zero_bound`, ``Statement.below_zero``):
a negative value printed beside its [0, upper] interval would state a value the quantity
cannot take. results.json keeps the signed estimate (a later correction or a pooled
analysis needs it); every printed output (certificate, summary.txt, the web, the DCC's
description) says the bound and the note. An empty acceptance interval of such a quantity (guard band wider than the
limit) is likewise said in words, never as a negative limit
(:func:`gonio.report.stated.conformity_texts`). Wording used by
every output: en "upper bound: ≤ 0.098 °/s (interval [0, 0.098], p = 95 %)", zh "上限：≤
0.098 °/s（区间 [0, 0.098]，p = 95 %）". The issue-24 coverage studies check such items one-sidedly: the
truth must lie below ``upper``. A quantity that may be negative (a bias, an offset, a
signed deviation) is declared ``nonnegative=False`` and is never given a bound.

>>> s = state(5.99906, 0.00316, k=1.97414, nu_eff=58.7, p=0.95, unit="mV/(°/s)")
>>> s.value, s.U, s.k, s.nu_eff, s.p, s.text()
('5.9991', '0.0032', '1.97', '58', '95', '5.9991 ± 0.0032 mV/(°/s) (k = 1.97, ν_eff = 58, p = 95 %)')
>>> state(786.5, 160.0, k=2.0, unit="°/h").text()
'790 ± 160 °/h (k = 2)'
>>> t = state(0.01, 0.088, k=2.0, p=0.95, unit="°/s", nonnegative=True)
>>> t.value, t.U, t.k, t.upper, t.text()
('0.010', None, None, '0.098', '0.010 °/s; upper bound: ≤ 0.098 °/s (interval [0, 0.098], p = 95 %)')
>>> state(2.1805064e-05, 1.3e-06, k=2).text()
'2.18×10⁻⁵ ± 0.13×10⁻⁵ (k = 2)'
>>> state(76434.8425925926, None, sig=8, unit="1").text()
'76434.843'
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from decimal import ROUND_CEILING, ROUND_FLOOR, ROUND_HALF_UP, Decimal, localcontext

from gonio.errors import GonioError
from gonio.units import STANDARD_GRAVITY_M_S2

_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _wide():
    """A decimal context wide enough for every float at every decimal place (±1e308, 1e-324)."""
    return localcontext(prec=1400, Emax=999_999, Emin=-999_999)


def _exact_sum(a: float, b: float) -> Decimal:
    """``a + b`` of the two floats' shortest reprs, exactly: an upper bound rounded up
    (ROUND_CEILING) from a float sum would carry its binary artefact one place up
    (0.1 + 0.2 = 0.30000000000000004 → "0.31").

    >>> _exact_sum(0.1, 0.2)
    Decimal('0.3')
    """
    with _wide():
        return Decimal(repr(float(a))) + Decimal(repr(float(b)))


def round_half_up(x: float | Decimal, decimals: int, rounding: str = ROUND_HALF_UP) -> str:
    """``x`` rounded half up to ``decimals`` places (negative: tens, hundreds...), as text.

    Works on the shortest repr of the float, so 0.125 → "0.13" and 2.675 → "2.68" (a
    :class:`~decimal.Decimal` is taken exactly); a result that rounds to zero has no sign.

    >>> round_half_up(0.35896, 2), round_half_up(-0.11879, 2), round_half_up(76434.84259, 3)
    ('0.36', '-0.12', '76434.843')
    >>> round_half_up(0.125, 2), round_half_up(1234.5, -2), round_half_up(-0.0004, 2)
    ('0.13', '1200', '0.00')
    """
    exact = x if isinstance(x, Decimal) else None
    x = float(x)
    if not math.isfinite(x):
        return "—"
    with _wide():              # total: any finite float and any place (no InvalidOperation)
        q = Decimal(1).scaleb(-decimals)
        d = (exact if exact is not None else Decimal(repr(x))).quantize(q, rounding=rounding)
        if d == 0:
            d = abs(d)
        return f"{d:f}" if decimals >= 0 else f"{d.quantize(Decimal(1)):f}"


def decimals_for_sig(x: float, sig: int) -> int:
    """Decimal place that leaves ``sig`` significant digits of ``x`` after half-up rounding.

    >>> decimals_for_sig(0.35896, 2), decimals_for_sig(0.0996, 2), decimals_for_sig(76434.8, 8)
    (2, 2, 3)
    >>> decimals_for_sig(160.0, 2), decimals_for_sig(1234.0, 2)
    (-1, -2)
    """
    if x == 0 or not math.isfinite(x):
        return sig - 1
    with _wide():
        d = Decimal(repr(abs(float(x))))
        e = d.adjusted()                       # exponent of the leading digit
        dec = sig - 1 - e
        r = d.quantize(Decimal(1).scaleb(-dec), rounding=ROUND_HALF_UP)
        if r.adjusted() > e:                   # 0.0996 → 0.100: one digit more to the left
            dec -= 1
        return dec


def decimals_at_U(U: float) -> int:
    """The decimal place of U stated to two significant digits (GUM 7.2.6).

    >>> decimals_at_U(0.00316), decimals_at_U(160.0), decimals_at_U(0.0996)
    (4, -1, 2)
    """
    return decimals_for_sig(U, 2)


def rounded(x: float, sig: int = 2) -> float:
    """``x`` to ``sig`` significant digits, half up, as a float: the stated number of a
    budget that carries it on (an annex computing with the rounded u_c of an earlier step).
    Zero and non-finite numbers are returned unchanged.

    >>> rounded(0.1487), rounded(0.297), rounded(0.0996), rounded(0.0034449, 3)
    (0.15, 0.3, 0.1, 0.00344)
    """
    x = float(x)
    if x == 0 or not math.isfinite(x):
        return x
    return float(round_half_up(x, decimals_for_sig(x, sig)))


def k_text(k: float | None) -> str | None:
    """A coverage factor as stated: 3 significant digits. Trailing zeros are dropped only
    where the rounded text is k exactly (a chosen k = 2 is "2"); a computed factor that
    rounds to a whole number keeps its three digits (t_95(68) = 1.9955 is "2.00", never
    "2", which would present a t-factor as the chosen k = 2).

    >>> k_text(1.97414), k_text(2.0), k_text(2.0452), k_text(None)
    ('1.97', '2', '2.05', None)
    >>> k_text(1.9954689), k_text(1.999), k_text(2.0000024), k_text(1.96), k_text(2.5)
    ('2.00', '2.00', '2.00', '1.96', '2.5')
    """
    if k is None or not math.isfinite(float(k)):
        return None
    s = round_half_up(float(k), max(decimals_for_sig(float(k), 3), 0))
    if "." in s and Decimal(s) == Decimal(repr(float(k))):
        return s.rstrip("0").rstrip(".")
    return s


#: Above this many effective degrees of freedom ν_eff is stated "∞" and k is the normal
#: quantile: t_0.975(1000) = 1.9623 and z_0.975 = 1.9600 differ by 0.12 %, far below U's two
#: significant digits. (Welch–Satterthwaite gives ν_eff of 10⁷ where a Type B input
#: dominates; stating "13539172" would claim a precision ν_eff does not have.)
NU_INFINITE: float = 1000.0


def stated_nu(nu: float | None) -> float | None:
    """ν_eff as stated, and as k is computed from (GUM G.6.4: "truncate to the next lower
    integer"): the integer part, at least 1; ∞ above :data:`NU_INFINITE` or when infinite;
    None when unknown.

    >>> stated_nu(58.7), stated_nu(2.43), stated_nu(13539172.4), stated_nu(0.7), stated_nu(None)
    (58.0, 2.0, inf, 1.0, None)
    """
    if nu is None or (isinstance(nu, float) and math.isnan(nu)):
        return None
    nu = float(nu)
    if math.isnan(nu):
        return None
    if math.isinf(nu) or nu > NU_INFINITE:
        return math.inf
    return float(max(1, math.floor(nu)))


def coverage_k(nu: float | None, p: float = 0.95) -> float:
    """The coverage factor k = t_p(ν) of a two-sided interval, ν = :func:`stated_nu` of
    ``nu`` (the normal quantile when ν is ∞ or unknown), so the k a statement prints is the
    one of the ν it prints (JCGM 100 G.3, G.4, G.6.4).

    >>> round(coverage_k(2.43), 2), round(coverage_k(2.0), 2), round(coverage_k(5000.0), 2)
    (4.3, 4.3, 1.96)
    """
    from uncertainty import coverage_factor

    nu_s = stated_nu(nu)
    return coverage_factor(math.inf if nu_s is None else nu_s, p)


def stated_gum(r):
    """An ``uncertainty.GumResult`` computed with p whose k (and U = k·u_c) follow
    :func:`coverage_k` of its ν_eff; a result with a fixed k (``p`` None) is returned as is."""
    from dataclasses import replace

    if r.p is None:
        return r
    k = coverage_k(r.dof, r.p)
    return replace(r, k=k, U=k * r.u_c)


def chi2_nu(nu: float | None) -> float | None:
    """ν of a standard deviation's one-sided χ² interval as stated and as the interval is
    computed from (:func:`gonio.result.gum.dispersion_uncertainty`): the integer part, at
    least 1, with no ∞ above :data:`NU_INFINITE`. That cap belongs to k = t_p(ν) alone,
    where t_0.975(1000) ≈ z; the χ² upper limit s·√(ν/χ²_0.05,ν) still moves with ν there
    (ν = 15 590: 1.0095·s; ν = ∞ would be s itself), so a certificate that printed "∞" beside
    it would state a ν that does not reproduce its own limit. None when unknown or infinite.

    >>> chi2_nu(49444.98), chi2_nu(2.4), chi2_nu(0.3), chi2_nu(math.inf), chi2_nu(None)
    (49444.0, 2.0, 1.0, None, None)
    """
    if nu is None or not math.isfinite(float(nu)):
        return None
    return float(max(1, math.floor(float(nu))))


def nu_text(nu: float | None, chi2: bool = False) -> str | None:
    """Effective degrees of freedom as stated (:func:`stated_nu`): the integer part, ∞ if
    infinite or above :data:`NU_INFINITE`; ``chi2``: the ν of a χ² interval
    (:func:`chi2_nu`: the integer part, never ∞).

    >>> nu_text(58.7), nu_text(math.inf), nu_text(3.0), nu_text(13539172.0), nu_text(None)
    ('58', '∞', '3', '∞', None)
    >>> nu_text(49444.98, chi2=True)
    '49444'
    """
    if chi2:
        nu_c = chi2_nu(nu)
        return None if nu_c is None else str(int(nu_c))
    nu_s = stated_nu(nu)
    if nu_s is None:
        return None
    return "∞" if math.isinf(nu_s) else str(int(nu_s))


#: The most decimals of a per-cent coverage probability below 100 % (:func:`p_text`).
P_TEXT_MAX_DECIMALS: int = 3


#: The coverage probabilities a procedure chooses, for which every k and interval is computed:
#: 95 % (k = t_0.95(ν) of the ν_eff stated, the normal 1.96 above the threshold, a JCGM 101
#: convolution's k, a χ² or Monte Carlo interval, all for 95 % by construction) and the p of
#: a normal distribution's k = 2 and k = 3 (EA-4/02 Annex E's t-factor tables, t_0.9545(ν)):
#: stated "p = 95 %", "p = 95.45 %" in every output (en and zh). A probability computed from
#: a distribution (the coverage an interval of whole grid steps reaches, 98 %, 99 %) is
#: stated "p ≈ …" (JCGM 100 6.2.2: an interval of about that coverage).
CHOSEN_P_TEXTS = ("95", "95.45", "99.73")


def p_relation(p: str | None) -> str:
    """The relation sign a stated coverage probability (its :func:`p_text`) is printed with:
    "=" for a p chosen as such (:data:`CHOSEN_P_TEXTS`), else "≈".

    >>> p_relation("95.45"), p_relation("95"), p_relation("99.7"), p_relation("98")
    ('=', '=', '≈', '≈')
    """
    return "=" if p in CHOSEN_P_TEXTS else "≈"


def p_text(p: float | None) -> str | None:
    """A coverage probability (a fraction) in per cent, as every output states it.

    A probability chosen by the procedure (exactly one of :data:`CHOSEN_P_TEXTS` in per cent:
    0.95, 0.9545 — the t-factors of EA-4/02 Annex E — 0.9973; or a whole per cent, 0.99) is
    stated as chosen, "95", "95.45", so that the certificate, summary.txt, results.json (0.9545) and
    the DCC (``si:coverageProbability`` 0.9545) state one p. A probability computed from a
    distribution (the coverage an interval of whole grid steps reaches: 0.99465…) is stated
    to 2 significant digits, **rounded down** at the digits printed: a computed coverage is
    never overstated (0.98765 is "98", never "99"; 0.94567 "94", never "95"). A probability
    below 1 is never shown as 100 (an interval's stated probability is not certainty,
    JCGM 100 6.2.2): one within half a unit of the last digit below 100 takes the decimals
    that show it below 100 (at most :data:`P_TEXT_MAX_DECIMALS`), rounded down at those.
    The certificate, summary.txt and the DCC (``si:coverageProbability``, this text / 100)
    print this one text.

    >>> p_text(0.95), p_text(0.9545), p_text(0.99), p_text(0.9973), p_text(None)
    ('95', '95.45', '99', '99.73', None)
    >>> p_text(0.99465), p_text(0.981526), p_text(0.98765), p_text(0.94567)
    ('99', '98', '98', '94')
    >>> p_text(0.99671), p_text(0.99998), p_text(0.9999999)
    ('99.6', '99.998', '99.999')
    >>> p_text(1.0)
    '100'

    A computed p whose digits would read as a chosen one takes one more decimal, so that its
    relation (:func:`p_relation`) stays "≈": a computed 95.999 % is "95.9", never "95"
    (which would read "p = 95 %", a chosen probability).

    >>> p_text(0.95999), p_text(0.9545001), p_text(0.9587), p_relation(p_text(0.95999))
    ('95.9', '95.4', '95.8', '≈')

    A computed p within :data:`P_TEXT_MAX_DECIMALS` decimals above a chosen one keeps its
    zeros, so that it is not read as chosen either:

    >>> p_text(0.950001), p_relation(p_text(0.950001)), p_text(0.9500004)
    ('95.000', '≈', '95.000')

    The same for a whole per cent, which the chosen path prints bare (0.99 → "99"): a
    computed p a hair above one (a sum of probabilities in binary floating point) keeps its
    zeros, never the round text of a p it is not:

    >>> p_text(0.990000001), p_text(0.98000000001), p_text(0.99), p_text(0.990011)
    ('99.000', '98.000', '99', '99')
    """
    if p is None or not math.isfinite(float(p)):
        return None
    with _wide():
        chosen = Decimal(repr(float(p))).scaleb(2)
    if 0 < chosen < 100 and chosen.as_tuple().exponent >= -2:
        s = f"{chosen:f}"
        s = s.rstrip("0").rstrip(".") if "." in s else s
        if s in CHOSEN_P_TEXTS or "." not in s:
            return s                # chosen (95, 95.45, 99.73), or a whole per cent
    v = 100.0 * float(p)
    d = max(decimals_for_sig(v, 2), 0)
    while v < 100.0 and d < P_TEXT_MAX_DECIMALS and float(round_half_up(v, d)) >= 100.0:
        d += 1                      # the digits that show it below 100

    def at(d: int) -> str:
        s = round_half_up(v, d) if v >= 100.0 else round_half_up(v, d, rounding=ROUND_FLOOR)
        return s.rstrip("0").rstrip(".") if "." in s else s
    s = at(d)
    while s in CHOSEN_P_TEXTS and d < P_TEXT_MAX_DECIMALS:
        d += 1                      # a computed p is never printed as a chosen one
        s = at(d)
    if s in CHOSEN_P_TEXTS or (v < 100.0 and _rounds_to_whole(v)):
        # just above a chosen p, or just above a whole per cent (the chosen path's own texts,
        # 0.99 → "99"), at every decimal shown: the zeros say it was computed ("95.000",
        # "99.000"), never the round value it is not
        s = round_half_up(v, P_TEXT_MAX_DECIMALS, rounding=ROUND_FLOOR)
    return s


def _rounds_to_whole(v: float) -> bool:
    """Whether a computed per-cent coverage ``v`` (not exactly a whole per cent: those take
    :func:`p_text`'s chosen path) lies above a whole per cent by less than the last decimal
    :func:`p_text` can show (:data:`P_TEXT_MAX_DECIMALS`), so that its digits, floored there,
    are that whole per cent's ("99.000" for 99.0000001).

    >>> _rounds_to_whole(99.0000001), _rounds_to_whole(99.0011), _rounds_to_whole(98.9999)
    (True, False, False)
    """
    s = round_half_up(v, P_TEXT_MAX_DECIMALS, rounding=ROUND_FLOOR)
    return Decimal(s) == Decimal(s).to_integral_value()


#: results.json unit → its printed SI form (degree, hour, second of arc: accepted for use with
#: the SI, SI Brochure 9th ed. table 8), the one source of every printed page's unit text
#: (certificate, web page; the Chinese page's own forms: :data:`UNIT_TEXT_ZH`). Units not
#: listed print as written. results.json, items.csv and summary.txt keep the unit key
#: itself; the DCC its D-SI form (:data:`DSI_UNITS`).
UNIT_TEXT: dict[str, str] = {
    "arcsec": "″", "deg": "°", "deg/h": "°/h", "deg/s": "°/s", "degC": "°C",
    "counts/deg": "counts/°", "one": "", "1": "", "1/°C": "°C⁻¹", "%/°C": "%/°C",
}

#: The units a Chinese page prints in its own form (JJF 1059.1's "(°)/h": a unit symbol
#: after a number-like symbol is bracketed), else :data:`UNIT_TEXT`'s.
UNIT_TEXT_ZH: dict[str, str] = {"counts/deg": "脉冲数/(°)", "deg/h": "(°)/h", "deg/s": "(°)/s"}

#: results.json unit → (D-SI 2.2 unit, factor applied to value and U). D-SI has no unit for
#: the standard acceleration of gravity, so per-g units are written per m s⁻² (÷ g_n).
_PER_G = 1.0 / STANDARD_GRAVITY_M_S2
DSI_UNITS: dict[str, tuple[str, float]] = {
    "arcsec": (r"\arcsecond", 1.0), "″": (r"\arcsecond", 1.0),
    "deg": (r"\degree", 1.0), "°": (r"\degree", 1.0),
    "deg/h": (r"\degree\hour\tothe{-1}", 1.0), "°/h": (r"\degree\hour\tothe{-1}", 1.0),
    "deg/s": (r"\degree\second\tothe{-1}", 1.0), "°/s": (r"\degree\second\tothe{-1}", 1.0),
    "°/√h": (r"\degree\hour\tothe{-0.5}", 1.0),
    "counts/deg": (r"\one\degree\tothe{-1}", 1.0),
    "(°/h)/°C": (r"\degree\hour\tothe{-1}\kelvin\tothe{-1}", 1.0),
    "(°/s)/°C": (r"\degree\second\tothe{-1}\kelvin\tothe{-1}", 1.0),
    "1/°C": (r"\kelvin\tothe{-1}", 1.0), "%/°C": (r"\percent\kelvin\tothe{-1}", 1.0),
    "(°/h)/g": (r"\degree\hour\tothe{-1}\metre\tothe{-1}\second\tothe{2}", _PER_G),
    "(°/s)/g": (r"\degree\metre\tothe{-1}\second", _PER_G),
    "%": (r"\percent", 1.0), "ppm": (r"\ppm", 1.0),
    "degC": (r"\degreecelsius", 1.0), "°C": (r"\degreecelsius", 1.0),
    "Hz": (r"\hertz", 1.0), "s": (r"\second", 1.0), "h": (r"\hour", 1.0),
    "one": (r"\one", 1.0), "1": (r"\one", 1.0), "": (r"\one", 1.0),
    "rad": (r"\radian", 1.0), "mrad": (r"\milli\radian", 1.0),
}


def unit_text(unit: str | None) -> str:
    """A results.json unit as printed.

    >>> unit_text("deg/s"), unit_text("(°/h)/g"), unit_text("one"), unit_text(None)
    ('°/s', '(°/h)/g', '', '')
    """
    if not unit:
        return ""
    return UNIT_TEXT.get(unit, unit)


def unit_text_in(unit: str | None, lang: str) -> str:
    """A results.json unit as a page in ``lang`` ("en", "zh") prints it.

    >>> unit_text_in("counts/deg", "en"), unit_text_in("counts/deg", "zh"), unit_text_in("%", "zh")
    ('counts/°', '脉冲数/(°)', '%')
    """
    if lang == "zh" and unit in UNIT_TEXT_ZH:
        return UNIT_TEXT_ZH[unit]
    return unit_text(unit)


def signed_text(x: float, decimals: int = 2) -> str:
    """A difference as printed (a temperature's from its reference): signed, to ``decimals``
    places, half up; one that rounds to zero unsigned (never "+0", never "-0").

    >>> signed_text(0.6), signed_text(-0.2), signed_text(0.0), signed_text(-0.001)
    ('+0.60', '-0.20', '0.00', '0.00')
    """
    text = round_half_up(float(x), decimals)
    return text.lstrip("+-") if float(text) == 0.0 else ("" if text.startswith("-") else "+") + text


def given_text(v: float) -> str:
    """A specification limit as the laboratory gave it (no rounding: it is not measured).

    >>> given_text(0.3), given_text(-0.5), given_text(1e-05), given_text(-2.5e6)
    ('0.3', '-0.5', '1×10⁻⁵', '-2.5×10⁶')
    >>> given_text(76434.87), given_text(1.23456789e-05)
    ('76434.87', '1.23456789×10⁻⁵')
    """
    text = f"{float(v):g}"
    if float(text) != float(v):          # %g keeps 6 digits: never round what was given
        text = repr(float(v))
    if "e" not in text:
        return text
    mant, exp = text.split("e")           # the certificate's power-of-ten form, never "1e-05"
    return f"{mant}×10{str(int(exp)).translate(str.maketrans('-0123456789', '⁻⁰¹²³⁴⁵⁶⁷⁸⁹'))}"


def dsi_unit(unit: str | None) -> tuple[str, float] | None:
    """(D-SI unit, factor on value and U) of a results.json unit, or None if it has none.

    >>> dsi_unit("°/h"), dsi_unit("furlong")
    (('\\\\degree\\\\hour\\\\tothe{-1}', 1.0), None)
    """
    return DSI_UNITS.get(unit or "")


@dataclass(frozen=True)
class Statement:
    """One value as every output states it (all fields are texts, already rounded).

    ``value`` and ``U`` share a decimal place (or, with ``exponent``, a power of ten);
    ``k``, ``nu_eff``, ``p`` (per cent) are None where unknown; ``upper`` is the upper
    bound of a non-negative quantity whose U exceeds its value (else None; with it ``U`` and
    ``k`` are None and ``interval`` is ("0", upper): one statement); ``decimals``
    is the decimal place the value was rounded at (None without U: ``sig`` digits);
    ``below_zero``: a non-negative quantity whose estimate fell below zero, stated by its
    upper bound alone (:func:`below_zero_bound`; ``value`` keeps the rounded estimate).
    """

    value: str
    U: str | None = None
    k: str | None = None
    nu_eff: str | None = None
    p: str | None = None
    unit: str = ""
    upper: str | None = None
    exponent: int = 0
    decimals: int | None = None
    interval: tuple[str, str] | None = None
    below_zero: bool = False
    #: the Monte Carlo's numerical widening of the interval's ends (2·s, two significant
    #: digits rounded up, with the common power of ten), where the draws settle not even
    #: one digit of its reach (:func:`state_interval`); None: the computed ends, rounded
    #: outward
    widened: str | None = None

    def _x(self, s: str) -> str:
        return f"{s}×10{str(self.exponent).translate(_SUP)}" if self.exponent else s

    @property
    def value_text(self) -> str:
        """The value as printed (with the common power of ten)."""
        return self._x(self.value) if self.value != "—" else "—"

    @property
    def U_text(self) -> str | None:
        """U as printed (with the common power of ten), or None."""
        return self._x(self.U) if self.U is not None else None

    @property
    def interval_ends(self) -> tuple[str, str] | None:
        """The ends of the coverage interval as printed (with the common power of ten)."""
        return None if self.interval is None else (self._x(self.interval[0]),
                                                   self._x(self.interval[1]))

    @property
    def upper_text(self) -> str | None:
        """The upper bound of a non-negative quantity as printed, or None."""
        return self._x(self.upper) if self.upper is not None else None

    def factors(self) -> str:
        """"k = 1.97, ν_eff = 58, p = 95 %" (the parts known), or ""."""
        parts = []
        if self.k is not None:
            parts.append(f"k = {self.k}")
        if self.nu_eff is not None:
            parts.append(f"ν_eff = {self.nu_eff}")
        if self.p is not None:
            parts.append(f"p {p_relation(self.p)} {self.p} %")
        return ", ".join(parts)

    def bound_text(self, lang: str = "en") -> str:
        """The upper-bound wording of a non-negative quantity (see module docstring), with its
        probability, or "" (the same as :meth:`interval_text` of such a statement)."""
        return self.interval_text(lang) if self.upper is not None else ""

    def interval_text(self, lang: str = "en", short: bool = False) -> str:
        """The coverage interval of an item stated by its interval (see :func:`state`), with
        its probability: "upper bound: ≤ 0.53 °/h (interval [0, 0.53], p = 95 %)" or
        "interval [0.066, 0.204] ″ (p = 95 %)"; "" for an item stated by U. ``short``: the
        form of a table cell whose unit is in another column, "≤ 0.53 (p = 95 %)" or
        "[0.066, 0.204] (p = 95 %)"."""
        if self.interval is None:
            return ""
        u = f" {self.unit}" if self.unit else ""
        lo, hi = (self._x(x) for x in self.interval)
        p = f"p {p_relation(self.p)} {self.p} %" if self.p is not None else ""
        if short:
            iv = f"≤ {hi}" if self.upper is not None else f"[{lo}, {hi}]"
            return iv + ((f"（{p}）" if lang == "zh" else f" ({p})") if p else "")
        if self.upper is not None:                      # one-sided from the natural bound 0
            if lang == "zh":
                return f"上限：≤ {hi}{u}（区间 [0, {hi}]" + (f"，{p}）" if p else "）")
            return f"upper bound: ≤ {hi}{u} (interval [0, {hi}]" + (f", {p})" if p else ")")
        if lang == "zh":
            return f"区间 [{lo}, {hi}]{u}" + (f"（{p}）" if p else "")
        return f"interval [{lo}, {hi}]{u}" + (f" ({p})" if p else "")

    def widened_note(self, lang: str = "en") -> str:
        """The note beside an interval whose ends :func:`state_interval` moved out by the
        Monte Carlo's numerical uncertainty (:data:`WIDENED_NOTE`), or ""."""
        if self.widened is None:
            return ""
        return WIDENED_NOTE.get(lang, WIDENED_NOTE["en"]).format(w=self._x(self.widened))

    def below_zero_note(self, lang: str = "en") -> str:
        """The note beside the upper bound of a quantity whose estimate fell below zero
        (:func:`below_zero_bound`), or ""."""
        return BELOW_ZERO_NOTE.get(lang, BELOW_ZERO_NOTE["en"]) if self.below_zero else ""

    def text(self, lang: str = "en") -> str:
        """The whole statement in one line: "5.9991 ± 0.0032 mV/(°/s) (k = 1.97, …)", or for
        an item stated by its interval "0.112 ″; interval [0.066, 0.204] ″ (p = 95 %)"; a
        non-negative quantity whose estimate fell below zero: its upper bound and the note."""
        u = f" {self.unit}" if self.unit else ""
        sep = "；" if lang == "zh" else "; "
        wide = sep + self.widened_note(lang) if self.widened is not None else ""
        if self.below_zero:
            return self.interval_text(lang) + sep + self.below_zero_note(lang) + wide
        if self.interval is not None:
            return f"{self.value_text}{u}" + sep + self.interval_text(lang) + wide
        if self.U is None:
            return f"{self.value_text}{u}"
        s = f"{self.value_text} ± {self.U_text}{u}"
        if self.factors():
            s += f" ({self.factors()})"
        return s

    def to_json(self) -> dict:
        """The fields as a JSON object (all texts; for summary files and checks)."""
        return asdict(self)


#: The note beside an interval whose Monte Carlo draws left not even one digit of its reach
#: settled, so that :func:`state_interval` moved both ends out by twice their numerical
#: standard uncertainty (``w``, as stated).
WIDENED_NOTE = {"en": "ends widened by {w} (2·s, Monte Carlo not settled)",
                "zh": "端点已各向外放宽 {w}（2s，蒙特卡洛未稳定）"}


#: The note beside the upper bound of a non-negative quantity whose estimate fell below zero.
BELOW_ZERO_NOTE = {"en": "the estimate fell below zero",
                   "zh": "估计值低于零"}


def below_zero_bound(st: Statement, value: float, nonnegative: bool) -> Statement:
    """The statement of a non-negative quantity whose estimate ``value`` fell below zero
    while its coverage interval [0, upper] reaches above it: its upper bound alone, "≤ upper
    (p = 95 %)", marked ``below_zero`` (every output then prints the bound and
    :data:`BELOW_ZERO_NOTE`, never the negative value beside an interval that starts at 0:
    GUM 4.3.9 / JCGM 101 7.7, a coverage interval and an estimate hold only possible values,
    and the estimate, unbiased or not, is not one). Any other statement is returned as it is.
    The signed estimate stays in results.json (``value``) and in ``Statement.value``.

    >>> st = below_zero_bound(state(-3.0, 4.0, nonnegative=True, unit="s"), -3.0, True)
    >>> st.below_zero, st.upper, st.interval_text(short=True)
    (True, '1.0', '≤ 1.0')
    >>> below_zero_bound(state(0.01, 0.088, nonnegative=True), 0.01, True).below_zero
    False
    >>> below_zero_bound(state(-0.2, 0.1), -0.2, False).below_zero     # may be negative
    False
    """
    from dataclasses import replace

    if nonnegative and st.upper is not None and math.isfinite(float(value)) and float(value) < 0:
        return replace(st, below_zero=True)
    return st


def _scaled(d: Decimal, exponent: int, decimals: int) -> str:
    """The already rounded Decimal ``d`` as a mantissa × 10^exponent at ``decimals`` places."""
    with _wide():
        m = d.scaleb(-exponent)
        return round_half_up(m, decimals)


def state_interval(value: float, interval: tuple[float, float], *, nu_eff: float | None = None,
                   p: float | None = None, unit: str | None = "",
                   nonnegative: bool = False, chi2: bool = False,
                   numerical_u: float | None = None) -> Statement:
    """A value stated by its coverage interval [lo, hi] (a dispersion, range or extreme whose
    distribution is not symmetric about the estimate: χ² for a standard deviation, Monte
    Carlo for an extreme): no "± U" and no k, one interval with its probability.

    The ends are stated at the decimal place that gives the nearer end's distance from the
    value two significant digits (the far end's, for an interval from 0), the lower end
    rounded down and the upper end up (never narrower than computed), the value half up at
    the same place. For a non-negative quantity an interval starting at 0 is a one-sided
    upper bound (``upper``).

    ``numerical_u``: for ends taken from a Monte Carlo's draws, the standard uncertainty of
    the ends from the finite number of draws. The digits stated must be numerically
    significant (JCGM 101 7.9.2, 7.9.4: the results are stable to the numerical tolerance δ
    when 2·s ≤ δ, δ half a unit of the last stated digit): the decimal place is moved left
    until ½·10⁻ᵈᵉᶜ ≥ 2·``numerical_u`` (10⁻ᵈᵉᶜ ≥ 4·``numerical_u``), never right, and at most
    to the place that leaves one significant digit in that distance (JCGM 101 7.9.2's ndig
    of 1: the ends rounded outward at a coarser place would widen the interval by more
    than the draws' scatter). A digit a rerun of the Monte Carlo would change is not
    printed where one digit can be kept. Where the draws settle not even that one digit
    (4·``numerical_u`` above a unit of it: a capped adaptive Monte Carlo), the ends are first
    moved out by 2·``numerical_u`` (the reach of the draws' scatter at about 95 %; not
    below 0 for a non-negative quantity) and stated at one digit of the widened reach, so
    the statement holds the interval an unlimited number of draws would give; ``widened``
    says by how much, and every output prints that note (:data:`WIDENED_NOTE`).

    Refused (:class:`~gonio.errors.GonioError`): an interval not finite, reversed, not
    holding the value (except a non-negative quantity's estimate below an interval from 0:
    stated by its upper bound alone, :func:`below_zero_bound`), of zero width, or reaching
    below zero for a non-negative quantity:
    no coverage interval is like that. The one point interval stated is a dispersion of
    exactly zero ([0, 0] of 0, a non-negative quantity: readings that did not differ at all,
    as a noise-free bench gives): it is stated as the value alone, "0", with no interval.

    >>> state_interval(0.112, (0.0662, 0.2038), p=0.95, unit="arcsec").text()
    '0.112 ″; interval [0.066, 0.204] ″ (p = 95 %)'
    >>> s = state_interval(1.0, (0.0, 4.415), nu_eff=2, p=0.95, nonnegative=True, unit="°/h")
    >>> s.text(), s.U, s.k, s.upper
    ('1.0 °/h; upper bound: ≤ 4.5 °/h (interval [0, 4.5], p = 95 %)', None, None, '4.5')
    >>> state_interval(0.0, (0.0, 0.0), nonnegative=True, unit="s").text()
    '0 s'
    >>> state_interval(-0.5, (0.0, 2.04), nonnegative=True).text()   # a corrected range < 0
    'upper bound: ≤ 2.1 (interval [0, 2.1]); the estimate fell below zero'
    >>> state_interval(0.0995, (0.0677, 0.1302), p=0.95, unit="°/s").text()
    '0.100 °/s; interval [0.067, 0.131] °/s (p = 95 %)'
    >>> state_interval(0.0995, (0.0677, 0.1302), p=0.95, unit="°/s", numerical_u=0.002).text()
    '0.10 °/s; interval [0.06, 0.14] °/s (p = 95 %)'
    >>> state_interval(0.006, (0.0, 0.0191), p=0.95, nonnegative=True, numerical_u=0.002).text()
    '0.01; upper bound: ≤ 0.02 (interval [0, 0.02], p = 95 %)'
    >>> s = state_interval(0.0995, (0.0677, 0.1302), p=0.95, unit="°/s", numerical_u=0.006)
    >>> s.interval, s.widened          # 0.0677 − 0.012, 0.1302 + 0.012: one digit of 0.043
    (('0.05', '0.15'), '0.012')
    >>> s.text()
    '0.10 °/s; interval [0.05, 0.15] °/s (p = 95 %); ends widened by 0.012 (2·s, Monte Carlo not settled)'
    >>> state_interval(-5.0, (-6.0, -4.0), nonnegative=True)
    Traceback (most recent call last):
    gonio.errors.GonioError: interval [-6, -4] of -5: a non-negative quantity's interval reaches below zero; not stated
    """
    unit_s = unit_text(unit)
    value, lo, hi = float(value), float(interval[0]), float(interval[1])
    where = f"interval [{lo:g}, {hi:g}] of {value:g}"
    if nonnegative and value == lo == hi == 0.0:
        return state(0.0, None, nu_eff=nu_eff, unit=unit)     # no dispersion in the readings
    below = nonnegative and lo == 0.0 and value < 0.0   # stated by its upper bound alone
    if not all(math.isfinite(x) for x in (value, lo, hi)) or not (lo <= value or below) \
            or not value <= hi or lo == hi:
        raise GonioError(f"{where}: a coverage interval must be finite, of positive width "
                         "and hold the value; not stated")
    if nonnegative and lo < 0:
        raise GonioError(f"{where}: a non-negative quantity's interval reaches below zero; "
                         "not stated")
    lo, hi, widen = numerically_widened(value, (lo, hi), numerical_u=numerical_u,
                                        nonnegative=nonnegative)
    gap = interval_reach(value, (lo, hi), nonnegative=nonnegative)
    dec = decimals_for_sig(gap, 1 if widen else 2)
    if not widen and numerical_u is not None and math.isfinite(numerical_u) and numerical_u > 0:
        # JCGM 101 7.9.2: ndig 2 where the draws settle it, else 1 (never fewer)
        dec = min(dec, max(numerical_decimals(numerical_u), decimals_for_sig(gap, 1)))
    one_sided = nonnegative and lo == 0
    q = Decimal(1).scaleb(-dec)
    with _wide():
        vr = Decimal(repr(value)).quantize(q, rounding=ROUND_HALF_UP)
        lr = Decimal(repr(lo)).quantize(q, rounding=ROUND_FLOOR)
        hr = Decimal(repr(hi)).quantize(q, rounding=ROUND_CEILING)
        exponent = max(vr.adjusted() if vr != 0 else hr.adjusted(), hr.adjusted()) \
            if dec > 6 or abs(hr) >= Decimal("1e15") else 0
    md = dec + exponent
    ht = _scaled(hr, exponent, md)
    wt = None
    if widen:                           # two significant digits, rounded up
        dw = decimals_for_sig(widen, 2)
        with _wide():
            w = Decimal(repr(widen)).quantize(Decimal(1).scaleb(-dw), rounding=ROUND_CEILING)
        wt = _scaled(w, exponent, dw + exponent)
    return below_zero_bound(
        Statement(_scaled(vr, exponent, md), None, None, nu_text(nu_eff, chi2), p_text(p), unit_s,
                  upper=ht if one_sided else None, exponent=exponent, decimals=dec,
                  interval=(_scaled(lr, exponent, md), ht), widened=wt), value, nonnegative)


def numerically_widened(value: float, interval: tuple[float, float], *,
                        numerical_u: float | None = None,
                        nonnegative: bool = False) -> tuple[float, float, float]:
    """(lo, hi, w): a Monte Carlo interval's ends as :func:`state_interval` states them
    before rounding. Where the draws' numerical standard uncertainty ``numerical_u`` settles
    not even one significant digit of the reach (:func:`interval_reach`; 4·s above a unit
    of that digit, JCGM 101 7.9.4), both ends are moved out by w = 2·s (the lower not below 0
    for a non-negative quantity); otherwise they are returned as given, w = 0.

    >>> numerically_widened(0.1, (0.07, 0.13), numerical_u=0.002)         # settled at 0.01
    (0.07, 0.13, 0.0)
    >>> tuple(round(x, 6) for x in numerically_widened(0.1, (0.07, 0.13), numerical_u=0.006))
    (0.058, 0.142, 0.012)
    """
    lo, hi = float(interval[0]), float(interval[1])
    if numerical_u is None or not math.isfinite(numerical_u) or not numerical_u > 0:
        return lo, hi, 0.0
    gap = interval_reach(value, (lo, hi), nonnegative=nonnegative)
    if numerical_decimals(numerical_u) >= decimals_for_sig(gap, 1):
        return lo, hi, 0.0
    w = 2.0 * float(numerical_u)
    return (max(lo - w, 0.0) if nonnegative else lo - w), hi + w, w


def interval_reach(value: float, interval: tuple[float, float], *,
                   nonnegative: bool = False) -> float:
    """The distance whose significant digits fix the decimal place of
    :func:`state_interval`: the nearer end's distance from the value, the upper end's for a
    non-negative quantity's interval from 0 (a one-sided bound), the width where the value
    sits on both ends.

    >>> interval_reach(0.1, (0.07, 0.13)), interval_reach(0.01, (0.0, 0.02), nonnegative=True)
    (0.03, 0.01)
    """
    value, lo, hi = float(value), float(interval[0]), float(interval[1])
    one_sided = nonnegative and lo == 0
    gaps = [g for g in ((hi - value,) if one_sided else (value - lo, hi - value)) if g > 0]
    return min(gaps) if gaps else hi - lo


def settled_numerical_u(value: float, interval: tuple[float, float], *,
                        nonnegative: bool = False, ndig: int = 1) -> float:
    """The largest numerical standard uncertainty of a Monte Carlo interval's ends at which
    :func:`state_interval` states ``ndig`` significant digits of its reach
    (:func:`interval_reach`) as computed (JCGM 101 7.9.4: 2·s ≤ δ, δ half a unit of that
    digit, i.e. s ≤ 10⁻ᵈᵉᶜ/4): the target of an adaptive Monte Carlo.

    >>> settled_numerical_u(0.1, (0.07, 0.13)), settled_numerical_u(0.1, (0.07, 0.13), ndig=2)
    (0.0025, 0.00025)
    """
    gap = interval_reach(value, interval, nonnegative=nonnegative)
    return 10.0 ** -decimals_for_sig(gap, ndig) / 4.0


def numerical_decimals(numerical_u: float) -> int:
    """The rightmost decimal place a Monte Carlo result may be stated at when its standard
    uncertainty from the finite number of draws is ``numerical_u`` (JCGM 101 7.9.2, 7.9.4:
    2·s ≤ δ, the numerical tolerance δ half a unit of the last digit): the largest ``dec``
    with 10⁻ᵈᵉᶜ ≥ 4·``numerical_u``.

    >>> numerical_decimals(0.002), numerical_decimals(0.0025), numerical_decimals(0.00024)
    (2, 2, 3)
    >>> numerical_decimals(3.0), numerical_decimals(2.5e-300)
    (-2, 299)

    Exact without a logarithm: ⌈log₁₀ x⌉ of x = 4·``numerical_u`` (its shortest repr, ≤ 17
    digits) is the exponent of its leading digit, plus one unless x is a power of ten (a
    1400-digit ``Decimal.log10`` gave the same integer at about 60 ms a call).
    """
    x = Decimal(repr(4.0 * float(numerical_u)))
    if not (x.is_finite() and x > 0):
        raise ValueError(f"numerical_decimals needs a positive finite u, got {numerical_u!r}")
    lead = x.adjusted()
    return -(lead if x.scaleb(-lead) == 1 else lead + 1)


def state(value: float | None, U: float | None = None, *, k: float | None = None,
          nu_eff: float | None = None, p: float | None = None, unit: str | None = "",
          sig: int = 3, nonnegative: bool = False) -> Statement:
    """A value with its expanded uncertainty as stated by the rule of this module.

    ``value`` None or not finite gives "—". ``U`` None, zero or not finite: the value to
    ``sig`` significant digits. ``nonnegative`` declares a quantity that cannot be negative
    (see the module docstring for the bound it may get).

    The form (plain or with a power of ten) and the power of ten are chosen from the
    numbers *as rounded*, so a rounding that carries into the next power is stated in it:
    9.996×10⁻⁵ to three digits is "1.00×10⁻⁴", never "10.0×10⁻⁵".

    >>> state(5.99906, 0.00316).value, state(-0.00004, 0.0031).value, state(None).value
    ('5.9991', '0.0000', '—')
    >>> state(0.01, 0.088, nonnegative=False).upper is None
    True
    >>> state(175.0, 1200.0, k=2, p=0.95, nonnegative=True, unit="s").text()
    '200 s; upper bound: ≤ 1400 s (interval [0, 1400], p = 95 %)'
    >>> state(-3.0, 4.0, nonnegative=True, unit="s").text()
    'upper bound: ≤ 1.0 s (interval [0, 1.0]); the estimate fell below zero'
    >>> state(-5.0, 1.0, nonnegative=True, unit="s")
    Traceback (most recent call last):
    gonio.errors.GonioError: -5 ± 1 s: a non-negative quantity whose interval lies wholly at or below zero has no coverage interval of possible values; not stated
    >>> state(9.996e-5).value_text, state(9.99996e-5, 1.0e-8).text()
    ('1.00×10⁻⁴', '1.00000×10⁻⁴ ± 0.00010×10⁻⁴')
    """
    unit_s = unit_text(unit)
    kt, nt, pt = k_text(k), nu_text(nu_eff), p_text(p)
    if value is None or not math.isfinite(float(value)):
        return Statement("—", None, kt, nt, pt, unit_s)
    value = float(value)
    if U is None or not math.isfinite(float(U)) or float(U) <= 0:
        if value == 0:
            return Statement("0", None, kt, nt, pt, unit_s)
        with _wide():
            d = Decimal(repr(value))
            r = d.quantize(Decimal(1).scaleb(-decimals_for_sig(value, sig)),
                           rounding=ROUND_HALF_UP)
            e = r.adjusted()                   # the rounded number's leading digit
        if abs(r) < Decimal("1e-3") or abs(r) >= Decimal("1e15"):
            return Statement(_scaled(r, e, sig - 1), None, kt, nt, pt, unit_s, exponent=e)
        # digits left of the point are never rounded away without U (1296000.003 → 1296000)
        return Statement(round_half_up(value, max(decimals_for_sig(value, sig), 0)), None,
                         kt, nt, pt, unit_s)
    U = float(U)
    if nonnegative and value + U <= 0:
        raise GonioError(f"{value:g} ± {U:g}{' ' + unit_s if unit_s else ''}: a non-negative "
                         "quantity whose interval lies wholly at or below zero has no "
                         "coverage interval of possible values; not stated")
    dec = decimals_at_U(U)
    q = Decimal(1).scaleb(-dec)
    with _wide():
        vr = Decimal(repr(value)).quantize(q, rounding=ROUND_HALF_UP)
        Ur = Decimal(repr(U)).quantize(q, rounding=ROUND_HALF_UP)
        ur = (_exact_sum(value, U).quantize(q, rounding=ROUND_CEILING)
              if nonnegative and U > value else None)
        exponent = 0
        if dec > 6 or abs(vr) >= Decimal("1e15"):
            # a power of ten common to value and U: that of the larger rounded one's leading digit
            exponent = max(vr.adjusted() if vr != 0 else Ur.adjusted(), Ur.adjusted())
    md = dec + exponent                        # the mantissas' decimal place (U keeps 2 digits)
    vt, Ut = _scaled(vr, exponent, md), _scaled(Ur, exponent, md)
    if ur is not None:          # one statement: the interval [0, upper], no ± U and no k
        upper = _scaled(ur, exponent, md)
        return below_zero_bound(
            Statement(vt, None, None, nt, pt, unit_s, upper=upper, exponent=exponent,
                      decimals=dec, interval=(_scaled(Decimal(0), exponent, md), upper)),
            value, nonnegative)
    return Statement(vt, Ut, kt, nt, pt, unit_s, exponent=exponent, decimals=dec)


def _get(obj, key: str, default=None):
    """``obj[key]`` of a results.json dict or ``obj.key`` of a model object."""
    if obj is None:
        return default
    if isinstance(obj, dict):
        return obj.get(key, default)
    return getattr(obj, key, default)


#: ``k_source`` prefix of a bound-condition statement (an item whose equipment errors are
#: taken at their bounds, plus k·u of the rest), ``gonio.report.stated.interval_kind`` "bound".
K_SOURCE_BOUND_PREFIX = "U = a + k·u"


def u_c_certified(it) -> bool:
    """Whether the certificate states the combined standard uncertainty u_c of ``it`` (a
    results.json item or a :class:`gonio.result.model.Item`, or a budget dict with its own
    ``u_c_certified`` flag), the one rule every writer of a certificate, summary, DCC or
    ``tables/items.csv`` follows: not for a quantity stated by a
    bound-condition interval — ``details.bound_condition``, or ``uncertainty.k_source``
    "U = a + k·u" (value ± (a + k·u): the equipment's errors at their bounds, a, plus k·u of
    the other lines) or :data:`K_SOURCE_BOUND_CHI2` (a dispersion's one-sided bound
    condition), or a budget marked ``u_c_certified`` False (U = k·u + b per point), nor for
    the interval of an extreme of magnitudes (:data:`K_SOURCE_MAX_ABS`, the optical E: its
    u_c is that of the extreme's point, no u of max|x_i|).
    Its u_c (the JCGM 100 budget, the bounded lines as rectangular distributions) does not
    hold those errors at their bounds: it is kept in results.json and shown in the budget
    table marked "beside, not stated"; the DCC writes the interval's ends without an
    si:valueStandardMU (:func:`gonio.report.dcc.interval_quantity`).

    >>> u_c_certified({"details": {"bound_condition": {"U": 1.0}}}), u_c_certified({})
    (False, True)
    >>> u_c_certified({"uncertainty": {"k_source": "U = a + k·u (bound condition)"}})
    False
    >>> u_c_certified({"uncertainty": {"k_source": K_SOURCE_BOUND_CHI2}})
    False
    >>> u_c_certified({"u_c_certified": False}), u_c_certified({"u_c_certified": True})
    (False, True)
    >>> u_c_certified({"uncertainty": {"k_source": K_SOURCE_MAX_ABS}})
    False
    """
    if _get(it, "u_c_certified", True) is False:
        return False
    if (_get(it, "details") or {}).get("bound_condition"):
        return False
    ks = str(_get(_get(it, "uncertainty"), "k_source") or "")
    return not (ks.startswith(K_SOURCE_BOUND_PREFIX) or ks in (K_SOURCE_BOUND_CHI2,
                                                                K_SOURCE_MAX_ABS))


#: ``k_source`` of an item whose value is signed but whose statement is the coverage interval
#: of the extreme of magnitudes max_i |x_i| (the optical draft's E = ± max|E_i|, 7.4): its
#: ``U`` is the distance from that extreme to the interval's upper end, so the extreme is
#: ``interval[1] - U``; the statement and the conformity decision take that extreme.
K_SOURCE_MAX_ABS = "max-abs-interval"
#: ``k_source`` of a standard deviation stated by its one-sided χ² interval
#: (:func:`gonio.result.gum.std_dev_uncertainty`): its ν is stated by :func:`chi2_nu`.
K_SOURCE_CHI2 = "chi-square"
#: ``k_source`` of a dispersion (a noise rms) stated by its one-sided bound-condition limit
#: (:func:`gonio.result.gum.dispersion_bound_statement`): [0, s + a + R], a its bounded lines
#: at their bounds, R the one-sided χ² reach of its other lines, whose ν it states
#: (:func:`chi2_nu`); written as the interval's formula, g the bounded relative error. A bound
#: condition: its u_c is beside, not stated (:func:`u_c_certified`);
#: ``gonio.report.stated.interval_kind`` "bound_chi2".
K_SOURCE_BOUND_CHI2 = "U = a + R: [0, (s + R)/(1 − g)]"


def chi2_stated_nu(k_source) -> bool:
    """Whether an item stated by its interval states the ν of a one-sided χ² limit (its
    integer part, never ∞: :func:`chi2_nu`): a standard deviation's χ² interval
    (:data:`K_SOURCE_CHI2`) and a dispersion's bound-condition limit, whose reach above a is
    that χ² limit's (:data:`K_SOURCE_BOUND_CHI2`).

    >>> chi2_stated_nu("chi-square"), chi2_stated_nu(K_SOURCE_BOUND_CHI2), chi2_stated_nu("")
    (True, True, False)
    """
    return k_source in (K_SOURCE_CHI2, K_SOURCE_BOUND_CHI2)


def bound_up_text(x: float, sig: int = 2) -> str:
    """An upper bound at ``sig`` significant digits, rounded up (never below the bound it
    states): a false-accept bound 1 − 0.980576 = 1.94 % reads "2.0", not "1.9" (the
    certificate's "≤ 2.0 %", summary.txt's and the DCC's).

    >>> bound_up_text(1.9424), bound_up_text(5.0), bound_up_text(0.6100001)
    ('2.0', '5.0', '0.62')
    """
    d = decimals_for_sig(x, sig)
    q = Decimal(1).scaleb(-d)
    return str(Decimal(repr(round(x, 12))).quantize(q, rounding=ROUND_CEILING))


def interval_nu_symbol(k_source) -> str:
    """The symbol of the ν an item stated by its interval prints beside that interval: "ν"
    for a χ² interval (:func:`chi2_stated_nu`: the ν the interval was computed with),
    "ν_eff" for another (the ν_eff its coverage factor was computed with: a bound-condition
    interval value ± (a + k·u), a non-negative item's upper bound value + U), as the
    certificate's ν_eff column prints the number.

    >>> interval_nu_symbol(K_SOURCE_CHI2), interval_nu_symbol("U = a + k·u")
    ('ν', 'ν_eff')
    """
    return "ν" if chi2_stated_nu(k_source) else "ν_eff"


def interval_nu_clause(st: "Statement", k_source) -> str:
    """"ν = 94" or "ν_eff = 7": the ν an item stated by its interval (``st.interval``)
    prints beside it (:func:`interval_nu_symbol`, the statement's own ν text, the
    certificate's ν_eff column), "" where it is stated otherwise or states no ν.

    >>> interval_nu_clause(state_interval(0.2288, (0.0, 0.2721), nu_eff=94.7, p=0.95,
    ...                    nonnegative=True, chi2=True), K_SOURCE_CHI2)
    'ν = 94'
    >>> interval_nu_clause(state_interval(0.88, (0.8736, 0.8872), nu_eff=6.0, p=0.9545),
    ...                    "U = a + k·u")
    'ν_eff = 6'
    >>> interval_nu_clause(state(5.99906, 0.00316, k=1.97414, nu_eff=58.7, p=0.95), None)
    ''
    """
    if st.interval is None or st.nu_eff is None:
        return ""
    return f"{interval_nu_symbol(k_source)} = {st.nu_eff}"

#: ``k_source`` of the largest of several standard deviations stated with the selection bias
#: of its maximum removed (IEC 62047-20 5.1.3.7's max σ_i): its 95 % interval inverts each
#: record's own χ² test (the upper end the largest of the records' own upper bounds, the lower
#: the largest of their Šidák-level lower bounds; ``max_spread_bounds`` of the IEC package).
K_SOURCE_SELECTED_MAX = "interval of the largest true spread inverting each record's own χ² test"
#: The same ``k_source`` as results.json files written before 1 Dec 2026 name it (their
#: interval was the χ² interval of the largest spread united over its selection excess).
K_SOURCE_SELECTED_MAX_BEFORE = "χ² interval of the largest spread over its selection excess"

#: ``k_source`` of a magnitude max_i |x_i| stated by the interval of the extreme of
#: magnitudes (:func:`gonio.result.gum.max_magnitude_statement`: JJF 1535 and IEC 62047-20
#: items); its ``value`` is the magnitude itself.
K_SOURCE_MAX_MAGNITUDE = "interval of max|x_i| (uncertainty.extreme.max_abs_interval)"

#: Every ``k_source`` of an item stated as an extreme of magnitudes max_i |x_i|: such an item
#: is compared with a symmetric limit only, and accepted on its interval's upper end
#: (:func:`is_magnitude_statement`).
MAGNITUDE_K_SOURCES: tuple[str, ...] = (K_SOURCE_MAX_ABS, K_SOURCE_MAX_MAGNITUDE)


def is_magnitude_statement(unc) -> bool:
    """Whether an uncertainty (results.json dict or model object) states an extreme of
    magnitudes max_i |x_i| (its ``k_source`` one of :data:`MAGNITUDE_K_SOURCES`): the kind of
    statement, whichever specification or item computed it.

    >>> is_magnitude_statement({"k_source": K_SOURCE_MAX_MAGNITUDE}), is_magnitude_statement(None)
    (True, False)
    """
    return _get(unc, "k_source") in MAGNITUDE_K_SOURCES


def item_statement(item, sig: int = 3, nonnegative: bool | None = None) -> Statement:
    """The statement of one item, from a results.json item (dict) or a model ``Item``: its
    ``value``, ``unit`` and ``uncertainty`` (``U``, ``k``, ``nu_eff``, ``coverage_probability``
    or ``p``). Every output states an item through this one call, so the certificate,
    ``summary.txt``, the CLI and the DCC cannot differ. ``nonnegative`` (default: the item's
    own ``nonnegative`` key, else False) asks for the upper bound of the module docstring.

    >>> item_statement({"value": 786.485, "unit": "°/h", "measured": True,
    ...                 "uncertainty": {"U": 159.4, "k": 2.38068, "nu_eff": 6.2, "p": 0.95}}).text()
    '790 ± 160 °/h (k = 2.38, ν_eff = 6, p = 95 %)'
    >>> item_statement({"value": None, "unit": "s", "measured": False}).value
    '—'
    """
    unc = _get(item, "uncertainty")
    U = _get(unc, "U")
    ok = U is not None and math.isfinite(float(U)) and float(U) > 0
    p = _get(unc, "coverage_probability")
    if p is None:
        p = _get(unc, "p")
    if nonnegative is None:
        nonnegative = bool(_get(item, "nonnegative", False))
    measured = _get(item, "measured", True)
    iv = _get(unc, "interval")
    if measured and iv is not None and _get(unc, "k") is None and _get(item, "value") is not None:
        # stated by its interval (no coverage factor exists for it): one statement
        if _get(unc, "k_source") == K_SOURCE_MAX_ABS:
            # the interval of an extreme of magnitudes, max_i |x_i|, beside a signed value:
            # the value stated is that extreme (the interval's upper end less U), >= 0
            return state_interval(float(iv[1]) - float(U), (iv[0], iv[1]),
                                  nu_eff=_get(unc, "nu_eff"), p=p, unit=_get(item, "unit", ""),
                                  nonnegative=True)
        return state_interval(_get(item, "value"), (iv[0], iv[1]), nu_eff=_get(unc, "nu_eff"),
                              p=p, unit=_get(item, "unit", ""), nonnegative=nonnegative,
                              chi2=chi2_stated_nu(_get(unc, "k_source")),
                              numerical_u=_get(unc, "interval_numerical_u"))
    return state(_get(item, "value") if measured else None, U if ok else None,
                 k=_get(unc, "k") if ok else None, nu_eff=_get(unc, "nu_eff") if ok else None,
                 p=p if ok else None, unit=_get(item, "unit", ""), sig=sig,
                 nonnegative=nonnegative)
