"""Coverage of the Welch–Satterthwaite interval (JCGM 100 G.4) for a budget of the shape of
JJF 1535 7.2.1's scale factor: a normal Type B line u₁ (the rate table's certificate), a
small normal Type B line u₂ (acquisition) and a Type A line s/√Q of ν = Q − 1 (the Q
calibrations' scatter), with k = t₉₅(ν_eff) and U = k·u_c.

Everything is drawn from its stated law (the Type B errors normal with their u, the Q
calibrations normal with σ, s² = σ²·χ²_ν/ν), so the coverage printed is the interval rule's
own, not gonio's: the rule alone falls short of 95 % where the Type A line carries a large
share of u_c with few degrees of freedom (u_c small exactly where s happens to be small).
Read beside docs/validation-rate.md's JJF 7.2.1 rows.

    python scripts/ws_type_a_coverage.py [--q 3] [--draws 400000] [--seed 1]
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.stats import norm, t as student_t


def coverage(ratio: float, q: int, draws: int, rng, u2_rel: float = 0.12
             ) -> tuple[float, float, float]:
    """(coverage with ν_eff as gonio states it — its integer part, ∞ above 1000 — coverage
    with the non-integer ν_eff, sd of z = error/u_c) of U = t₉₅(ν)·u_c where the Type A
    line's σ/√Q is ``ratio`` times u₁ (u₁ = 1, u₂ = ``u2_rel``)."""
    u1, u2, sa = 1.0, u2_rel, ratio * np.sqrt(q)
    err = rng.normal(0, u1, draws) + rng.normal(0, u2, draws) + rng.normal(0, sa / np.sqrt(q), draws)
    s2 = sa ** 2 * rng.chisquare(q - 1, draws) / (q - 1)
    ua2 = s2 / q
    uc = np.sqrt(u1 ** 2 + u2 ** 2 + ua2)
    with np.errstate(divide="ignore"):              # no Type A line: ν_eff = ∞
        nu = uc ** 4 / (ua2 ** 2 / (q - 1))
    nu_s = np.where(nu > 1000, np.inf, np.floor(nu))      # gonio's stated ν (coverage_k)
    k = np.where(np.isinf(nu_s), norm.ppf(0.975), student_t.ppf(0.975, np.where(np.isinf(nu_s), 1, nu_s)))
    k_exact = student_t.ppf(0.975, nu)
    return float(np.mean(np.abs(err) <= k * uc)), float(np.mean(np.abs(err) <= k_exact * uc)), \
        float(np.std(err / uc))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--q", type=int, default=3)
    ap.add_argument("--draws", type=int, default=400_000)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    print(f"Welch–Satterthwaite interval, Q = {a.q} (Type A ν = {a.q - 1}), {a.draws} draws, "
          f"seed {a.seed}")
    print("σ_A/√Q over u₁   coverage, ν stated (integer part)   with ν_eff exact   sd z")
    for ratio in (0.0, 0.3, 0.6, 0.76, 1.0, 1.33, 2.0, 3.0, 5.0, 10.0):
        c, ce, sd = coverage(ratio, a.q, a.draws, rng)
        print(f"{ratio:14.2f}   {c:33.4f}   {ce:16.4f}   {sd:5.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
