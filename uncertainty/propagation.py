"""The law of propagation of uncertainty (JCGM 100 clause 5, Annex G).

- :func:`sensitivity_coefficients` — c_i = ∂f/∂x_i, symbolic for a sympy model,
  central differences for a Python callable (JCGM 100 5.1.3, 5.1.4).
- :func:`combined_uncertainty` — u_c² = cᵀ V c with V the input covariance matrix
  (JCGM 100 5.1.2 uncorrelated, 5.2.2 correlated).
- :func:`welch_satterthwaite` — ν_eff (JCGM 100 G.4.1).
- :func:`coverage_factor` — k = t_p(ν_eff) (JCGM 100 G.3, G.4).
- :func:`propagate` — all of the above in one :class:`GumResult`.

How a result is stated (U to two significant digits, the value at its decimal place, JCGM 100
7.2.6) is not this engine's business: gonio states every number by one rule,
``gonio.result.statement``.

Compiled (lambdified) sympy models are cached, so evaluating the same model again is fast.
SymPy is imported only when a sympy model is compiled: an additive model written as a
:class:`LinearModel` (its coefficients known) is evaluated and differentiated without it,
so a process that only propagates such models (a coverage study's workers) never pays the
SymPy import.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import sys

import numpy as np
from scipy import stats

from uncertainty.quantities import InputQuantity

__all__ = ["Contribution", "GumResult", "LinearModel", "compile_model", "sensitivity_coefficients",
           "combined_uncertainty", "welch_satterthwaite", "coverage_factor", "propagate"]


# --------------------------------------------------------------------------- model evaluation
@dataclass(frozen=True)
class LinearModel:
    """y = ``value`` + Σ ``coeffs``[i]·X_i over the inputs named ``names``: an additive
    model whose sensitivity coefficients are the coefficients themselves (JCGM 100 5.1.3),
    evaluated and differentiated without SymPy. :meth:`to_sympy` gives the same model as a
    sympy expression (Float(value) + Σ Float(c_i)·X_i) for whatever needs one.

    >>> m = LinearModel(2.0, (1.0, -0.5), ("a", "b"))
    >>> float(m(1.0, 4.0)), m.gradient(1.0, 4.0)
    (1.0, [1.0, -0.5])
    >>> m.to_sympy()
    1.0*a - 0.5*b + 2.0
    """

    value: float
    coeffs: tuple[float, ...]
    names: tuple[str, ...]

    def __call__(self, *x):
        y = self.value
        for c, xi in zip(self.coeffs, x):
            y = y + c * xi
        return y

    def gradient(self, *x) -> list[float]:
        """∂y/∂X_i: the coefficients (in ``names`` order)."""
        return [float(c) for c in self.coeffs]

    def to_sympy(self):
        """The model as the sympy expression Float(value) + Σ Float(c_i)·Symbol(X_i, real)."""
        import sympy
        syms = [sympy.Symbol(n, real=True) for n in self.names]
        return sympy.Float(self.value) + sum((sympy.Float(c) * x for c, x in
                                              zip(self.coeffs, syms)), sympy.Integer(0))


def _is_sympy(model) -> bool:
    """Whether ``model`` is a sympy object (never true while SymPy is not imported)."""
    sp = sys.modules.get("sympy")
    return sp is not None and isinstance(model, sp.Basic)


@functools.lru_cache(maxsize=512)
def _lambdified(expr, names: tuple[str, ...]):
    import sympy
    by_name = {s.name: s for s in expr.free_symbols}
    missing = set(by_name) - set(names)
    if missing:
        raise ValueError(f"model symbols without an input quantity: {', '.join(sorted(missing))}")
    syms = [by_name.get(n, sympy.Symbol(n)) for n in names]
    f = sympy.lambdify(syms, expr, "numpy")
    grad = sympy.lambdify(syms, [sympy.diff(expr, s) for s in syms], "numpy")
    return f, grad


def compile_model(model, names: Sequence[str]) -> tuple[Callable, Callable | None]:
    """The model as a vectorised numpy function of the inputs in ``names`` order.

    Returns ``(f, grad)``; ``grad`` is the lambdified symbolic gradient for a sympy
    model and None for a callable (whose derivatives are taken numerically). The
    sympy compilation is cached on (expression, names).

    >>> import sympy
    >>> x, y = sympy.symbols("x y")
    >>> f, grad = compile_model(x * y, ("x", "y"))
    >>> float(f(2.0, 3.0)), [float(g) for g in grad(2.0, 3.0)]
    (6.0, [3.0, 2.0])
    """
    names = tuple(names)
    if isinstance(model, LinearModel):
        if tuple(model.names) != names:
            if set(model.names) - set(names):
                raise ValueError("model symbols without an input quantity: "
                                 + ", ".join(sorted(set(model.names) - set(names))))
            model = model.to_sympy()
        else:
            return model, model.gradient
    if _is_sympy(model):
        return _lambdified(model, names)
    if callable(model):
        return model, None
    raise TypeError(f"model must be a sympy expression or a callable, got {type(model).__name__}")


def _numeric_gradient(f: Callable, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Central differences (JCGM 100 5.1.4 allows numerical c_i).

    Step h_i = ε^(1/3)·max(|x_i|, u_i) (the step that balances truncation O(h²) and
    rounding O(ε/h) errors of a central difference); h_i = ε^(1/3) if both are 0.
    """
    eps3 = np.finfo(float).eps ** (1.0 / 3.0)
    c = np.empty_like(x)
    for i in range(x.size):  # one pair of evaluations per input, not per sample
        h = eps3 * max(abs(x[i]), u[i])
        if h == 0.0:
            h = eps3
        xp = x.copy()
        xm = x.copy()
        xp[i] += h
        xm[i] -= h
        h2 = xp[i] - xm[i]  # the step actually represented in floating point
        c[i] = (float(f(*xp)) - float(f(*xm))) / h2
    return c


def sensitivity_coefficients(model, inputs: Sequence[InputQuantity]) -> np.ndarray:
    """c_i = ∂f/∂X_i at the estimates (JCGM 100 5.1.3).

    Symbolic for a sympy expression, central differences for a callable.

    >>> from uncertainty.quantities import type_b
    >>> import sympy
    >>> a, b = sympy.symbols("a b")
    >>> q = [type_b("a", 2.0, 0.1), type_b("b", 4.0, 0.1)]
    >>> sensitivity_coefficients(a / b, q).tolist()
    [0.25, -0.125]
    >>> [round(float(c), 9) for c in sensitivity_coefficients(lambda a, b: a / b, q)]
    [0.25, -0.125]
    """
    names = tuple(q.symbol for q in inputs)
    x = np.array([q.value for q in inputs], dtype=float)
    f, grad = compile_model(model, names)
    if grad is not None:
        return np.array([float(g) for g in grad(*x)], dtype=float)
    u = np.array([q.u for q in inputs], dtype=float)
    return _numeric_gradient(f, x, u)


# --------------------------------------------------------------------------- combination
def _covariance(u: np.ndarray, correlation=None, covariance=None) -> np.ndarray:
    if covariance is not None:
        v = np.asarray(covariance, dtype=float)
    elif correlation is not None:
        r = np.asarray(correlation, dtype=float)
        v = r * np.outer(u, u)
    else:
        return np.diag(u * u)
    n = u.size
    if v.shape != (n, n):
        raise ValueError(f"correlation/covariance must be {n}x{n}, got {v.shape}")
    if not np.allclose(v, v.T):
        raise ValueError("correlation/covariance matrix must be symmetric")
    return v


def combined_uncertainty(c, u, correlation=None, covariance=None) -> float:
    """u_c(y) = sqrt(cᵀ V c) (JCGM 100 eq. (10) uncorrelated, eq. (13) correlated).

    V = diag(u)·R·diag(u) from a correlation matrix R (JCGM 100 5.2.2, eq. (14)),
    or the covariance matrix V itself.

    Draft Annex A.6, unrounded components:

    >>> round(combined_uncertainty([1, 1, 1, -1], [0.0577350, 0.0453450, 0.0866025, 0.096]), 4)
    0.1487
    >>> round(combined_uncertainty([1, 1], [1.0, 1.0], correlation=[[1, 1], [1, 1]]), 12)
    2.0
    """
    c = np.asarray(c, dtype=float)
    u = np.asarray(u, dtype=float)
    v = _covariance(u, correlation, covariance)
    var = float(c @ v @ c)
    return math.sqrt(max(var, 0.0))


def welch_satterthwaite(u_c: float, contributions, dofs, correlation=None) -> float:
    """Effective degrees of freedom ν_eff = u_c⁴ / Σ u_i(y)⁴/ν_i (JCGM 100 G.4.1, eq. (G.2b)).

    ``contributions`` are u_i(y) = |c_i|·u(x_i). Inputs with ν_i = ∞ add nothing.
    The formula assumes independent inputs; if a correlated input has finite
    degrees of freedom it is not valid (Willink, Metrologia 44 (2007) 340) and NaN is
    returned, as GTC does for such inputs outside an ensemble. Correlation between
    inputs of infinite dof is allowed (they do not enter the sum).

    GUM H.1.6 (end gauge): u_c² = 1002 nm², components 25, 9.7, 2.9, 16.6 nm with
    ν = 18, 25.6, 50, 2 give ν_eff = 16.7, which H.1.6 truncates to 16.

    >>> round(welch_satterthwaite(math.sqrt(1002), [25, 9.7, 2.9, 16.6], [18, 25.6, 50, 2]), 1)
    16.7
    >>> welch_satterthwaite(1.0, [1.0], [math.inf])
    inf
    """
    ui = np.abs(np.asarray(contributions, dtype=float))
    nu = np.asarray(dofs, dtype=float)
    if correlation is not None:
        r = np.asarray(correlation, dtype=float)
        off = (r != 0) & ~np.eye(r.shape[0], dtype=bool)
        involved = off.any(axis=0) & (ui > 0)
        if np.any(involved & np.isfinite(nu)):
            return math.nan
    finite = np.isfinite(nu) & (ui > 0)
    denom = float(np.sum(ui[finite] ** 4 / nu[finite]))
    if denom == 0.0:
        return math.inf
    return float(u_c) ** 4 / denom


def coverage_factor(dof: float = math.inf, p: float = 0.95, *, integer_dof: bool = False) -> float:
    """k_p = t_p(ν), the two-sided Student t quantile (JCGM 100 G.3.4, Table G.2).

    ``integer_dof`` truncates ν_eff to the next lower integer, as JCGM 100 G.4.1
    note 1 suggests when t tables are used; the default interpolates (exact t).

    >>> round(coverage_factor(16, 0.99), 2)   # GUM H.1.6: t_99(16)
    2.92
    >>> round(coverage_factor(math.inf, 0.9545), 3)
    2.0
    """
    if not 0.0 < p < 1.0:
        raise ValueError(f"coverage probability must be in (0, 1), got {p}")
    q = 0.5 * (1.0 + p)
    if dof is None or math.isinf(dof) or math.isnan(dof):
        return float(stats.norm.ppf(q))
    if integer_dof:
        dof = math.floor(dof)
    if dof < 1:
        raise ValueError(f"degrees of freedom must be >= 1, got {dof}")
    return float(stats.t.ppf(q, dof))


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class Contribution:
    """One row of an uncertainty budget (JCGM 100 7.2.7: list all components)."""

    symbol: str
    source: str
    type: str
    distribution: str
    half_width: float | None
    divisor: float | None
    u_xi: float
    c_i: float
    contribution: float
    dof: float


@dataclass(frozen=True)
class GumResult:
    """Result of the GUM uncertainty framework for one output quantity.

    ``k`` is the coverage factor used for ``U``: fixed, or t_p(ν_eff) when ``p`` is set.
    """

    value: float
    u_c: float
    dof: float
    k: float
    U: float
    p: float | None
    contributions: tuple[Contribution, ...]
    correlation: tuple[tuple[float, ...], ...] | None = field(default=None, repr=False)

    @property
    def interval(self) -> tuple[float, float]:
        """y ± U."""
        return (self.value - self.U, self.value + self.U)

    def table(self):
        """The budget as a pandas DataFrame (see :func:`uncertainty.table.budget_table`)."""
        from uncertainty.table import budget_table
        return budget_table(self)


def propagate(model, inputs: Sequence[InputQuantity], *, correlation=None, covariance=None,
              k: float | None = 2.0, p: float | None = None,
              integer_dof: bool = False) -> GumResult:
    """Evaluate y = f(x) and its uncertainty by the law of propagation (JCGM 100 5).

    Parameters
    ----------
    model : sympy.Expr or callable
        The measurement model; a sympy expression's symbols are matched to the
        inputs by name, a callable takes the inputs positionally.
    inputs : sequence of InputQuantity
    correlation, covariance : array_like, optional
        Input correlation matrix R or covariance matrix V (JCGM 100 5.2.2).
    k : float, optional
        Fixed coverage factor (used when ``p`` is None), e.g. k = 2 (draft A.7).
    p : float, optional
        Coverage probability: then k = t_p(ν_eff) (JCGM 100 G.4.1, G.3).
    integer_dof : bool
        Truncate ν_eff before looking up t_p (JCGM 100 G.4.1 note 1).

    Examples
    --------
    Draft Annex A.2 model Δ = (φ_e + B_E) − P plus repeatability r:

    >>> from uncertainty.quantities import type_b, from_u
    >>> import sympy
    >>> P, phi, B, r = sympy.symbols("P phi_e B_E r")
    >>> q = [type_b("P", 0, 0.1), type_b("phi_e", 0, 0.0785), type_b("B_E", 0, 0.15),
    ...      from_u("r", 0, 0.096)]
    >>> res = propagate(phi + B - P + r, q, k=2)
    >>> round(res.u_c, 4), round(res.U, 3)
    (0.1487, 0.297)
    """
    if k is not None and p is None and not k > 0:
        raise ValueError(f"coverage factor k must be > 0, got {k}")
    names = tuple(q.symbol for q in inputs)
    if len(set(names)) != len(names):
        raise ValueError(f"input symbols must be unique, got {names}")
    x = np.array([q.value for q in inputs], dtype=float)
    u = np.array([q.u for q in inputs], dtype=float)
    if covariance is not None:
        u = np.sqrt(np.diag(np.asarray(covariance, dtype=float)))
    f, _ = compile_model(model, names)
    y = float(f(*x))
    c = sensitivity_coefficients(model, inputs)
    v = _covariance(u, correlation, covariance)
    u_c = combined_uncertainty(c, u, covariance=v)
    ui = np.abs(c) * u
    nu = np.array([q.dof for q in inputs], dtype=float)
    r = None
    if correlation is not None or covariance is not None:
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.where(np.outer(u, u) > 0, v / np.outer(u, u), np.eye(len(u)))
    nu_eff = welch_satterthwaite(u_c, ui, nu, correlation=r)
    if p is not None:
        kk = coverage_factor(nu_eff, p, integer_dof=integer_dof)
    else:
        if k is None:
            raise ValueError("give a fixed k or a coverage probability p")
        kk = float(k)
    rows = tuple(Contribution(symbol=q.symbol, source=q.source, type=q.type,
                              distribution=q.distribution, half_width=q.half_width,
                              divisor=q.divisor, u_xi=float(u[i]), c_i=float(c[i]),
                              contribution=float(ui[i]), dof=float(q.dof))
                 for i, q in enumerate(inputs))
    rt = None if r is None else tuple(tuple(float(v) for v in row) for row in r)
    return GumResult(value=y, u_c=u_c, dof=nu_eff, k=kk, U=kk * u_c, p=p,
                     contributions=rows, correlation=rt)
