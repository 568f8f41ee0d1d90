"""JJF 1535 7.2.6 / 7.2.7: the level z of the threshold's and resolution's stated outcome
distribution, as certified (the plug-in: the rule's outcome under the data's noise about the
MEASURED responses) and as the distribution of the measurand given the measured responses
(the median outcome under the noise about the EXACT responses μ, μ from a flat prior,
:func:`median_outcome_distribution` below) — the second was tried as the fix of the plug-in's
level z (mean +0.94 / +1.22) and is NOT used: on the study bench it is worse (see
docs/validation-rate.md, "JJF 7.2.6/7.2.7: the measurand's distribution tried").

    python scripts/jjf_rule_outcome_study.py [--trials 40] [--seed 11]

Each trial is the study's own (``SPEC.run_trial`` on the study bench and protocol, trial i
seeded by SeedSequence(seed, spawn_key=(i,))), calibrated for K, 7.2.6 and 7.2.7 only, and
judged by the study's level z (``gonio.pipeline.coverage.trial_records``, the randomised PIT
of the truth in the stated distribution). Prints the level z's mean and sd per item and
distribution.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import gonio.specs.jjf1535.items as I
from gonio.pipeline import coverage as cv
from gonio.specs import get
from gonio.specs._rate_family import formulas as rg


def median_outcome_distribution(runs, *, limit: float = 0.5, nodes: int = 2000,
                                bins: int = 8192) -> dict:
    """JJF 1535 7.2.6 / 7.2.7 (eqs (13), (14), two-sided 50 % rule; the reading of
    docs/jjf1535-readings.md): the distribution of the measurand — the median of the larger
    direction's rule outcome under the noise of each referred mean about the gyro's EXACT
    responses μ — given the measured responses, not the outcome's distribution about the
    measured ones (that plug-in adds the noise a second time: too wide, shifted to larger
    steps).

    Derivation. In one run, with steps |s_1| > |s_2| > … walked in that order, the outcome is
    at or below |s_i| exactly when steps 1…i all pass; steps pass independently with
    p_j(μ_j) = Φ((e_j + l|e_j| − μ_j)/σ_j) − Φ((e_j − l|e_j| − μ_j)/σ_j). The larger of the
    runs' outcomes is at or below k with G_k(μ) = Π_runs Π_{|s_j| ≥ k} p_j(μ_j), and its median
    T(μ) is at or below k exactly when G_k(μ) ≥ ½, i.e. when Σ L_j ≤ ln 2 with
    L_j = −ln p_j(μ_j) ≥ 0. Given the measured mean m_j with standard deviation σ_j on ν_j
    degrees of freedom, μ_j = m_j + σ_j·t_ν (JCGM 101 6.4.9: the state of knowledge of a
    mean from n readings; normal for ν = ∞), independent across steps. So
    P(T ≤ k) = P(Σ_{|s_j| ≥ k} L_j ≤ ln 2): each L_j's distribution by ``nodes`` equal-
    probability nodes of t_ν, summed by convolution on ``bins`` cells of [0, ln 2] (mass
    above ln 2 leaves: the step set fails). "None" (above the grid) is T above the largest
    step. ``runs``: [(steps, measured, sigmas, expected, dofs), …] per direction.

    >>> d = median_outcome_distribution([([0.1, 0.05], [0.1, 0.05], [0.0, 0.0], [0.1, 0.05], [9, 9])])
    >>> {k: round(v, 6) for k, v in d.items()}     # no noise: the walk's outcome
    {0.1: 0.0, 0.05: 1.0}
    """
    from scipy import stats

    h = math.log(2.0) / bins
    items = []                                       # (|step|, L nodes) of every step
    q = (np.arange(nodes) + 0.5) / nodes
    for steps, meas, sig, exp, dof in runs:
        for st, m, s, e, nu in zip(steps, meas, sig, exp, dof):
            s, e = float(s), float(e)
            if s > 0:
                x = stats.norm.ppf(q) if not math.isfinite(nu) else stats.t.ppf(q, nu)
                mu = float(m) + s * x
                p = rg.fifty_percent_pass_probability(mu, s, np.full(mu.shape, e), limit=limit)
            else:
                p = rg.fifty_percent_pass_probability([m], [0.0], [e], limit=limit)
            with np.errstate(divide="ignore"):
                L = -np.log(np.clip(p, 0.0, 1.0))
            items.append((abs(float(st)), L))
    items.sort(key=lambda t: -t[0])
    dist = np.zeros(bins + 1)
    dist[0] = 1.0                                   # the empty sum
    G, i = {}, 0
    while i < len(items):
        k = items[i][0]
        while i < len(items) and items[i][0] == k:
            L = items[i][1]
            cell = np.rint(L[np.isfinite(L)] / h)
            cell = cell[cell <= bins].astype(int)
            step = np.bincount(cell) / L.size if cell.size else np.zeros(1)
            dist = np.convolve(dist, step)[:bins + 1]
            i += 1
        G[k] = float(dist.sum())                     # P(T ≤ k)
    keys = sorted(G, reverse=True)
    pmf = {None: max(1.0 - G[keys[0]], 0.0)}
    for a, b in zip(keys, keys[1:] + [None]):
        pmf[a] = max(G[a] - (G[b] if b is not None else 0.0), 0.0)
    return {k: v for k, v in pmf.items() if v > 0 or k is not None}   # every tested step


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--seed", type=int, default=11)
    a = ap.parse_args()
    keep = ("threshold", "resolution")
    I.ITEMS = [r for r in I.ITEMS if r[0] in keep + ("scale_factor",)]
    stash: list = []
    rule_run, plugin = I._rule_run, rg.rule_outcome_uncertainty

    def spy_run(steps, meas, exp, sig, cands, pmfs):
        stash.append((steps, meas, [x for x, _ in sig], exp, [n for _, n in sig]))
        return rule_run(steps, meas, exp, sig, cands, pmfs)

    def posterior(pmfs, value):
        runs = list(stash)
        stash.clear()
        return plugin([median_outcome_distribution(runs)], value)

    def as_certified(pmfs, value):
        stash.clear()
        return plugin(pmfs, value)

    I._rule_run = spy_run
    spec = get("jjf1535-2015")
    bench = cv.study_bench(spec)
    proto, _ = cv._study_protocol(spec, None)
    for name, fn in (("as certified (plug-in)", as_certified),
                     ("measurand's distribution (posterior)", posterior)):
        rg.rule_outcome_uncertainty = fn
        z = {k: [] for k in keep}
        hits = {k: 0 for k in keep}
        for i in range(a.trials):
            s = int(np.random.SeedSequence(a.seed, spawn_key=(i,)).generate_state(1)[0])
            rec = cv.trial_records(spec.key, bench, proto, s)
            for k in keep:
                r = rec[k]
                if r.get("z_level") is not None:
                    z[k].append(r["z_level"])
                    lo, hi = r["interval"]
                    hits[k] += lo <= r["truth"] <= hi
        for k in keep:
            v = np.array(z[k])
            print(f"{name:38s} {k:10s} n {v.size}  cover {hits[k] / max(v.size, 1):.3f}  "
                  f"level z mean {v.mean():+.2f} sd {v.std(ddof=1):.2f}")


if __name__ == "__main__":
    main()
