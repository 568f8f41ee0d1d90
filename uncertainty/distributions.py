"""Probability distributions for Type B input quantities, chosen by name.

One mapping, :data:`DISTRIBUTIONS`, turns a name into a distribution class; each
class knows its divisor (half-width / standard uncertainty, JCGM 100 4.3.7–4.3.9)
and how to draw samples for a Monte Carlo run (JCGM 101 6.4).

=============  =======================  ==========================================
name           divisor (a / u)          source
=============  =======================  ==========================================
normal         k (given coverage factor) JCGM 100 4.3.4; JCGM 101 6.4.7
rectangular    √3                        JCGM 100 4.3.7; JCGM 101 6.4.2
triangular     √6                        JCGM 100 4.3.9; JCGM 101 6.4.5
arcsine        √2                        JCGM 101 6.4.6 (U-shaped)
trapezoidal    √(6 / (1 + β²))           JCGM 100 4.3.9; JCGM 101 6.4.4
rectangular-   3                         product X₁X₂ of two independent zero-mean
product                                  rectangulars: JCGM 100 5.1.2 NOTE (second order)
rectangular-   √(3 / ((1 − β)² + β²/3))  product of a zero-mean rectangular and a
shifted-                                 rectangular on [1 − 2β, 1] (scaled): JCGM 100
product                                  5.1.2 NOTE, exact; JCGM 101 6.4.2.4 per factor
=============  =======================  ==========================================

Aliases: ``uniform`` → rectangular, ``u-shaped`` / ``u_shaped`` → arcsine,
``gaussian`` → normal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Normal", "Rectangular", "Triangular", "Arcsine", "Trapezoidal",
           "RectangularProduct", "RectangularShiftedProduct", "DISTRIBUTIONS", "distribution"]


@dataclass(frozen=True)
class Normal:
    """Normal distribution given by a half-width (expanded uncertainty) and its k.

    JCGM 100 4.3.4: u = a / k.

    >>> Normal(k=2.0).divisor
    2.0
    """

    k: float = 1.0
    name = "normal"

    @property
    def divisor(self) -> float:
        return float(self.k)

    def sample(self, rng: np.random.Generator, half_width: float, size: int) -> np.ndarray:
        """Zero-mean samples (JCGM 101 6.4.7)."""
        return rng.standard_normal(size) * (half_width / self.k)


@dataclass(frozen=True)
class Rectangular:
    """Rectangular (uniform) distribution on [−a, a]: u = a/√3 (JCGM 100 4.3.7).

    >>> round(0.1 / Rectangular().divisor, 4)
    0.0577
    """

    name = "rectangular"

    @property
    def divisor(self) -> float:
        return math.sqrt(3.0)

    def sample(self, rng: np.random.Generator, half_width: float, size: int) -> np.ndarray:
        """Zero-mean samples (JCGM 101 6.4.2.4)."""
        return rng.uniform(-half_width, half_width, size)


@dataclass(frozen=True)
class Triangular:
    """Symmetric triangular distribution on [−a, a]: u = a/√6 (JCGM 100 4.3.9).

    >>> round(Triangular().divisor, 6)
    2.44949
    """

    name = "triangular"

    @property
    def divisor(self) -> float:
        return math.sqrt(6.0)

    def sample(self, rng: np.random.Generator, half_width: float, size: int) -> np.ndarray:
        """Zero-mean samples (JCGM 101 6.4.5.4: sum of two rectangulars of half-width a/2)."""
        h = 0.5 * half_width
        x = rng.uniform(-h, h, size)
        x += rng.uniform(-h, h, size)          # in place: the same bits as the sum
        return x


@dataclass(frozen=True)
class Arcsine:
    """Arcsine (U-shaped) distribution on [−a, a]: u = a/√2 (JCGM 101 6.4.6).

    >>> round(Arcsine().divisor, 6)
    1.414214
    """

    name = "arcsine"

    @property
    def divisor(self) -> float:
        return math.sqrt(2.0)

    def sample(self, rng: np.random.Generator, half_width: float, size: int) -> np.ndarray:
        """Zero-mean samples X = a·sin(2πU) (JCGM 101 6.4.6.4)."""
        x = rng.random(size)                   # in place: the same bits as the expression
        x *= 2.0 * np.pi
        np.sin(x, out=x)
        x *= half_width
        return x


@dataclass(frozen=True)
class Trapezoidal:
    """Symmetric trapezoid on [−a, a] with top half-width β·a: u² = a²(1 + β²)/6.

    JCGM 100 4.3.9; β = 0 is triangular, β = 1 rectangular.

    >>> round(Trapezoidal(beta=1.0).divisor, 6) == round(math.sqrt(3), 6)
    True
    """

    beta: float = 0.5
    name = "trapezoidal"

    def __post_init__(self) -> None:
        if not 0.0 <= self.beta <= 1.0:
            raise ValueError(f"trapezoidal beta must be in [0, 1], got {self.beta}")

    @property
    def divisor(self) -> float:
        return math.sqrt(6.0 / (1.0 + self.beta ** 2))

    def sample(self, rng: np.random.Generator, half_width: float, size: int) -> np.ndarray:
        """Zero-mean samples: sum of rectangulars of half-widths a(1±β)/2 (JCGM 101 6.4.4.4)."""
        h1 = 0.5 * half_width * (1.0 + self.beta)
        h2 = 0.5 * half_width * (1.0 - self.beta)
        return rng.uniform(-h1, h1, size) + rng.uniform(-h2, h2, size)


@dataclass(frozen=True)
class RectangularProduct:
    """The product X₁X₂ of two independent zero-mean rectangulars on [−a₁, a₁] and [−a₂, a₂],
    given by a = a₁a₂: density ln(a/|x|)/(2a) on [−a, a], u = a/3.

    A product whose factors both have zero estimate has no first-order term; JCGM 100 5.1.2
    NOTE's second-order term gives u²(x₁x₂) = u²(x₁)u²(x₂) = (a₁²/3)(a₂²/3), exact for
    independent factors. Monte Carlo samples: the product of the two draws (JCGM 101 6.4.2.4
    for each factor).

    >>> RectangularProduct().divisor
    3.0
    """

    name = "rectangular-product"

    @property
    def divisor(self) -> float:
        return 3.0

    def sample(self, rng: np.random.Generator, half_width: float, size: int) -> np.ndarray:
        """Zero-mean samples a·U₁U₂, U₁ and U₂ independent and uniform on [−1, 1]."""
        x = rng.uniform(-1.0, 1.0, size)       # in place: the same bits as the expression
        x *= half_width
        x *= rng.uniform(-1.0, 1.0, size)
        return x


@dataclass(frozen=True)
class RectangularShiftedProduct:
    """The product X₁X₂ of a zero-mean rectangular X₁ on [−a₁, a₁] and an independent
    rectangular X₂ on [c − m, c + m] (c ≥ 0, m ≥ 0, not both 0), given by its half-width
    a = a₁(c + m) (the largest |X₁X₂|) and β = m/(c + m) ∈ [0, 1]: X₁X₂ = a·U·W, U uniform
    on [−1, 1], W uniform on [1 − 2β, 1].

    Its mean is 0 (E X₁ = 0) and, X₁ and X₂ independent, u² = E[X₁²]E[X₂²] =
    (a₁²/3)(c² + m²/3) exactly (JCGM 100 5.1.2 NOTE: the first-order term u²(x₁)x₂² plus the
    second-order u²(x₁)u²(x₂); the one with x₁ = 0 vanishes), so u = a·√(((1 − β)² + β²/3)/3).
    β = 0 is the rectangular (X₂ exactly c), β = 1 the ``rectangular-product`` (c = 0).
    Monte Carlo samples: the product of the two draws (JCGM 101 6.4.2.4 for each factor).

    >>> [round(RectangularShiftedProduct(beta=b).divisor ** 2, 12) for b in (0.0, 1.0)]
    [3.0, 9.0]
    """

    beta: float = 0.5
    name = "rectangular-shifted-product"

    def __post_init__(self) -> None:
        if not 0.0 <= self.beta <= 1.0:
            raise ValueError(f"rectangular-shifted-product beta must be in [0, 1], "
                             f"got {self.beta}")

    @property
    def divisor(self) -> float:
        b = self.beta
        return math.sqrt(3.0 / ((1.0 - b) ** 2 + b * b / 3.0))

    def sample(self, rng: np.random.Generator, half_width: float, size: int) -> np.ndarray:
        """Zero-mean samples a·U·W, U uniform on [−1, 1], W on [1 − 2β, 1], independent."""
        return (half_width * rng.uniform(-1.0, 1.0, size)
                * rng.uniform(1.0 - 2.0 * self.beta, 1.0, size))


#: The one mapping from a distribution's name to its class.
DISTRIBUTIONS = {
    "normal": Normal,
    "gaussian": Normal,
    "rectangular": Rectangular,
    "uniform": Rectangular,
    "triangular": Triangular,
    "arcsine": Arcsine,
    "u-shaped": Arcsine,
    "u_shaped": Arcsine,
    "trapezoidal": Trapezoidal,
    "rectangular-product": RectangularProduct,
    "rectangular-shifted-product": RectangularShiftedProduct,
}


def distribution(name: str, *, k: float | None = None, beta: float | None = None):
    """The distribution called ``name`` (see :data:`DISTRIBUTIONS`).

    ``k`` is the coverage factor of a normal half-width, ``beta`` the top/base
    ratio of a trapezoid or the shifted factor's share of a ``rectangular-shifted-product``.

    >>> distribution("uniform").name
    'rectangular'
    >>> distribution("normal", k=2).divisor
    2.0
    """
    try:
        cls = DISTRIBUTIONS[name.lower()]
    except KeyError:
        raise ValueError(f"unknown distribution {name!r}; expected one of "
                         f"{', '.join(sorted(DISTRIBUTIONS))}") from None
    if cls is Normal:
        return Normal(k=1.0 if k is None else float(k))
    if cls is Trapezoidal:
        return Trapezoidal(beta=0.5 if beta is None else float(beta))
    if cls is RectangularShiftedProduct:
        return RectangularShiftedProduct(beta=0.5 if beta is None else float(beta))
    return cls()
