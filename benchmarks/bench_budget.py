"""Benchmark: JCGM 101 Monte Carlo and GUM evaluation of the draft's Annex A budget.

Prints (best of several runs):
- our MC of Δ = (φ_e + B_E) − P + r with 10⁶ trials (samples, model, mean, u, 95 % interval);
- the full GUM evaluation ``annex_a_budget()`` (target < 50 ms; sympy lambdification cached);
- if ``suncal`` is importable (``pip install suncal``; benchmark only, never a dependency),
  suncal's MC of the same model with its symmetric 95 % interval, and the ratio
  (target: ours >= 1.5x faster).

Run: ``python benchmarks/bench_budget.py [--trials N] [--repeat R]``
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a checkout

from gonio.specs.ogam_draft.budget import annex_a_budget, annex_a_model  # noqa: E402
from uncertainty import from_u, monte_carlo, type_b  # noqa: E402


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()

    b = annex_a_budget()
    phi_half = b.gum.contributions[1].half_width
    inputs = [type_b("P", 0.0, 0.1, "rectangular"), type_b("phi_e", 0.0, phi_half, "rectangular"),
              type_b("B_E", 0.0, 0.15, "rectangular"), from_u("r", 0.0, 0.096)]
    model = annex_a_model()
    monte_carlo(model, inputs, 1000, seed=0)  # warm the lambdify cache

    t_mc = best_of(lambda: monte_carlo(model, inputs, a.trials, seed=0), a.repeat)
    r = monte_carlo(model, inputs, a.trials, seed=0)
    print(f"ours   MC  {a.trials:>9d} trials: {t_mc * 1e3:8.1f} ms   u = {r.u:.5f}\u2033, "
          f"95 % [{r.low:.4f}, {r.high:.4f}]\u2033")

    t_gum = best_of(annex_a_budget, max(a.repeat, 20))
    print(f"ours   GUM annex_a_budget():    {t_gum * 1e3:8.3f} ms   u_c = {b.u_c_arcsec:.4f}\u2033 "
          f"(target < 50 ms: {'met' if t_gum < 0.05 else 'NOT met'})")
    t_full = best_of(lambda: annex_a_budget(monte_carlo_trials=a.trials), a.repeat)
    print(f"ours   GUM + MC + validation:   {t_full * 1e3:8.1f} ms")

    try:
        import suncal  # benchmark-only peer
    except ImportError:
        print("suncal not installed (pip install suncal): no comparison")
        return
    m = suncal.Model("Delta = phi_e + B_E - P + r")
    m.var("P").measure(0).typeb(dist="uniform", a=0.1)
    m.var("phi_e").measure(0).typeb(dist="uniform", a=phi_half)
    m.var("B_E").measure(0).typeb(dist="uniform", a=0.15)
    m.var("r").measure(0).typeb(dist="normal", std=0.096)

    def suncal_mc():
        res = m.monte_carlo(samples=a.trials)
        return res, res.expanded(conf=0.95)

    t_sc = best_of(suncal_mc, a.repeat)
    res, exp = suncal_mc()
    print(f"suncal {suncal.version.__version__} MC {a.trials:>9d} trials: {t_sc * 1e3:8.1f} ms   "
          f"u = {float(res.uncertainty['Delta']):.5f}\u2033")
    ratio = t_sc / t_mc
    print(f"ratio suncal / ours: {ratio:.2f}x (target >= 1.5x: {'met' if ratio >= 1.5 else 'NOT met'})")


if __name__ == "__main__":
    main()
