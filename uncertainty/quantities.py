"""Input quantities: Type B from a distribution and a half-width, Type A from data.

Each :class:`InputQuantity` carries its estimate, standard uncertainty, degrees of
freedom and the way to draw Monte Carlo samples (JCGM 101 6.4).

- :func:`type_b` — JCGM 100 4.3: u = a / divisor, infinite dof unless given.
- :func:`type_a` — JCGM 100 4.2: mean, s (one reading) or s/√n (the mean), ν = n − 1;
  sampled as a scaled and shifted t distribution (JCGM 101 6.4.9).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from uncertainty.distributions import distribution

__all__ = ["InputQuantity", "type_a", "type_b", "from_u"]


@dataclass(frozen=True)
class InputQuantity:
    """One input quantity X_i of a measurement model.

    Attributes
    ----------
    symbol : str
        Name used in the model (a sympy symbol's name or a callable's argument position).
    value : float
        Estimate x_i.
    u : float
        Standard uncertainty u(x_i).
    dof : float
        Degrees of freedom ν_i (``math.inf`` for a Type B value known exactly).
    type : str
        ``"A"`` or ``"B"`` (JCGM 100 4.2, 4.3).
    distribution : str
        Name of the distribution (``"t"`` for Type A with finite dof).
    half_width : float or None
        a, for Type B; None for Type A.
    divisor : float or None
        a / u, for Type B.
    source : str
        What the component stands for.
    """

    symbol: str
    value: float
    u: float
    dof: float = math.inf
    type: str = "B"
    distribution: str = "normal"
    half_width: float | None = None
    divisor: float | None = None
    source: str = ""
    _dist: object = field(default=None, repr=False, compare=False)

    @property
    def drawn_as(self) -> str:
        """The distribution the Monte Carlo draws (:meth:`sample`): the Type B line's own
        when it has one and a half-width, else ``"t"`` for a finite ν (JCGM 101 6.4.9) or
        ``"normal"``."""
        if self._dist is not None and self.half_width is not None:
            return self.distribution
        return "t" if math.isfinite(self.dof) else "normal"

    @property
    def shape_beta(self) -> float | None:
        """The shape parameter β of a trapezoidal or rectangular-shifted-product line (the
        top/base ratio, or m/(c + m)); None for the others."""
        return getattr(self._dist, "beta", None)

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """Draw ``size`` Monte Carlo samples of X_i (JCGM 101 6.4).

        Type B: the named distribution about ``value``. Type A (or a quantity
        given by u and a finite ν): x + u·t_ν, the scaled-shifted t of JCGM 101
        6.4.9.7, whose standard deviation is u·√(ν/(ν−2)). Infinite ν: normal.

        >>> q = type_b("P", 0.0, 0.1, "rectangular")
        >>> x = q.sample(np.random.default_rng(1), 100000)
        >>> bool(abs(x.std() - 0.0577) < 0.001)
        True
        """
        # x + u·z computed in place on the draws z (the same bits as the expression: IEEE
        # addition and multiplication commute), without a temporary per operation
        if self._dist is not None and self.half_width is not None:
            z = self._dist.sample(rng, self.half_width, size)
        else:
            z = (rng.standard_t(self.dof, size) if math.isfinite(self.dof)
                 else rng.standard_normal(size))
            z *= self.u
        z += self.value
        return z


def type_b(symbol: str, value: float, half_width: float, distribution_name: str = "rectangular",
           *, k: float | None = None, beta: float | None = None, dof: float = math.inf,
           source: str = "") -> InputQuantity:
    """A Type B input quantity from a half-width and a distribution (JCGM 100 4.3).

    Parameters
    ----------
    symbol, value : str, float
        Name and estimate.
    half_width : float
        a (for ``normal``: the expanded uncertainty whose coverage factor is ``k``).
    distribution_name : str
        A key of :data:`uncertainty.distributions.DISTRIBUTIONS`.
    k, beta : float, optional
        Normal coverage factor; trapezoid top/base ratio.
    dof : float
        Degrees of freedom (JCGM 100 G.4.2), infinite by default.

    Examples
    --------
    Draft Annex A.4.1: table MPE ±0.1″, rectangular.

    >>> q = type_b("P", 0.0, 0.1, "rectangular")
    >>> round(q.u, 4), q.divisor == math.sqrt(3)
    (0.0577, True)
    >>> round(type_b("l_s", 0.0, 75.0, "normal", k=3).u, 6)
    25.0
    """
    if half_width < 0:
        raise ValueError(f"half-width of {symbol} must be >= 0, got {half_width}")
    dist = distribution(distribution_name, k=k, beta=beta)
    div = dist.divisor
    return InputQuantity(symbol=symbol, value=float(value), u=float(half_width) / div,
                         dof=float(dof), type="B", distribution=dist.name,
                         half_width=float(half_width), divisor=div, source=source, _dist=dist)


def type_a(symbol: str, data, *, of_mean: bool = True, source: str = "") -> InputQuantity:
    """A Type A input quantity from repeated readings (JCGM 100 4.2).

    Estimate: the arithmetic mean (4.2.1); u: the experimental standard deviation
    s (4.2.2, Bessel) of one reading, or of the mean s/√n (4.2.3) when ``of_mean``;
    ν = n − 1 (G.3.3). Monte Carlo samples: scaled-shifted t_ν (JCGM 101 6.4.9).

    >>> q = type_a("d", [215.0, 216.0, 214.0, 215.0])
    >>> q.value, round(q.u, 6), q.dof
    (215.0, 0.408248, 3.0)
    >>> round(type_a("r", [1.0, 2.0, 3.0], of_mean=False).u, 6)
    1.0
    """
    x = np.asarray(data, dtype=float).ravel()
    n = x.size
    if n < 2:
        raise ValueError(f"Type A evaluation of {symbol} needs at least 2 readings, got {n}")
    s = float(np.std(x, ddof=1))
    u = s / math.sqrt(n) if of_mean else s
    return InputQuantity(symbol=symbol, value=float(np.mean(x)), u=u, dof=float(n - 1), type="A",
                         distribution="t", half_width=None, divisor=None, source=source,
                         _dist=None)


def reliability_dof(relative_uncertainty_of_u: float) -> float:
    """The degrees of freedom of a standard uncertainty judged reliable to
    ``relative_uncertainty_of_u`` = Δu/u: JCGM 100 G.4.2 eq. (G.3), ν ≈ ½ (Δu/u)⁻². The
    one reading of a line whose ν no sample gives (a drift model's u, a noise level
    carried from a fit): "u is good to 10 %" is ν = 50.

    >>> reliability_dof(0.10), reliability_dof(0.25)
    (50.0, 8.0)
    """
    r = float(relative_uncertainty_of_u)
    if not r > 0:
        raise ValueError(f"the relative uncertainty of u must be > 0, got {r}")
    return 0.5 / r / r


#: ν of a line whose u is judged reliable to 10 % (:func:`reliability_dof`): 50.
DOF_U_WITHIN_10PCT = reliability_dof(0.10)


def from_u(symbol: str, value: float, u: float, *, dof: float = math.inf, type: str = "A",
           source: str = "") -> InputQuantity:
    """An input quantity given directly by x, u(x) and ν (e.g. a stated repeatability).

    Sampled as normal (ν infinite) or scaled-shifted t_ν (JCGM 101 6.4.9.7).

    >>> from_u("r", 0.0, 0.096).u
    0.096
    """
    if u < 0:
        raise ValueError(f"u({symbol}) must be >= 0, got {u}")
    return InputQuantity(symbol=symbol, value=float(value), u=float(u), dof=float(dof),
                         type=type, distribution="normal" if math.isinf(dof) else "t",
                         half_width=None, divisor=None, source=source,
                         _dist=None)

