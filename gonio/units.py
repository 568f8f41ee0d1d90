"""Units: every constant and conversion gonio uses, in one place.

Names carry their unit (``_deg``, ``_arcsec``, ``_rad``, ``_s``, ``_h``, ``_dps``
for °/s, ``_dph`` for °/h); values are converted here and nowhere else. A test
(``tests/test_layers.py``) checks that no other module writes the bare literals
3600 or 206264.8.

Angle random walk (ARW) and rate random walk (RRW) units follow IEEE Std 952-1997
Annex C: N in °/√h equals 60·N in (°/h)/√Hz, since √h = 60 √s.

>>> ARCSEC_PER_DEG, S_PER_H, round(ARCSEC_PER_RAD, 3)
(3600.0, 3600.0, 206264.806)
>>> deg_to_arcsec(0.5), arcsec_to_deg(1800.0)
(1800.0, 0.5)
>>> dph_to_dps(36.0), dps_to_dph(0.01)
(0.01, 36.0)
"""

from __future__ import annotations

import math
import re
from fractions import Fraction

__all__ = [
    "ARCSEC_PER_DEG", "ARCMIN_PER_DEG", "ARCSEC_PER_RAD", "DEG_PER_RAD", "S_PER_MIN",
    "MIN_PER_H", "S_PER_H", "S_PER_DAY", "PPM", "PERCENT", "STANDARD_GRAVITY_M_S2",
    "deg_to_arcsec", "arcsec_to_deg", "rad_to_arcsec", "arcsec_to_rad",
    "dph_to_dps", "dps_to_dph", "dps_to_arcsec_s", "arcsec_s_to_dph", "dph_to_arcsec_s",
    "rad_s_from_dph", "dph_from_rad_s", "s_to_h", "h_to_s", "min_to_s",
    "dph_sqrt_hz_from_deg_sqrt_h", "deg_sqrt_h_from_dph_sqrt_hz",
    "arcsec_sqrt_s_from_deg_sqrt_h", "deg_sqrt_h_from_arcsec_sqrt_s",
    "rad_s_sqrt_hz_from_deg_sqrt_h", "deg_sqrt_h_from_rad_s_sqrt_hz",
    "deg_sqrt_s_from_deg_sqrt_h", "dph_per_sqrt_h_from_dph_sqrt_hz_per_s",
    "unit_key", "unit_powers", "same_unit", "unit_factor",
]

#: Arcseconds per degree (″/°).
ARCSEC_PER_DEG: float = 3600.0
#: Arcminutes per degree.
ARCMIN_PER_DEG: float = 60.0
#: Degrees per radian.
DEG_PER_RAD: float = 180.0 / math.pi
#: Arcseconds per radian, 206264.806…″.
ARCSEC_PER_RAD: float = DEG_PER_RAD * ARCSEC_PER_DEG
#: Seconds per minute.
S_PER_MIN: float = 60.0
#: Minutes per hour.
MIN_PER_H: float = 60.0
#: Seconds per hour.
S_PER_H: float = S_PER_MIN * MIN_PER_H
#: Seconds per (solar) day.
S_PER_DAY: float = 24.0 * S_PER_H
#: One part per million, as a ratio.
PPM: float = 1e-6
#: One per cent, as a ratio.
PERCENT: float = 1e-2
#: Standard acceleration of gravity g_n (CGPM 1901), m/s².
STANDARD_GRAVITY_M_S2: float = 9.80665


def deg_to_arcsec(x_deg):
    """Degrees → arcseconds (works on floats and numpy arrays)."""
    return x_deg * ARCSEC_PER_DEG


def arcsec_to_deg(x_arcsec):
    """Arcseconds → degrees."""
    return x_arcsec / ARCSEC_PER_DEG


def rad_to_arcsec(x_rad):
    """Radians → arcseconds.

    >>> round(rad_to_arcsec(1e-6), 6)
    0.206265
    """
    return x_rad * ARCSEC_PER_RAD


def arcsec_to_rad(x_arcsec):
    """Arcseconds → radians."""
    return x_arcsec / ARCSEC_PER_RAD


def dph_to_dps(rate_dph):
    """°/h → °/s."""
    return rate_dph / S_PER_H


def dps_to_dph(rate_dps):
    """°/s → °/h."""
    return rate_dps * S_PER_H


def dps_to_arcsec_s(rate_dps):
    """°/s → ″/s."""
    return rate_dps * ARCSEC_PER_DEG


def dph_to_arcsec_s(rate_dph):
    """°/h → ″/s (numerically the same: 3600″/3600 s).

    >>> dph_to_arcsec_s(15.0)
    15.0
    """
    return rate_dph * ARCSEC_PER_DEG / S_PER_H


def arcsec_s_to_dph(rate_arcsec_s):
    """″/s → °/h."""
    return rate_arcsec_s * S_PER_H / ARCSEC_PER_DEG


def rad_s_from_dph(rate_dph):
    """Rate °/h → rad/s (π/180/3600).

    >>> f"{rad_s_from_dph(15.041):.4e}"
    '7.2921e-05'
    """
    return rate_dph / DEG_PER_RAD / S_PER_H


def dph_from_rad_s(rate_rad_s):
    """Rate rad/s → °/h (180·3600/π).

    >>> round(dph_from_rad_s(7.292115e-5), 4)
    15.0411
    """
    return rate_rad_s * DEG_PER_RAD * S_PER_H


def s_to_h(t_s):
    """Seconds → hours."""
    return t_s / S_PER_H


def h_to_s(t_h):
    """Hours → seconds."""
    return t_h * S_PER_H


def min_to_s(t_min):
    """Minutes → seconds."""
    return t_min * S_PER_MIN


# ----------------------------------------------------------------- noise coefficients
def dph_sqrt_hz_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → (°/h)/√Hz: ×60 (IEEE 952 C.1).

    >>> dph_sqrt_hz_from_deg_sqrt_h(0.01)
    0.6
    """
    return arw_deg_sqrt_h * MIN_PER_H


def deg_sqrt_h_from_dph_sqrt_hz(arw_dph_sqrt_hz):
    """Angle random walk (°/h)/√Hz → °/√h: ÷60.

    >>> deg_sqrt_h_from_dph_sqrt_hz(0.6)
    0.01
    """
    return arw_dph_sqrt_hz / MIN_PER_H


def arcsec_sqrt_s_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → ″/√s: 3600″ / 60 √s = 60 ″/√s per °/√h.

    >>> round(arcsec_sqrt_s_from_deg_sqrt_h(0.001), 12)
    0.06
    """
    return arw_deg_sqrt_h * ARCSEC_PER_DEG / math.sqrt(S_PER_H)


def deg_sqrt_h_from_arcsec_sqrt_s(arw_arcsec_sqrt_s):
    """Angle random walk ″/√s → °/√h.

    >>> round(deg_sqrt_h_from_arcsec_sqrt_s(0.06), 12)
    0.001
    """
    return arw_arcsec_sqrt_s * math.sqrt(S_PER_H) / ARCSEC_PER_DEG


def rad_s_sqrt_hz_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → (rad/s)/√Hz = rad/√s.

    >>> f"{rad_s_sqrt_hz_from_deg_sqrt_h(1.0):.4e}"
    '2.9089e-04'
    """
    return arw_deg_sqrt_h / DEG_PER_RAD / math.sqrt(S_PER_H)


def deg_sqrt_h_from_rad_s_sqrt_hz(arw_rad_s_sqrt_hz):
    """Angle random walk (rad/s)/√Hz → °/√h.

    >>> round(deg_sqrt_h_from_rad_s_sqrt_hz(2.908882e-4), 6)
    1.0
    """
    return arw_rad_s_sqrt_hz * math.sqrt(S_PER_H) * DEG_PER_RAD


def deg_sqrt_s_from_deg_sqrt_h(arw_deg_sqrt_h):
    """Angle random walk °/√h → °/√s (the white rate density in (°/s)/√Hz): ÷60."""
    return arw_deg_sqrt_h / math.sqrt(S_PER_H)


def dph_per_sqrt_h_from_dph_sqrt_hz_per_s(k_dph_per_sqrt_s):
    """Rate random walk (°/h)/√s → (°/h)/√h: ×60."""
    return k_dph_per_sqrt_s * math.sqrt(S_PER_H)


# ------------------------------------------------------------------ unit texts compared
#: Spellings of one unit symbol (a file's or a person's) → the symbol results.json and the
#: certificates write (:data:`gonio.result.statement.UNIT_TEXT`'s printed forms), applied in
#: this order by :func:`unit_key`: the masculine ordinal "º" and the ring "˚" typed for the
#: degree sign, "deg" for "°", "arcsec" / "arcmin" for "″" / "′", the micro sign for "μ".
UNIT_SPELLINGS: tuple[tuple[str, str], ...] = (
    (" ", ""), ("\u00ba", "°"), ("\u02da", "°"), ("degC", "°C"), ("degrees", "°"),
    ("degree", "°"), ("deg", "°"),
    ("arcsec", "″"), ("arcmin", "′"), ("\u00b5", "μ"), ("sqrt", "√"), ("*", "·"),
    ("⋅", "·"), ("one", "1"))

#: The unit symbols :func:`unit_factor` converts exactly, each as (its base symbol or "" for
#: a ratio, the exponent of that base, the exact factor): 1 ″ = 1/3600 °, 1 h = 3600 s,
#: 1 Hz = 1 s⁻¹, 1 % = 1/100, 1 ppm = 10⁻⁶ (from the constants above).
_EXACT: dict[str, tuple[str, int, Fraction]] = {
    "°": ("°", 1, Fraction(1)), "″": ("°", 1, 1 / Fraction(ARCSEC_PER_DEG)),
    "′": ("°", 1, 1 / Fraction(ARCMIN_PER_DEG)), "s": ("s", 1, Fraction(1)),
    "min": ("s", 1, Fraction(S_PER_MIN)), "h": ("s", 1, Fraction(S_PER_H)),
    "Hz": ("s", -1, Fraction(1)), "%": ("", 0, Fraction(str(PERCENT))),
    "ppm": ("", 0, Fraction(str(PPM)))}

_UNIT_TOKEN = re.compile(r"[()/·√^]|-?[0-9]+(?=[)/·]|$)|[^()/·√^]+")


def unit_key(text: str | None) -> str:
    """A unit's text in one spelling (:data:`UNIT_SPELLINGS`; no spaces): "deg/h", "º/h" and
    "° / h" are all "°/h"; None and "" (a pure number) are "1".

    >>> unit_key("deg/h"), unit_key("º/h"), unit_key(" (deg/s)/degC "), unit_key(None)
    ('°/h', '°/h', '(°/s)/°C', '1')
    """
    t = str(text or "")
    for old, new in UNIT_SPELLINGS:
        t = t.replace(old, new)
    return t or "1"


def unit_powers(text: str | None) -> dict[str, Fraction] | None:
    """A unit as {symbol: exponent} (:func:`unit_key`'s spelling): products "·", quotients
    "/" (left to right), brackets, a square root "√", a power "^n"; the number 1 is no
    symbol. None where the text is not such a unit (an unbalanced bracket, an empty part).

    >>> unit_powers("mV/(deg/s)") == {"mV": 1, "°": -1, "s": 1}
    True
    >>> unit_powers("°/√h") == {"°": 1, "h": Fraction(-1, 2)}, unit_powers("1"), unit_powers("(°/h")
    (True, {}, None)
    """
    tokens = _UNIT_TOKEN.findall(unit_key(text))
    pos = 0

    def term():
        nonlocal pos
        root = pos < len(tokens) and tokens[pos] == "√"
        pos += root
        if pos >= len(tokens) or tokens[pos] in ")/·^√":
            return None
        if tokens[pos] == "(":
            pos += 1
            inner = expr()
            if inner is None or pos >= len(tokens) or tokens[pos] != ")":
                return None
            pos += 1
        else:
            inner = {} if tokens[pos] == "1" else {tokens[pos]: Fraction(1)}
            pos += 1
        power = Fraction(1, 2) if root else Fraction(1)
        if pos + 1 < len(tokens) and tokens[pos] == "^" and re.fullmatch(r"-?[0-9]+",
                                                                      tokens[pos + 1]):
            power, pos = power * int(tokens[pos + 1]), pos + 2
        return {k: v * power for k, v in inner.items()}

    def expr():
        nonlocal pos
        out = term()
        while out is not None and pos < len(tokens) and tokens[pos] in "/·":
            sign = -1 if tokens[pos] == "/" else 1
            pos += 1
            nxt = term()
            if nxt is None:
                return None
            for k, v in nxt.items():
                out[k] = out.get(k, 0) + sign * v
        return out

    powers = expr()
    if powers is None or pos != len(tokens):
        return None
    return {k: v for k, v in powers.items() if v}


def same_unit(a: str | None, b: str | None) -> bool:
    """Whether units ``a`` and ``b`` are one unit, however spelt (:func:`unit_key`) or
    bracketed ("°/h/°C" is "(°/h)/°C"); "%" and "ppm", "°/s" and "°/h" are not.

    >>> same_unit("deg/h", "º/h"), same_unit("%", "ppm"), same_unit("(°/h)/°C", "°/h/°C")
    (True, False, True)
    """
    pa, pb = unit_powers(a), unit_powers(b)
    if pa is None or pb is None:
        return unit_key(a) == unit_key(b)
    return pa == pb


def _exact_power(f: Fraction, e: Fraction) -> Fraction | None:
    """``f`` to the power ``e`` exactly (a whole or half power of a square), else None."""
    if e.denominator == 1:
        return f ** int(e)
    if e.denominator != 2:
        return None
    n, d = math.isqrt(f.numerator), math.isqrt(f.denominator)
    if n * n != f.numerator or d * d != f.denominator:
        return None
    return Fraction(n, d) ** e.numerator


def _in_base(powers: dict[str, Fraction]) -> tuple[dict[str, Fraction], Fraction] | None:
    """A unit's powers in the base symbols of :data:`_EXACT` with its exact factor; a symbol
    it does not know stays as it is (factor 1). None where a factor is not exact."""
    base: dict[str, Fraction] = {}
    factor = Fraction(1)
    for sym, e in powers.items():
        to, n, f = _EXACT.get(sym, (sym, 1, Fraction(1)))
        part = _exact_power(f, e)
        if part is None:
            return None
        factor *= part
        if to:
            base[to] = base.get(to, 0) + n * e
    return {k: v for k, v in base.items() if v}, factor


def unit_factor(frm: str | None, to: str | None) -> Fraction | None:
    """The exact factor c with 1 ``frm`` = c ``to``, where the two units differ only by
    symbols whose ratio is exact (:data:`_EXACT`: ″, ′ and °; s, min and h; Hz; %, ppm and
    the number 1); None where they do not convert so (another quantity, a prefix, a radian).

    >>> unit_factor("°/s", "deg/h"), unit_factor("%", "ppm"), unit_factor("″", "°")
    (Fraction(3600, 1), Fraction(10000, 1), Fraction(1, 3600))
    >>> unit_factor("°/√h", "(°/h)/√Hz"), unit_factor("ppm", "1"), unit_factor("mV/(°/s)", "V/(°/s)")
    (Fraction(60, 1), Fraction(1, 1000000), None)
    """
    pa, pb = unit_powers(frm), unit_powers(to)
    if pa is None or pb is None:
        return None
    a, b = _in_base(pa), _in_base(pb)
    if a is None or b is None or a[0] != b[0]:
        return None
    return a[1] / b[1]
