"""Identification of the extended MEMS-gyro model K(ϑ, U), b(ϑ, U), ARW(ϑ) ([Vagner2015], docs/references.md).

The thesis's model (eq. 6.14–6.20) for gyro i::

    y = K(ϑ, U) (ω + b(ϑ, U))         K = k0 + Σ_j κ_ϑj ϑ^j + Σ_j κ_Uj U^j
                                      b = b0 + Σ_j β_ϑj ϑ^j + Σ_j β_Uj U^j
                                      white noise density ARW(ϑ) = Σ_j B_ϑj ϑ^j

with ϑ the temperature relative to the reference (the thesis ties the model to the
gyro's own temperature-sensor output, whose offset and nonlinearity the polynomials
absorb, §6.1) and U = V − V_ref the supply deviation. Polynomials have no cross terms and
no constant beyond k0, b0 (eq. 6.17–6.18).

Identification steps (as the thesis runs them, §5.2.3–5.2.4, §6.2, §6.4)
-------------------------------------------------------------------------
1. At each soak (temperature settled, chamber stability ~±0.5 °C) and each supply voltage
   (voltages stepped in alternating order around the nominal, Fig. 5.8), a +ω / −ω pair
   of whole-revolution dwells about the gyro's input axis gives
   K = (y₊ − y₋)/(2ω) and b = (y₊ + y₋)/(2K) − Ω_E,in (the Earth rate along the input axis
   cancels in the difference and is removed from the mean); a static dwell gives the
   white-noise density ARW = σ_sample/K · √τ0 (white noise dominates at the sample
   interval; the thesis uses 6 h Allan records per temperature for the same number).
2. Polynomials in ϑ and U fitted by least squares, the orders chosen by a stated
   criterion (:data:`CRITERIA`: BIC by default, AIC, or a forward sequential F-test at
   α = 0.05) instead of fixed — the thesis compares orders 1–4 by their maximum error
   (Table 6.6) and settles on 2–3 for K and b, 2 for ARW(ϑ), linear in U (Table 6.7).
3. Parameter covariance s² (XᵀX)⁻¹ (GUM Type A), prediction uncertainty
   u(ŷ(ϑ, U)) = sqrt(xᵀ C x) across the operating range.
4. Ramps: the static-soak model applied to static blocks recorded during the ramps; its
   error there (thermal lag between the temperature used and the sensing element:
   hysteresis on up/down ramps) is reported, and two remedies offered: a
   rate-of-temperature-change term γ dϑ/dt fitted to the ramp residuals, and a
   first-order lag of time constant τ applied to the temperature (τ fitted). The thesis
   does neither: it feeds the model with the gyro's internal temperature sensor, found
   no measurable sensor-to-element dynamics up to 4 °C/min for its ADXRS parts (§6.3),
   and advises limiting the ramp gradient (§6.2.2).
5. Compensation of new records: ω̂ = y / K̂(ϑ, U) − b̂(ϑ, U) (− γ dϑ/dt); residual bias and
   scale-factor errors before (constant reference-condition k0, b0) and after.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import optimize, stats

from gonio.physics.earth import earth_rate_enu
from gonio.units import deg_sqrt_s_from_deg_sqrt_h
from gonio.errors import GonioError
from gonio.specs.triad_alignment.readings import OUT, TriadReadings
from gonio.physics.alignment import AXES, mean_earth_rate_ref, signed_axis

CRITERIA = ("bic", "aic", "ftest")
F_TEST_ALPHA = 0.05
#: The highest polynomial orders the selection tries (temperature, supply; the ARW model has
#: no supply term): the largest polynomial a result can hold (its coefficients are information).
MAX_ORDER_T, MAX_ORDER_U, MAX_ORDER_ARW = 4, 2, 2


# --------------------------------------------------------------------------- data
def soak_points(readings: TriadReadings, *, temperature: str = "sensor") -> pd.DataFrame:
    """One row per ± pair of soak dwells: channel, ϑ, U, K, b (°/s), ARW (°/√h) of the
    static dwell that follows at the same supply (NaN if none, or if it holds one sample: no
    standard deviation; ``arw_n`` its samples, 0 if none, ``arw_fs_hz`` their rate), time (s)
    — step 1 of the
    module docstring ([Vagner2015] §5.2.3–5.2.4: K from the ± difference, b from the mean
    with the Earth rate removed; whole revolutions, §5.3).

    ``temperature`` is ``sensor`` (the gyro's internal sensor, the thesis's choice) or
    ``chamber``.
    """
    if temperature not in ("sensor", "chamber"):
        raise GonioError(f"temperature source must be sensor or chamber, got {temperature!r}")
    col = "sensor_c" if temperature == "sensor" else "chamber_c"
    th = readings.rows("thermal")
    if th.empty:
        raise GonioError(f"{readings.path}: no thermal rows")
    t_ref = float(readings.metadata.get("reference_c", 25.0))
    v_ref = float(readings.metadata.get("reference_v", 5.0))
    w_enu = np.degrees(earth_rate_enu(readings.latitude_deg))
    fs = readings.sample_rate_hz
    # a soak: one run of consecutive soak rows (a ramp or another up axis ends it)
    block = ((th["phase"] != th["phase"].shift()) | (th["up"] != th["up"].shift())).cumsum()
    soak = th.assign(soak=block)[th["phase"] == "soak"].to_dict("records")
    pts = []
    k = 0
    while k < len(soak) - 1:
        a, b = soak[k], soak[k + 1]
        if a["rate_dps"] > 0 and b["rate_dps"] == -a["rate_dps"] and a["supply_v"] == b["supply_v"] \
                and a["up"] == b["up"]:
            axis = signed_axis(a["up"])
            c = int(np.argmax(np.abs(axis)))
            sgn = float(axis[c])
            ch = OUT[c]
            kk = (a[ch] - b[ch]) / (2.0 * a["rate_dps"] * sgn)
            e = mean_earth_rate_ref(w_enu, a["up"], a["north0"], a["table_deg"], a["rate_dps"],
                                    a["duration_s"])[c]
            bias = 0.5 * (a[ch] + b[ch]) / kk - e
            arw, arw_n = math.nan, 0
            if k + 2 < len(soak):
                s = soak[k + 2]
                if s["rate_dps"] == 0 and s["supply_v"] == a["supply_v"]:
                    arw_n = int(s["n_samples"])     # one sample: no standard deviation
                    if arw_n >= 2 and np.isfinite(s[f"sd_{AXES[c]}"]):
                        arw = (s[f"sd_{AXES[c]}"] / abs(kk) * math.sqrt(1.0 / fs)
                               / deg_sqrt_s_from_deg_sqrt_h(1.0))
            pts.append({"channel": AXES[c], "theta_c": 0.5 * (a[col] + b[col]) - t_ref,
                        "chamber_c": 0.5 * (a["chamber_c"] + b["chamber_c"]),
                        "u_v": a["supply_v"] - v_ref, "scale": kk, "bias_dps": bias,
                        "arw_deg_sqrt_h": arw, "arw_n": arw_n, "arw_fs_hz": float(fs),
                        "time_s": a["time_s"], "line": int(a["line"]),
                        "soak": int(a["soak"])})
            k += 2
        else:
            k += 1
    if not pts:
        raise GonioError(f"{readings.path}: no ± soak pairs found in the thermal rows")
    return pd.DataFrame(pts)


# ----------------------------------------------------------------- polynomial fits
def design(theta, u, n_t: int, n_u: int) -> np.ndarray:
    """Columns 1, ϑ … ϑ^n_t, U … U^n_u (thesis eq. 6.17–6.18)."""
    theta = np.asarray(theta, float)
    u = np.asarray(u, float)
    cols = [np.ones_like(theta)] + [theta ** j for j in range(1, n_t + 1)] \
        + [u ** j for j in range(1, n_u + 1)]
    return np.column_stack(cols)


@dataclass
class PolyFit:
    """A polynomial in ϑ and U with its covariance and the order-selection record."""

    name: str
    n_t: int
    n_u: int
    coef: np.ndarray
    cov: np.ndarray
    s: float
    dof: int
    criterion: str
    table: list                  # every candidate: n_t, n_u, rss, aic, bic
    scale_t: float = 1.0         # ϑ and U are divided by these inside the fit (conditioning)
    scale_u: float = 1.0
    u_order: np.ndarray | None = None   # model-order standard uncertainty per coefficient
    cov_method: str = "ols"      # "ols" s²(XᵀX)⁻¹ or "soak components" (:func:`soak_covariance`)
    dof_coef: np.ndarray | None = None   # ν of each coefficient (``dof``: the smallest)
    parts: dict | None = None    # :func:`soak_parts` of the selected fit (point variances)
    candidate_coef: dict | None = None   # (n_t, n_u) → coefficients of every candidate order

    def point(self, theta: float, u: float = 0.0) -> dict:
        """The fitted value at one point (ϑ, U) with its standard uncertainties: ``u_fit``
        and ``nu`` of the fit (:func:`linear_variance`: the soak components, ν by
        Welch–Satterthwaite) and ``u_order`` = √(Σ_m w_m (ŷ_m − ŷ)²), the spread of every
        candidate order's value at the point about the selected one with the criterion's
        weights (:func:`criterion_weights`; 0 with fixed orders). Inside the soaked range
        the orders the criterion nearly chose agree closely at a point even where their
        coefficients do not: the point value is the same measurand whatever the order."""
        g = self._x(np.atleast_1d(float(theta)), np.atleast_1d(float(u)))[0]
        value = float(g @ self.coef)
        if self.parts is None:
            var, nu = float(g @ self.cov @ g), float(self.dof)
        else:
            var, nu = linear_variance(self.parts, g)
        u_order = 0.0
        if self.criterion != "fixed" and self.candidate_coef:
            w = criterion_weights(self.table, self.criterion)
            lt, lu = np.atleast_1d(theta / self.scale_t), np.atleast_1d(u / self.scale_u)
            spread = [(design(lt, lu, row["order_temperature"], row["order_supply"])[0]
                       @ self.candidate_coef[(row["order_temperature"], row["order_supply"])]
                       - value) ** 2 for row in self.table]
            u_order = math.sqrt(float(np.dot(w, spread)))
        return {"value": value, "u_fit": math.sqrt(max(var, 0.0)), "nu": float(nu),
                "u_order": u_order}

    def dof_of(self, term: str) -> float:
        """ν of one coefficient (``c0``, ``theta2``, ``u1`` …)."""
        if self.dof_coef is None:
            return float(self.dof)
        idx = 0 if term == "c0" else int(term[5:]) if term.startswith("theta") \
            else self.n_t + int(term[1:])
        return float(self.dof_coef[idx])

    def _x(self, theta, u):
        return design(np.asarray(theta, float) / self.scale_t, np.asarray(u, float) / self.scale_u,
                      self.n_t, self.n_u)

    def predict(self, theta, u=0.0) -> np.ndarray:
        t = np.atleast_1d(np.asarray(theta, float))
        uu = np.broadcast_to(np.asarray(u, float), t.shape)
        return self._x(t, uu) @ self.coef

    def u_predict(self, theta, u=0.0) -> np.ndarray:
        """Standard uncertainty of the fitted value (parameter uncertainty only)."""
        t = np.atleast_1d(np.asarray(theta, float))
        uu = np.broadcast_to(np.asarray(u, float), t.shape)
        x = self._x(t, uu)
        return np.sqrt(np.einsum("ij,jk,ik->i", x, self.cov, x))

    def coefficients(self) -> dict:
        """Coefficients in physical units: c0, ϑ^j and U^j terms, each with its standard
        uncertainty ``u_<term>`` = √(u_fit² + u_order²): ``u_fit_<term>`` from the fit's
        covariance, ``u_order_<term>`` the model-order term (:func:`order_uncertainty`)."""
        uo = np.zeros(self.coef.size) if self.u_order is None else self.u_order
        terms = ["c0"] + [f"theta{j}" for j in range(1, self.n_t + 1)] \
            + [f"u{j}" for j in range(1, self.n_u + 1)]
        facs = [1.0] + [self.scale_t ** j for j in range(1, self.n_t + 1)] \
            + [self.scale_u ** j for j in range(1, self.n_u + 1)]
        out = {}
        for idx, (term, f) in enumerate(zip(terms, facs)):
            u_fit = math.sqrt(self.cov[idx, idx]) / f
            out[term] = float(self.coef[idx] / f)
            out[f"u_{term}"] = float(math.hypot(u_fit, uo[idx] / f))
            out[f"u_fit_{term}"] = float(u_fit)
            out[f"u_order_{term}"] = float(uo[idx] / f)
        return out

    def to_json(self) -> dict:
        return {"name": self.name, "order_temperature": self.n_t, "order_supply": self.n_u,
                "criterion": self.criterion, "s": self.s, "dof": self.dof,
                "dof_coefficients": None if self.dof_coef is None else
                [float(v) for v in self.dof_coef],
                "covariance": self.cov_method,
                "coefficients": self.coefficients(), "candidates": self.table}


def _ols(x, y):
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    r = y - x @ coef
    return coef, float(r @ r)


def soak_covariance(x: np.ndarray, r: np.ndarray, groups: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, str]:
    """Covariance of the least-squares coefficients when the points of one soak share an
    error (the gyro's bias wanders over the minutes a soak's supply steps take, so the
    three points at one temperature move together): Σ = σ_w² I + σ_b² ZZᵀ, Z the soak
    indicator — the split-plot analysis (whole plots: soaks; Searle et al. 1992 §4.6).
    SS_w, the residual left after the soak means (ν_w = n − rank[Z X]), gives MS_w;
    SS_b = RSS − SS_w (ν_b = rank[Z X] − p) has E[SS_b] = σ_w² ν_b + σ_b² tr(M ZZᵀ)
    (M = I − X(XᵀX)⁻¹Xᵀ), so σ̂_b² = (SS_b − MS_w ν_b)/tr. The covariance is
    MS_w (XᵀX)⁻¹ + σ̂_b² HZ(HZ)ᵀ (H = (XᵀX)⁻¹Xᵀ), i.e. (XᵀX)⁻¹XᵀΣ̂X(XᵀX)⁻¹; coefficient j
    has var_j = (a_j − b_j ν_b/tr)·MS_w + (b_j ν_b/tr)·MS_b (a_j = [(XᵀX)⁻¹]_jj,
    b_j = [HZ(HZ)ᵀ]_jj) and its Welch–Satterthwaite ν_j (JCGM 100 G.4). For a balanced
    programme a temperature coefficient's variance is exactly that of the fit of the soak
    means, with ν = the soaks less the temperature terms.

    Returns (cov, ν per coefficient, method). Without replicated soaks (ν_w = 0) or
    without between-soak degrees of freedom (ν_b ≤ 0) it is the ordinary s²(XᵀX)⁻¹ with
    ν = n − p ("ols"). When the soak means scatter no more than the points within a soak
    (σ̂_b² ≤ 0) MS_b is floored at MS_w, its ν_b kept: the covariance is MS_w (XᵀX)⁻¹ and a
    temperature coefficient keeps ν ≈ ν_b. Pooling into s² with ν = n − p there (as
    an earlier version did) gave the heavy tails of the coverage study: with 8 soaks and up to 5
    temperature terms ν_b is 3–4, and a shared error the soak means happen to hide (often
    by an order that absorbed the wander) was then certified with k ≈ 2.1
    (docs/thermal-model.md §2, §7)."""
    parts = soak_parts(x, r, groups)
    if parts["method"] == "ols":
        return parts["s2"] * parts["xtx_inv"], np.full(x.shape[1], parts["nu_ols"]), "ols"
    hz, ms_w, nu_b, tr = parts["hz"], parts["ms_w"], parts["nu_b"], parts["tr"]
    b = np.sum(hz ** 2, axis=1)
    cov = ms_w * parts["xtx_inv"] + (parts["ss_b"] - ms_w * nu_b) / tr * hz @ hz.T
    cw, cb = (np.diag(parts["xtx_inv"]) - b * nu_b / tr) * ms_w, b * nu_b / tr * parts["ms_b"]
    nu = (cw + cb) ** 2 / (cw ** 2 / parts["nu_w"] + cb ** 2 / nu_b)
    return cov, nu, parts["method"]


def soak_parts(x: np.ndarray, r: np.ndarray, groups: np.ndarray) -> dict:
    """The pieces of :func:`soak_covariance` (MS_w, MS_b with ν_w, ν_b, tr(M ZZᵀ),
    (XᵀX)⁻¹, H Z, and the method), from which the variance and the Welch–Satterthwaite ν
    of any linear combination gᵀĉ follow (:func:`linear_variance`): a point value
    K̂(ϑ, U) = x(ϑ, U)ᵀĉ is such a combination."""
    n, p = x.shape
    rss = float(r @ r)
    xtx_inv = np.linalg.inv(x.T @ x)
    ols = {"method": "ols", "s2": rss / (n - p), "nu_ols": float(n - p), "xtx_inv": xtx_inv}
    _, inv = np.unique(groups, return_inverse=True)
    z = np.zeros((n, inv.max() + 1))
    z[np.arange(n), inv] = 1.0
    zx = np.column_stack([z, x])
    rank = int(np.linalg.matrix_rank(zx))
    nu_w, nu_b = n - rank, rank - p
    if nu_w <= 0 or nu_b <= 0:
        return ols
    coef_w, *_ = np.linalg.lstsq(zx, r, rcond=None)
    rw = r - zx @ coef_w
    ss_w = float(rw @ rw)
    ss_b = rss - ss_w
    ms_w, ms_b = ss_w / nu_w, ss_b / nu_b
    tr = float(np.trace(z.T @ (np.eye(n) - x @ xtx_inv @ x.T) @ z))
    if tr <= 0:
        return ols
    method = "soak components"
    if ms_b <= ms_w:
        # σ̂_b² ≤ 0: the soak means scatter no more than the points within a soak. Not
        # pooled into s²(XᵀX)⁻¹ with ν = n − p: the shared error is then merely hidden by
        # ν_b = 3–4 soak-mean degrees of freedom (often by an order that absorbed it), and
        # the temperature terms still rest on the soak means — MS_b is floored at MS_w and
        # keeps its ν_b (the "never pool" rule of split-plot analysis).
        ms_b, ss_b, method = ms_w, ms_w * nu_b, "soak components, MS_b floored at MS_w"
    return {"method": method, "xtx_inv": xtx_inv, "hz": xtx_inv @ x.T @ z, "ms_w": ms_w,
            "ms_b": ms_b, "ss_b": ss_b, "nu_w": nu_w, "nu_b": nu_b, "tr": tr}


def linear_variance(parts: dict, g: np.ndarray) -> tuple[float, float]:
    """Variance of gᵀĉ and its Welch–Satterthwaite ν (JCGM 100 G.4) from the pieces of
    :func:`soak_parts`: (gᵀ(XᵀX)⁻¹g − ‖gᵀHZ‖² ν_b/tr)·MS_w + (‖gᵀHZ‖² ν_b/tr)·MS_b, the
    coefficient formula of :func:`soak_covariance` with g in place of a unit vector; the
    ordinary s² gᵀ(XᵀX)⁻¹g with ν = n − p where the soaks are not replicated."""
    g = np.asarray(g, float)
    a = float(g @ parts["xtx_inv"] @ g)
    if parts["method"] == "ols":
        return parts["s2"] * a, parts["nu_ols"]
    bb = float(np.sum((g @ parts["hz"]) ** 2)) * parts["nu_b"] / parts["tr"]
    cw, cb = (a - bb) * parts["ms_w"], bb * parts["ms_b"]
    return cw + cb, (cw + cb) ** 2 / (cw ** 2 / parts["nu_w"] + cb ** 2 / parts["nu_b"])


def criterion_weights(table: list, criterion: str) -> np.ndarray:
    """The candidates' weights w_m ∝ exp(−Δ_m/2) of the criterion (Akaike / Schwarz weights,
    Burnham & Anderson 2002 §4.2); the F-test and fixed orders use the BIC's."""
    key = "aic" if criterion == "aic" else "bic"
    crit = np.array([row[key] for row in table])
    w = np.exp(-(crit - crit.min()) / 2.0)
    return w / w.sum()


def order_uncertainty(fits: dict, table: list, sel: tuple[int, int], criterion: str
                      ) -> np.ndarray:
    """Model-order standard uncertainty of each coefficient of the selected model ``sel``:
    u_order² = Σ_m w_m (c_m − ĉ)², over every candidate order m with the criterion's weights
    w_m ∝ exp(−Δ_m/2) (Akaike / Schwarz weights, Burnham & Anderson 2002 §4.2–4.3, the
    unconditional variance of Buckland et al. 1997 centred on the selected model); a
    candidate without the term counts it as 0. The F-test uses the BIC weights. The spread
    of the neighbouring orders' coefficients is what selecting one order leaves out of
    s²(XᵀX)⁻¹ (docs/thermal-model.md §2)."""
    w = criterion_weights(table, criterion)
    nt, nu = sel
    c_sel = fits[sel][0]
    var = np.zeros(c_sel.size)
    for wm, row in zip(w, table):
        mt, mu = row["order_temperature"], row["order_supply"]
        cm = fits[(mt, mu)][0]
        aligned = np.zeros(c_sel.size)
        aligned[0] = cm[0]
        for j in range(1, nt + 1):
            aligned[j] = cm[j] if j <= mt else 0.0
        for j in range(1, nu + 1):
            aligned[nt + j] = cm[mt + j] if j <= mu else 0.0
        var += wm * (aligned - c_sel) ** 2
    return np.sqrt(var)


def fit_polynomial(name: str, theta, u, y, *, criterion: str = "bic", max_t: int = 4,
                   max_u: int = 2, orders: tuple[int, int] | None = None,
                   soak=None) -> PolyFit:
    """Fit y = poly(ϑ) + poly(U) choosing the orders by ``criterion``:

    * ``bic``: n ln(RSS/n) + p ln n, the smallest wins (Schwarz 1978);
    * ``aic``: n ln(RSS/n) + 2p (Akaike 1974);
    * ``ftest``: forward selection from (0, 0): of the two next models (one more order
      in ϑ or in U) the one whose extra-sum-of-squares
      F = (RSS_small − RSS_big) / (RSS_big/(n − p_big)) has the smaller p is kept while
      that p < 0.05.

    Orders are capped by the number of distinct ϑ levels (rounded to 0.5 °C) and U levels
    minus one, and by n − 2 parameters in all. ``orders`` = (n_t, n_u) fixes the orders
    (criterion recorded as ``fixed``).

    Uncertainty: the covariance of :func:`soak_covariance` (points of one soak ``soak``
    — default: ϑ rounded to 0.5 °C — share an error) and, unless the orders are fixed,
    the model-order term of :func:`order_uncertainty` beside it (``PolyFit.u_order``).
    """
    if criterion not in CRITERIA:
        raise GonioError(f"order criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}")
    theta = np.asarray(theta, float)
    u = np.asarray(u, float)
    y = np.asarray(y, float)
    ok = np.isfinite(theta) & np.isfinite(u) & np.isfinite(y)
    theta, u, y = theta[ok], u[ok], y[ok]
    if soak is not None:
        soak = np.asarray(soak)[ok]
    n = y.size
    if n < 3:
        raise GonioError(f"{name}: need at least 3 points to fit a temperature model, got {n}")
    st = max(float(np.max(np.abs(theta))), 1e-9)
    su = max(float(np.max(np.abs(u))), 1e-9)
    lt, lu = theta / st, u / su
    cap_t = min(max_t, len(np.unique(np.round(theta * 2))) - 1)
    cap_u = min(max_u, len(np.unique(np.round(u, 6))) - 1)
    table = []
    fits = {}
    for nt in range(0, cap_t + 1):
        for nu in range(0, cap_u + 1):
            p = 1 + nt + nu
            if p > n - 2:
                continue
            x = design(lt, lu, nt, nu)
            coef, rss = _ols(x, y)
            rss = max(rss, 1e-300)
            fits[(nt, nu)] = (coef, rss, x)
            table.append({"order_temperature": nt, "order_supply": nu, "rss": rss,
                          "aic": n * math.log(rss / n) + 2 * p,
                          "bic": n * math.log(rss / n) + p * math.log(n)})
    if orders is not None:
        sel = (int(orders[0]), int(orders[1]))
        if sel not in fits:
            raise GonioError(f"{name}: orders {sel} not identifiable from {n} points "
                             f"(max ϑ order {cap_t}, U order {cap_u})")
        criterion = "fixed"
    elif criterion in ("aic", "bic"):
        best = min(table, key=lambda r: (r[criterion], r["order_temperature"] + r["order_supply"]))
        sel = (best["order_temperature"], best["order_supply"])
    else:
        sel = (0, 0)
        while True:
            best = None
            for nxt in ((sel[0] + 1, sel[1]), (sel[0], sel[1] + 1)):
                if nxt not in fits:
                    continue
                rss_s, rss_b = fits[sel][1], fits[nxt][1]
                p_b = 1 + nxt[0] + nxt[1]
                pval = stats.f.sf((rss_s - rss_b) / (rss_b / (n - p_b)), 1, n - p_b)
                if best is None or pval < best[0]:
                    best = (pval, nxt)
            if best is None or best[0] >= F_TEST_ALPHA:
                break
            sel = best[1]
    coef, rss, x = fits[sel]
    s2 = rss / (n - x.shape[1])
    groups = soak if soak is not None else np.round(theta * 2)
    cov, nu, method = soak_covariance(x, y - x @ coef, groups)
    u_order = None if criterion == "fixed" else order_uncertainty(fits, table, sel, criterion)
    return PolyFit(name, sel[0], sel[1], coef, cov, math.sqrt(s2), float(np.min(nu)), criterion,
                   table, st, su, u_order, method, nu, soak_parts(x, y - x @ coef, groups),
                   {k: v[0] for k, v in fits.items()})


# --------------------------------------------------------------------------- ramps
def _lagged(time_s, temp, tau_s):
    """First-order lag of a (possibly unevenly sampled) temperature series, τ dT_f/dt = T − T_f
    (the chamber-to-sample lag of [Vagner2015] Fig. 5.7), discretised exactly for a
    temperature linear between the samples (first-order hold): with α = e^{−Δt/τ} and
    s = (T[k] − T[k−1])/Δt, T_f[k] = α T_f[k−1] + (1 − α) T[k] − s (τ(1 − α) − αΔt).
    The samples are block means at the blocks' mid-times, on a ramp the temperature there;
    holding each sample constant instead (zero-order hold) would lag the ramp by a further
    Δt/2 and bias the fitted τ by half a block (30 s on the built-in programme).

    >>> t = np.arange(0.0, 6001.0, 60.0)
    >>> f = _lagged(t, t / 60.0, 300.0)          # 1 °C/min ramp, τ = 300 s
    >>> round(float(t[-1] / 60.0 - f[-1]) * 60.0, 4)   # settled: the lag is τ·dT/dt
    300.0
    """
    out = np.empty_like(temp)
    out[0] = temp[0]
    for k in range(1, temp.size):
        dt = time_s[k] - time_s[k - 1]
        if tau_s <= 0 or dt <= 0:
            out[k] = temp[k]
            continue
        a = math.exp(-dt / tau_s)
        slope = (temp[k] - temp[k - 1]) / dt
        out[k] = a * out[k - 1] + (1.0 - a) * temp[k] - slope * (tau_s * (1.0 - a) - a * dt)
    return out


@dataclass
class RampAnalysis:
    """Error of the static-soak model on the ramps, and the two remedies."""

    channel: str
    rms_static_model_dps: float          # ramp residual with the static-soak model
    gamma_dps_per_c_per_s: float         # rate-of-temperature-change term
    u_gamma: float
    rms_with_ramp_term_dps: float
    tau_s: float                         # fitted lag of the temperature
    rms_with_lag_dps: float
    hysteresis_dps: float                # max |up-ramp − down-ramp| bias at equal temperature
    tau_low_s: float = math.nan          # 95 % profile interval of τ (:func:`lag_interval`)
    tau_high_s: float = math.nan         # inf: the ramps bound τ from above no tighter than 10⁴ s
    tau_resolved: bool = False           # τ = 0 (no lag) lies outside the interval
    time_s: list = field(default_factory=list)
    theta_c: list = field(default_factory=list)
    dtheta_dt: list = field(default_factory=list)
    bias_dps: list = field(default_factory=list)
    residual_dps: list = field(default_factory=list)

    @property
    def lag_case(self) -> str:
        """How the lag is stated (the decision is the result's; the report renders it):
        ``fit`` τ with its 95 % interval; ``above`` resolved but unbounded above (τ ≥ low);
        ``bound`` not resolved, τ ≤ high; ``open`` not resolved and unbounded — never τ̂
        alone where no lag is inside the interval (:func:`lag_interval`)."""
        if self.tau_resolved:
            return "fit" if math.isfinite(self.tau_high_s) else "above"
        return "bound" if math.isfinite(self.tau_high_s) else "open"

    def lag_text(self) -> str:
        """The lag in words (English, for the terminal and the HTML report)."""
        return {"fit": f"τ = {self.tau_s:.0f} s (95 %: {self.tau_low_s:.0f}–{self.tau_high_s:.0f} s)",
                "above": f"τ ≥ {self.tau_low_s:.0f} s (95 %)",
                "bound": f"not resolved, τ ≤ {self.tau_high_s:.0f} s (95 %)",
                "open": "not resolved by the ramps"}[self.lag_case]

    def to_json(self) -> dict:
        d = dict(self.__dict__)
        d["lag_case"] = self.lag_case
        return d


def ramp_analysis(readings: TriadReadings, scale: PolyFit, bias: PolyFit, channel: str, *,
                  temperature: str = "sensor") -> RampAnalysis | None:
    """Apply the static-soak model to the ramp blocks of ``channel`` (module step 4): its
    rms error, the fitted γ of a γ·dϑ/dt term (linear least squares), the lag τ minimising
    the residuals of the model fed with the lagged temperature (grid over 1 s … 10⁴ s, then
    a bounded scalar search), and the up/down hysteresis at equal chamber temperature."""
    col = "sensor_c" if temperature == "sensor" else "chamber_c"
    th = readings.rows("thermal")
    c = AXES.index(channel)
    sel = th[[int(np.argmax(np.abs(signed_axis(u)))) == c for u in th["up"]]] if len(th) else th
    ramp = sel[(sel["phase"] == "ramp") & (sel["rate_dps"] == 0)]
    if len(ramp) < 5:
        return None
    t_ref = float(readings.metadata.get("reference_c", 25.0))
    v_ref = float(readings.metadata.get("reference_v", 5.0))
    w_enu = np.degrees(earth_rate_enu(readings.latitude_deg))
    all_t = (sel["time_s"] + 0.5 * sel["duration_s"]).to_numpy()
    all_T = sel[col].to_numpy() - t_ref
    is_ramp = ((sel["phase"] == "ramp") & (sel["rate_dps"] == 0)).to_numpy()
    u = (ramp["supply_v"].to_numpy() - v_ref)
    theta = all_T[is_ramp]
    kk = scale.predict(theta, u)
    e = np.array([mean_earth_rate_ref(w_enu, r.up, r.north0, r.table_deg, 0.0, r.duration_s)[c]
                  for r in ramp.itertuples(index=False)])
    b_obs = ramp[OUT[c]].to_numpy() / kk - e
    resid = b_obs - bias.predict(theta, u)
    rms0 = float(np.sqrt(np.mean(resid ** 2)))
    dtdt = np.gradient(all_T, all_t)[is_ramp]
    x = dtdt[:, None]
    g, *_ = np.linalg.lstsq(x, resid, rcond=None)
    r1 = resid - x @ g
    s2 = float(r1 @ r1) / max(1, r1.size - 1)
    u_g = math.sqrt(s2 / float(x[:, 0] @ x[:, 0])) if np.any(x) else math.nan

    def cost_tau(tau_s):
        lag = _lagged(all_t, all_T, tau_s)[is_ramp]
        kl = scale.predict(lag, u)
        r = ramp[OUT[c]].to_numpy() / kl - e - bias.predict(lag, u)
        return float(r @ r)

    def cost(log_tau):
        return cost_tau(math.exp(log_tau))
    grid = np.linspace(math.log(1.0), math.log(1e4), 41)
    vals = [cost(v) for v in grid]
    j = int(np.argmin(vals))
    lo, hi = grid[max(0, j - 1)], grid[min(len(grid) - 1, j + 1)]
    opt = optimize.minimize_scalar(cost, bounds=(lo, hi), method="bounded",
                                   options={"xatol": 1e-4})
    tau, best = math.exp(opt.x), min(opt.fun, vals[j])
    if opt.fun > vals[j]:
        tau = math.exp(grid[j])
    c0 = cost_tau(0.0)
    if c0 <= best:
        tau, best = 0.0, c0
    rms_lag = math.sqrt(best / resid.size)
    lag = _lagged(all_t, all_T, tau)[is_ramp]
    r_lag = ramp[OUT[c]].to_numpy() / scale.predict(lag, u) - e - bias.predict(lag, u)
    t_lo, t_hi, resolved = lag_interval(cost, grid, vals, tau, best, c0,
                                        effective_blocks(r_lag))
    # hysteresis: bias on rising vs falling ramps at the same temperature (uses chamber
    # temperature as the abscissa, the quantity an operator sets)
    ch = ramp["chamber_c"].to_numpy()
    rising = dtdt > 0
    hyst = 0.0
    if rising.any() and (~rising).any():
        grid_t = np.linspace(max(ch[rising].min(), ch[~rising].min()),
                             min(ch[rising].max(), ch[~rising].max()), 50)
        if grid_t[-1] > grid_t[0]:
            o1, o2 = np.argsort(ch[rising]), np.argsort(ch[~rising])
            up_b = np.interp(grid_t, ch[rising][o1], b_obs[rising][o1])
            dn_b = np.interp(grid_t, ch[~rising][o2], b_obs[~rising][o2])
            hyst = float(np.max(np.abs(up_b - dn_b)))
    return RampAnalysis(channel, rms0, float(g[0]), u_g, float(np.sqrt(np.mean(r1 ** 2))), tau,
                        rms_lag, hyst, t_lo, t_hi, resolved, ramp["time_s"].tolist(),
                        theta.tolist(), dtdt.tolist(), b_obs.tolist(), resid.tolist())


def effective_blocks(resid) -> float:
    """Number of independent ramp blocks the residuals ``resid`` (in time order) are worth:
    n / (1 + 2 Σ_k ρ_k), the autocorrelations ρ_k summed while the sums of pairs
    ρ_{2m} + ρ_{2m+1} stay positive (Geyer's initial positive sequence, Statist. Sci. 1992).
    The bias instability's wander makes neighbouring 60 s blocks move together over many
    blocks, so the n blocks carry fewer independent errors. At least 2."""
    r = np.asarray(resid, float) - float(np.mean(resid))
    n = r.size
    den = float(r @ r)
    if den <= 0 or n < 4:
        return float(max(n, 2))
    rho = np.array([float(r[k:] @ r[:n - k]) / den for k in range(n // 2)])
    total = -1.0                        # Σ over pairs starts with ρ_0 = 1: 1 + 2Σρ_k = 2Σ − 1
    for m in range(rho.size // 2):
        pair = rho[2 * m] + rho[2 * m + 1]
        if pair <= 0:
            break
        total += 2.0 * pair
    return max(n / max(total, 1.0), 2.0)


def lag_interval(cost, grid, vals, tau: float, best: float, cost0: float, n: float
                 ) -> tuple[float, float, bool]:
    """95 % profile interval of the fitted lag τ: the τ whose residual sum of squares
    exceeds the minimum S by no more than S/(n − 1)·F₀.₉₅(1, n − 1) (the extra-sum-of-squares
    interval of one nonlinear parameter, Bates & Watts 1988 §6.1; n the ramp blocks'
    effective number, :func:`effective_blocks`). ``cost`` is
    the sum of squares against ln τ, ``grid``/``vals`` its values on the search grid
    (1 s … 10⁴ s), ``cost0`` that without a lag. Returns (τ_low, τ_high, resolved):
    ``resolved`` is False when no lag (τ = 0) is inside — the ramps then do not show a lag
    and τ̂ (often 0, the search's bound, or a few seconds of noise) is no measured value;
    τ_low = 0 then. τ_high = inf when the sum of squares stays under the threshold up to the
    grid's end (10⁴ s): the ramps bound τ on neither side. The certificate, the report and the
    figure state the interval, or 'not resolved' with the upper bound."""
    limit = best * (1.0 + float(stats.f.ppf(0.95, 1, max(n - 1, 1))) / max(n - 1, 1))
    resolved = cost0 > limit
    vals = np.asarray(vals, float)
    lt = math.log(tau) if tau > 0 else grid[0]

    def edge(side: int) -> float:
        idx = np.nonzero((vals > limit) & ((grid > lt) if side > 0 else (grid < lt)))[0]
        if idx.size == 0:
            return math.inf if side > 0 else 0.0
        k = int(idx[0] if side > 0 else idx[-1])
        inner = max(grid[k - 1], lt) if side > 0 else min(grid[k + 1], lt)
        if cost(inner) > limit:         # the threshold crossed between the grid points
            return float(math.exp(inner))
        return float(math.exp(optimize.brentq(lambda v: cost(v) - limit, *sorted((inner,
                                                                             grid[k])))))
    hi = edge(+1)
    lo = edge(-1) if resolved else 0.0
    return lo, hi, bool(resolved)


def flicker_lift_var(b_dps: float, n: int, fs_hz: float) -> float:
    """Expected sample variance ((°/s)²) that a bias instability B (flicker, one-sided PSD
    h/f with h = B²/π, IEEE 952 Annex C; the Allan floor 0.664·B) adds to the standard
    deviation of one record of ``n`` samples at ``fs_hz`` when its band reaches the Nyquist
    frequency: ∫₀^{fs/2} (h/f)·n/(n − 1)·(1 − D_n(f)²) df, D_n(f) = sin(π f n/fs)/(n sin(π f/fs))
    the transfer of the record's mean (the sample variance keeps what the mean does not).
    The largest lift a flicker of that B can give the record; none where its band ends below
    1/(record length).

    >>> v = flicker_lift_var(1.0, 600, 10.0)          # B = 1 °/s, 60 s at 10 Hz
    >>> round(v * math.pi, 2)                          # the integral, in units of h
    6.63
    """
    if not (b_dps > 0 and n > 1 and fs_hz > 0):
        return 0.0
    lnf = np.linspace(math.log(fs_hz / 2.0) - math.log(1e5 * n), math.log(fs_hz / 2.0), 20001)
    x = np.pi * np.exp(lnf) / fs_hz
    d = np.sin(n * x) / (n * np.sin(x))
    g = n / (n - 1.0) * (1.0 - d * d)
    integral = float(np.sum(0.5 * (g[1:] + g[:-1]) * np.diff(lnf)))    # ∫ (…) d ln f
    return b_dps ** 2 / math.pi * integral


# --------------------------------------------------------------------------- model
@dataclass
class ChannelModel:
    """The identified model of one gyro."""

    channel: str
    scale: PolyFit
    bias: PolyFit
    arw: PolyFit | None
    ramp: RampAnalysis | None
    points: pd.DataFrame
    temperature: str
    theta_range: tuple
    u_range: tuple

    def prediction_grid(self, n: int = 26) -> pd.DataFrame:
        """Predicted K, b, ARW and their standard uncertainties across the operating range
        (ϑ over the identified range, at U = min, 0, max)."""
        th = np.linspace(self.theta_range[0], self.theta_range[1], n)
        rows = []
        for u in sorted({self.u_range[0], 0.0, self.u_range[1]}):
            for t, k, uk, b, ub in zip(th, self.scale.predict(th, u), self.scale.u_predict(th, u),
                                       self.bias.predict(th, u), self.bias.u_predict(th, u)):
                rows.append({"theta_c": float(t), "u_v": float(u), "scale": float(k),
                             "u_scale": float(uk), "bias_dps": float(b), "u_bias_dps": float(ub)})
        df = pd.DataFrame(rows)
        if self.arw is not None:
            df["arw_deg_sqrt_h"] = self.arw.predict(df["theta_c"].to_numpy())
            df["u_arw_deg_sqrt_h"] = self.arw.u_predict(df["theta_c"].to_numpy())
        return df

    def certified_points(self, reference_c: float, reference_v: float) -> list[dict]:
        """The certified values: K(ϑ, U) and b(ϑ, U) at every chamber set point of the
        programme (soaked; the chamber temperature rounded to 0.1 °C) and every supply level,
        ARW(ϑ) at every set point — fixed measurands, whatever orders the criterion chose.
        With the sensor temperature as input the model is evaluated at the sensor's reading
        of the soaked set point: the soak's mean (sensor − chamber) added to the set point,
        so a chamber that settled a little off its set point does not move the measurand;
        that mean's Type A uncertainty (``u_theta_c``, ν = points − 1) enters through the
        model's slope. Each entry: t, v (1-based indices, ascending), setpoint_c, supply_v,
        theta_c, u_v (the model's coordinates), u_theta_c, nu_theta and, per model, the
        :meth:`PolyFit.point` record with the slope."""
        pts = self.points
        sp = np.round(pts["chamber_c"].to_numpy(float), 1)
        off = pts["theta_c"].to_numpy(float) - (pts["chamber_c"].to_numpy(float) - reference_c)
        levels = sorted({round(float(v), 6) for v in pts["u_v"]})
        out = []
        for i, t_set in enumerate(sorted(set(sp.tolist())), 1):
            o = off[sp == t_set]
            theta = float(np.mean(o)) + t_set - reference_c
            u_th = float(np.std(o, ddof=1) / math.sqrt(o.size)) if o.size > 1 else 0.0
            fits = [("K", self.scale, levels), ("b", self.bias, levels)]
            if self.arw is not None:
                fits.append(("ARW", self.arw, [0.0]))
            for name, fit, us in fits:
                for j, uv in enumerate(us, 1):
                    rec = fit.point(theta, uv)
                    rec["slope"] = float((fit.predict(theta + 0.01, uv)[0]
                                          - fit.predict(theta - 0.01, uv)[0]) / 0.02)
                    if name == "ARW":
                        rec["u_chi2"], rec["nu_chi2"] = self.arw_chi2(theta)
                        rec["n_samples"] = int(np.median(self.points["arw_n"][self.points["arw_n"] > 1]))
                        rec["fs_hz"] = float(self.points["arw_fs_hz"].iloc[0])
                    out.append({"model": name, "t": i, "v": j if name != "ARW" else 0,
                                "setpoint_c": float(t_set),
                                "supply_v": None if name == "ARW" else float(uv + reference_v),
                                "theta_c": theta, "u_v": float(uv), "u_theta_c": u_th,
                                "nu_theta": float(o.size - 1), **rec})
        return out

    def arw_chi2(self, theta: float) -> tuple[float, float]:
        """(u, ν) of the fitted ARW(ϑ) at ``theta`` from the white rate noise the procedure
        assumes at the sample interval: each static dwell's ARW is s·√τ0/K with s the sample
        standard deviation of its n samples, s²(n − 1)/σ² a χ² with ν_i = n − 1, so
        u(ARW_i) = ARW_i/√(2ν_i) (JCGM 100 E.4.3; the fitted ARW_i in place of the reading).
        The value at ϑ is Σ_i w_i ARW_i with w the least-squares weights gᵀ(XᵀX)⁻¹Xᵀ of the
        selected order, so u² = Σ_i w_i² ARW_i²/(2ν_i) and ν = ½(ARW(ϑ)/u)² (the ν of a standard
        deviation of that spread). The between-dwell scatter of the fit's residuals estimates
        the same spread with a few degrees of freedom; the χ² gives it with the dwells' own."""
        f = self.arw
        pts = self.points[np.isfinite(self.points["arw_deg_sqrt_h"].to_numpy(float))
                          & (self.points["arw_n"].to_numpy() > 1)]
        if f is None or pts.empty:
            return 0.0, math.inf
        x = design(pts["theta_c"].to_numpy(float) / f.scale_t, np.zeros(len(pts)), f.n_t, 0)
        g = design(np.atleast_1d(float(theta)) / f.scale_t, np.zeros(1), f.n_t, 0)[0]
        w = g @ np.linalg.pinv(x)
        fitted = x @ f.coef
        var = float(np.sum(w ** 2 * fitted ** 2 / (2.0 * (pts["arw_n"].to_numpy(float) - 1.0))))
        value = float(f.predict(theta)[0])
        u = math.sqrt(max(var, 0.0))
        return u, (0.5 * (value / u) ** 2 if u > 0 else math.inf)

    def compensate(self, outputs, theta_c, u_v=0.0, dtheta_dt=None) -> np.ndarray:
        """ω̂ = y/K̂(ϑ, U) − b̂(ϑ, U) (− γ dϑ/dt when given and a ramp term was fitted), °/s."""
        y = np.asarray(outputs, float)
        w = y / self.scale.predict(theta_c, u_v) - self.bias.predict(theta_c, u_v)
        if dtheta_dt is not None and self.ramp is not None:
            w = w - self.ramp.gamma_dps_per_c_per_s * np.asarray(dtheta_dt, float)
        return w

    def to_json(self) -> dict:
        return {"channel": self.channel, "temperature_source": self.temperature,
                "theta_range_c": list(self.theta_range), "supply_range_v": list(self.u_range),
                "scale": self.scale.to_json(), "bias": self.bias.to_json(),
                "arw": None if self.arw is None else self.arw.to_json(),
                "ramp": None if self.ramp is None else self.ramp.to_json(),
                "prediction": self.prediction_grid(9).to_dict(orient="list")}


@dataclass
class ThermalModelResult:
    """Identified models, one per gyro whose input axis was on the table axis."""

    channels: dict
    reference_c: float
    reference_v: float
    criterion: str
    output_unit: str = ""

    def to_json(self) -> dict:
        return {"kind": "thermal-model", "reference_c": self.reference_c,
                "reference_v": self.reference_v, "criterion": self.criterion,
                "output_unit": self.output_unit,
                "channels": {k: dict(v.to_json(), certified_points=v.certified_points(
                    self.reference_c, self.reference_v)) for k, v in self.channels.items()}}


def check_temperature_span(theta_c: np.ndarray, channel: str, readings: TriadReadings) -> None:
    """GonioError unless the soak points of a gyro hold at least two temperatures (1 °C
    apart) and bracket the reference temperature (ϑ = 0): a model from one temperature, or
    its value at a reference outside the temperatures soaked, is an extrapolation that
    would be certified as a measurement (−40 °C only gave K at 25 °C as
    49.10 ± 0.39 against 49.69)."""
    ref = float(readings.metadata.get("reference_c", 25.0))
    levels = np.unique(np.round(theta_c))
    lo, hi = float(theta_c.min()) + ref, float(theta_c.max()) + ref
    if levels.size < 2:
        raise GonioError(f"gyro {channel}: the thermal programme holds one temperature "
                         f"({lo:.1f} °C); a temperature model needs at least two",
                         file=readings.path)
    if not theta_c.min() <= 0.0 <= theta_c.max():
        raise GonioError(f"gyro {channel}: the reference {ref:g} °C lies outside the "
                         f"temperatures soaked ({lo:.1f} … {hi:.1f} °C); the model there "
                         "would be an extrapolation", file=readings.path, key="reference_c")


def identify_thermal_model(readings: TriadReadings, *, criterion: str = "bic",
                           temperature: str = "sensor", max_order_t: int = MAX_ORDER_T,
                           max_order_u: int = MAX_ORDER_U, max_order_arw: int = MAX_ORDER_ARW,
                           fixed_orders: dict | None = None,
                           ramps: bool = True) -> ThermalModelResult:
    """Identify K(ϑ, U), b(ϑ, U), ARW(ϑ) for every gyro the thermal rows exercise
    (module docstring, steps 1–4). ``fixed_orders`` ({"scale": (n_t, n_u), "bias": …,
    "arw": (n_t, 0)}) bypasses the order selection for the parts it names; ``ramps=False``
    skips step 4."""
    fo = fixed_orders or {}
    pts = soak_points(readings, temperature=temperature)
    out = {}
    for ch, grp in pts.groupby("channel", sort=True):
        check_temperature_span(grp["theta_c"].to_numpy(float), ch, readings)
        kf = fit_polynomial(f"K_{ch}", grp["theta_c"], grp["u_v"], grp["scale"],
                            criterion=criterion, max_t=max_order_t, max_u=max_order_u,
                            orders=fo.get("scale"), soak=grp["soak"])
        bf = fit_polynomial(f"b_{ch}", grp["theta_c"], grp["u_v"], grp["bias_dps"],
                            criterion=criterion, max_t=max_order_t, max_u=max_order_u,
                            orders=fo.get("bias"), soak=grp["soak"])
        arw = grp.dropna(subset=["arw_deg_sqrt_h"])
        af = None
        if len(arw) >= 3:
            af = fit_polynomial(f"ARW_{ch}", arw["theta_c"], np.zeros(len(arw)),
                                arw["arw_deg_sqrt_h"], criterion=criterion, max_t=max_order_arw,
                                max_u=0, orders=fo.get("arw"), soak=arw["soak"])
        ra = ramp_analysis(readings, kf, bf, ch, temperature=temperature) if ramps else None
        out[ch] = ChannelModel(ch, kf, bf, af, ra, grp.reset_index(drop=True), temperature,
                               (float(grp["theta_c"].min()), float(grp["theta_c"].max())),
                               (float(grp["u_v"].min()), float(grp["u_v"].max())))
    return ThermalModelResult(out, float(readings.metadata.get("reference_c", 25.0)),
                              float(readings.metadata.get("reference_v", 5.0)), criterion,
                              readings.metadata.get("output_unit", ""))


@dataclass
class Compensation:
    """Residual bias and scale-factor errors of a new record, before and after."""

    channel: str
    points: pd.DataFrame          # theta_c, u_v, bias/scale errors before and after
    rms_bias_before_dps: float
    rms_bias_after_dps: float
    rms_scale_before_rel: float
    rms_scale_after_rel: float
    rms_ramp_before_dps: float
    rms_ramp_after_dps: float

    def to_json(self) -> dict:
        d = {k: v for k, v in self.__dict__.items() if k != "points"}
        d["points"] = self.points.to_dict(orient="list")
        return d


def compensate_record(model: ChannelModel, readings: TriadReadings) -> Compensation:
    """Apply an identified model to a new thermal record (module step 5).

    "Before" uses the constant reference-condition values k0 = K̂(0, 0), b0 = b̂(0, 0);
    "after" the full model at each point's ϑ and U. Ramp blocks (static) are compared the
    same way for the bias (with the ramp term when the model has one).
    """
    pts = soak_points(readings, temperature=model.temperature)
    pts = pts[pts["channel"] == model.channel]
    if pts.empty:
        raise GonioError(f"{readings.path}: no soak pairs for gyro {model.channel}")
    k0 = float(model.scale.predict(0.0, 0.0)[0])
    b0 = float(model.bias.predict(0.0, 0.0)[0])
    kh = model.scale.predict(pts["theta_c"], pts["u_v"])
    bh = model.bias.predict(pts["theta_c"], pts["u_v"])
    df = pd.DataFrame({"theta_c": pts["theta_c"], "u_v": pts["u_v"],
                       "bias_before_dps": pts["bias_dps"] - b0,
                       "bias_after_dps": pts["bias_dps"] - bh,
                       "scale_before_rel": pts["scale"] / k0 - 1.0,
                       "scale_after_rel": pts["scale"] / kh - 1.0}).reset_index(drop=True)
    rb = ra = math.nan
    ramp = ramp_analysis(readings, model.scale, model.bias, model.channel,
                         temperature=model.temperature)
    if ramp is not None:
        bo = np.asarray(ramp.bias_dps)
        rb = float(np.sqrt(np.mean((bo - b0) ** 2)))
        res = np.asarray(ramp.residual_dps)
        if model.ramp is not None:
            res = res - model.ramp.gamma_dps_per_c_per_s * np.asarray(ramp.dtheta_dt)
        ra = float(np.sqrt(np.mean(res ** 2)))

    def rms(a):
        return float(np.sqrt(np.mean(np.asarray(a) ** 2)))
    return Compensation(model.channel, df, rms(df["bias_before_dps"]), rms(df["bias_after_dps"]),
                        rms(df["scale_before_rel"]), rms(df["scale_after_rel"]), rb, ra)
