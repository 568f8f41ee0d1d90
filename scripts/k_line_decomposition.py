"""K's (7.1) and K_l's (7.2) budget lines against the spread of the effects they budget,
on the optical study's trials, and the closed form of what a table line on the MPE alone
can reach.

    python scripts/k_line_decomposition.py [--case typeb] [--trials 40] [--seed 20261129]
                                           [--sample-rate-hz 5]

Each trial is the one ``gonio validate --spec ogam-draft --cases CASE --trials N --seed S
--all-items --sample-rate-hz R`` runs (the same trial seeds, protocol and drawn bench),
calibrated as the study does. Prints, over the trials:

- K's lines: the mean u of each (ppm of K) and its share of u_c²;
- K's table error on the trial's drawn table, exactly: Σ_p c_p e(p) over the positions the
  7.1 rounds reach (``item_uncertainty.scale_factor_table_coefficients``, e the drawn
  table's error there), its rms and largest, beside the line's u;
- K's error (value − truth, ppm), its rms with and without the table's part, z =
  (value − truth)/u_c (mean, sd) and coverage |value − truth| ≤ k·u_c;
- the same z and coverage with ``P_K`` replaced by two other readings of the MPE (beside,
  not stated): the positions independent (``scale_factor_table_u_rel``) and the draft's
  A.4.1 read as a bound on the angle turned from the table's zero, the zero's own error not
  counted (MPE·Σ_stops|c_p|/√3);
- the closed form: the corner table moves K by a = MPE·Σ|c_p| (the line's half-width); a
  statement that holds it at the stated k needs u_c ≥ a/k, so on tables that move K by an
  rms σ the z sd is at most k·σ/a (the table at the MPE) — the largest z sd a statement
  holding every allowed table can have on those tables;
- K_l's lines (``K_rng``, ``K_tab``, ppm), its error's sd, z (mean, sd), and the same
  closed form with its worst range shift D (``K_tab``'s half-width).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from gonio.specs.ogam_draft import study
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.bench.instrument import harmonic_sum_arcsec
from gonio.specs.ogam_draft.calibration import analyse
from gonio.specs.ogam_draft.item_coverage import item_record
from gonio.specs.ogam_draft.item_uncertainty import (scale_factor_table_bound_rel,
                                                     scale_factor_table_u_rel)
from gonio.specs.ogam_draft.readings import Readings
from gonio.units import PPM


def _stops_only_u_rel(coef: dict, mpe: float) -> float:
    """The draft's A.4.1 read as a bound on the angle from the table's zero: the 0° position
    carries no error of its own; every other position's within ±MPE, worst combination."""
    return mpe * sum(abs(c) for p, c in coef.items() if p != 0.0) / math.sqrt(3.0)


def trial(proto, base, case: str, seed: int, coef: dict) -> dict:
    tb = study.trial_bench(case, base, proto, seed)
    pos = np.array(sorted(coef))
    tab = float(np.array([coef[p] for p in pos]) @ harmonic_sum_arcsec(
        pos, tb.table.positioning_harmonics)) / PPM
    res = run_session(proto, tb, seed=seed)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    rep = analyse(Readings(df, dict(res.metadata)), proto, budget="draft",
                  static_record=res.static_record)
    rec = item_record(rep, res.truth)
    b = rep.item_uncertainty["scale_factor"]
    k_val, k_true = rec["scale_factor"]["value"], rec["scale_factor"]["truth"]
    out = {"err": (k_val - k_true) / k_true / PPM, "tab": tab, "k": float(b.k),
           "u_c": b.u_c / abs(k_val) / PPM,
           "lines": {c.symbol: c.u / abs(k_val) / PPM for c in b.components}}
    kl = rec.get("scale_factor_nonlinearity")
    bl = rep.item_uncertainty.get("scale_factor_nonlinearity")
    if kl is not None and bl is not None:   # K_l in %: ppm = 1e4 × %
        out["kl"] = {"err": 1e4 * (kl["value"] - kl["truth"]), "u_c": 1e4 * kl["u_c"],
                     "lines": {c.symbol: 1e4 * c.u for c in bl.components},
                     "half": {c.symbol: 1e4 * c.u * math.sqrt(3.0) for c in bl.components
                              if c.distribution == "rectangular"}}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="typeb")
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--seed", type=int, default=20261129)
    ap.add_argument("--sample-rate-hz", type=float, default=5.0)
    a = ap.parse_args()
    proto = study.study_protocol("ogam-draft", True)
    bench = study.study_bench(load_bench("rlg"), a.sample_rate_hz)
    base = study.case_bench(a.case, bench, proto)
    coef = study._k_coefficients(proto)
    mpe = float(bench.table.mpe_arcsec)
    rows = [trial(proto, base, a.case, study.trial_seed(a.seed, a.case, i), coef)
            for i in range(a.trials)]
    err = np.array([r["err"] for r in rows])
    tab = np.array([r["tab"] for r in rows])
    uc = np.array([r["u_c"] for r in rows])
    k = np.array([r["k"] for r in rows])
    sign = 1.0 if float(err @ tab) >= 0 else -1.0     # the bench's sign convention of e
    rest = err - sign * tab
    a_rel = scale_factor_table_bound_rel([60, 120, 180, 240, 300, 360], mpe) / PPM
    th = sorted(coef)
    print(f"case {a.case}, {a.trials} trials, seed {a.seed}, {a.sample_rate_hz:g} Hz, "
          f"table MPE {mpe:g} arcsec")
    print("K (ppm of K): lines' mean u and share of u_c^2")
    for s in rows[0]["lines"]:
        u = np.array([r["lines"].get(s, 0.0) for r in rows])
        print(f"  {s:6s} u {u.mean():.4f}  share {np.mean(u ** 2 / uc ** 2):.2f}")
    print(f"  u_c    {uc.mean():.4f}  k {k.mean():.3g}")
    print(f"K's table error on the drawn tables: rms {np.sqrt(np.mean(tab ** 2)):.4f}, largest "
          f"|.| {np.abs(tab).max():.4f} (P_K half-width a = {a_rel:.4f}, u = "
          f"{a_rel / math.sqrt(3):.4f}; positions {', '.join(f'{p:g}' for p in th)} deg)")
    print(f"K's error: rms {np.sqrt(np.mean(err ** 2)):.4f}, without the table's part "
          f"{np.sqrt(np.mean(rest ** 2)):.4f}")
    p_k = np.array([r["lines"]["P_K"] for r in rows])
    for name, u_tab in (("stated (P_K)", p_k),
                        ("positions independent", np.full_like(p_k, scale_factor_table_u_rel(
                            [60, 120, 180, 240, 300, 360], mpe) / PPM)),
                        ("A.4.1 from the zero, zero not counted",
                         np.full_like(p_k, _stops_only_u_rel(coef, mpe) / PPM))):
        u = np.sqrt(uc ** 2 - p_k ** 2 + u_tab ** 2)
        z = err / u
        print(f"  {name:38s} table u {u_tab.mean():.4f}: z {z.mean():+.2f}, sd {z.std(ddof=1):.2f}"
              f", covered {int(np.sum(np.abs(z) <= k))}/{len(z)}")
    sigma = float(np.sqrt(np.mean(err ** 2)))
    print(f"closed form: holding the corner (a = {a_rel:.4f}) at k = {k.mean():.3g} needs u_c >= "
          f"a/k = {a_rel / k.mean():.4f}, so z sd <= k*sigma/a = {k.mean() * sigma / a_rel:.2f} "
          f"on these tables (sigma {sigma:.4f})")
    kls = [r["kl"] for r in rows if "kl" in r]
    if kls:
        e = np.array([r["err"] for r in kls])
        u = np.array([r["u_c"] for r in kls])
        z = e / u
        print("K_l (ppm): lines' mean u and share of u_c^2")
        for s in kls[0]["lines"]:
            v = np.array([r["lines"].get(s, 0.0) for r in kls])
            print(f"  {s:6s} u {v.mean():.4f}  share {np.mean(v ** 2 / u ** 2):.2f}")
        d = np.mean([r["half"].get("K_tab", math.nan) for r in kls])
        print(f"  u_c    {u.mean():.4f}; error sd {e.std(ddof=1):.4f}, rms "
              f"{np.sqrt(np.mean(e ** 2)):.4f}; z {z.mean():+.2f}, sd {z.std(ddof=1):.2f}")
        if math.isfinite(d):
            print(f"closed form: K_tab's worst range shift D = {d:.4f}; holding it at k = 2 "
                  f"needs u_c >= D/2, z sd <= 2*rms/D = "
                  f"{2 * np.sqrt(np.mean(e ** 2)) / d:.2f}")


if __name__ == "__main__":
    main()
