"""JJF 1535-2015 Annex A reproduced: the scale-factor (A.1) and bias (A.2) budgets.

A.1 model K = (F − F_0 − v)/Ω; relative components u₁ (rate table, U_rel = 5×10⁻⁴, k = 2),
u₂ (acquisition, 6½-digit voltmeter, U_rel = 6×10⁻⁵, k = 2), u₃ (repeatability,
4.65×10⁻⁴, the annex's value for its gyro model); u_c = 5.29×10⁻⁴, U_rel = 1.1×10⁻³ (k = 2).
A.2 model B_0 = F/K; components: acquisition 3.0×10⁻⁵ and the scale factor's u_c
5.29×10⁻⁴ (the rounded A.1.3 value, as the annex does); u_c = 5.30×10⁻⁴, U = 1.1×10⁻³.

Readings taken on the annex's slips (each also in :data:`ANNEX_SLIPS`): "航姿仪输出"
(AHRS output) in A.1.1 is the gyro output; v has no term and u(F_0) no value; A.2.2's
first component is headed u₁ but computed as "u₂ = U_rel/2"; A.2.4's "U" is relative.
The propagation goes through the package's GUM engine (:mod:`uncertainty`), so the
printed digits are reproduced by the same code that computes real budgets.
"""

from __future__ import annotations

from dataclasses import dataclass

from gonio.result.statement import rounded
from uncertainty import from_u, propagate, type_b

#: The annex's slips and the readings taken.
ANNEX_SLIPS: tuple[str, ...] = (
    "A.1.1: the output is printed as '航姿仪输出' (AHRS output), a copy-over slip; read: the "
    "gyro output F.",
    "A.1.1: the residual v appears in the model without a sensitivity coefficient or a value, "
    "and u(F_0) is given no value; read: both are absorbed in the repeatability u3.",
    "A.1.2: u1 stands for u(Ω)/Ω and u2 for u(F)/(F − F_0) (relative components).",
    "A.2.2: the acquisition component is headed 'u1' but computed as 'u2 = U_rel/2'; read: "
    "u1 = 3.0e-5 (acquisition), u2 = 5.29e-4 (scale factor).",
    "A.2.2: u(K) is the relative combined (not expanded) uncertainty of A.1.3, rounded.",
    "A.2.4: 'U = 1.1e-3' is a relative expanded uncertainty (U_rel).",
    "A.1 and A.2 are relative budgets: a bias near zero would get a vanishing uncertainty; "
    "the package's own bias budget adds absolute components (type A scatter, Earth-rate "
    "projection) — its extension, not the annex's.",
)


@dataclass(frozen=True)
class AnnexBudget:
    """One reproduced budget: components (symbol, source, u), u_c, U (k = 2), stated values."""

    name: str
    components: tuple[tuple[str, str, float], ...]
    u_c: float
    k: float
    U: float
    u_c_stated: float
    U_stated: float

    def to_dict(self) -> dict:
        return {"name": self.name,
                "components": [{"symbol": s, "source": src, "u_rel": u}
                               for s, src, u in self.components],
                "u_c_rel": self.u_c, "k": self.k, "U_rel": self.U,
                "u_c_rel_stated": self.u_c_stated, "U_rel_stated": self.U_stated}


@dataclass(frozen=True)
class AnnexA:
    """JJF 1535 Annex A: the A.1 scale-factor and A.2 bias budgets and the slips."""

    scale_factor: AnnexBudget
    bias: AnnexBudget
    slips: tuple[str, ...] = ANNEX_SLIPS

    def to_dict(self) -> dict:
        return {"scale_factor": self.scale_factor.to_dict(), "bias": self.bias.to_dict(),
                "readings_taken": list(self.slips)}

    def to_text(self) -> str:
        out = []
        for b in (self.scale_factor, self.bias):
            out.append(f"{b.name}")
            for s, src, u in b.components:
                out.append(f"  {s:4s} {u:.3e}  {src}")
            out.append(f"  u_c = {b.u_c:.4e}  (stated {b.u_c_stated:.3g})")
            out.append(f"  U_rel = {b.U:.4e}, k = {b.k:g}  (stated {b.U_stated:.2g})")
        out.append("Readings taken on the annex's slips:")
        out += [f"  - {s}" for s in self.slips]
        return "\n".join(out) + "\n"


def annex_a(*, table_U_rel: float = 5e-4, acquisition_U_rel: float = 6e-5,
            repeatability_rel: float = 4.65e-4, k: float = 2.0) -> AnnexA:
    """Reproduce JJF 1535 Annex A (A.1.2–A.1.4, A.2.2–A.2.4) with the GUM engine.

    >>> a = annex_a()
    >>> [f"{u:.2e}" for _, _, u in a.scale_factor.components]
    ['2.50e-04', '3.00e-05', '4.65e-04']
    >>> f"{a.scale_factor.u_c:.3e}", f"{a.scale_factor.U:.3e}", a.scale_factor.U_stated
    ('5.288e-04', '1.058e-03', 0.0011)
    >>> f"{a.bias.u_c:.4e}", f"{a.bias.u_c_stated:.3g}", a.bias.U_stated
    ('5.2985e-04', '0.00053', 0.0011)
    """
    # A.1: relative model k/K = (1 + e_F)(1 + r)/(1 + e_Ω) about the estimate
    q = [type_b("u1", 0.0, table_U_rel, "normal", k=2, source="rate table (U_rel, k = 2)"),
         type_b("u2", 0.0, acquisition_U_rel, "normal", k=2,
                source="data acquisition, 6½-digit voltmeter (U_rel, k = 2)"),
         from_u("u3", 0.0, repeatability_rel, type="A", source="measurement repeatability")]
    r1 = propagate(lambda e_om, e_f, rep: (1 + e_f) * (1 + rep) / (1 + e_om), q, k=k)
    sf = AnnexBudget("A.1 scale factor K (relative)",
                     tuple((c.symbol, c.source, c.u_xi) for c in r1.contributions),
                     r1.u_c, k, r1.U, rounded(r1.u_c, 3), rounded(r1.U, 2))
    # A.2: B0 = F/K; u(K)/K = the rounded A.1.3 value (as the annex does)
    uK = rounded(r1.u_c, 3)
    q2 = [type_b("u1", 0.0, acquisition_U_rel, "normal", k=2,
                 source="data acquisition (printed heading u1, computed as u2)"),
          from_u("u2", 0.0, uK, type="B", source="scale factor, u_c(K)/K of A.1.3")]
    r2 = propagate(lambda e_f, e_k: (1 + e_f) / (1 + e_k), q2, k=k)
    bias = AnnexBudget("A.2 bias B_0 (relative)",
                       tuple((c.symbol, c.source, c.u_xi) for c in r2.contributions),
                       r2.u_c, k, r2.U, rounded(r2.u_c, 3), rounded(r2.U, 2))
    return AnnexA(sf, bias)
