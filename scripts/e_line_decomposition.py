"""E's physical budget per 7.4 point, line by line, against the spread each effect alone
produces on the study's trials.

    python scripts/e_line_decomposition.py [--trials 12] [--seed 20261129] [--case typeb]
                                           [--sample-rate-hz 100]

Each trial is the one ``gonio validate --spec ogam-draft --cases CASE --trials N --seed S
--all-items`` runs (the same trial seeds, protocol and drawn bench). Its readings are
calibrated as the study does (E corrected at the measured tilt, the physical budget per
point), which gives every line's u per point. The same trial's instrument is then run on
an ideal set-up (no noise, tilt, Earth rate, bias or table error: the intrinsic E_i) and on
that set-up with one effect of the drawn bench put back: the table (its periodic errors,
scatter, wobble, axis set-up, rate error), the drift (the bias instability), the noise
(angle and rate random walk, quantisation), the tilt with the Earth rate and the bias.
The difference from the intrinsic E_i is what that effect alone does to E_i. Prints, per point, the rms over the
trials of each effect and of the full error, beside the mean u of the budget's lines, and
the sd of z = (E_i − intrinsic)/u_c over all points (the study's z sd).
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

import gonio.specs.ogam_draft.calibration as cal
from gonio.specs.ogam_draft import study
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.readings import Readings


def _e(proto, bench, seed, budget=False):
    """E_i (″, corrected at the measured tilt) of one session, and its per-point budgets."""
    res = run_session(proto, bench, seed=seed)
    df = res.readings.copy()
    df["line"] = np.arange(2, len(df) + 2)
    rd = Readings(df, dict(res.metadata))
    rep = cal.analyse(rd, proto, budget="draft", static_record=res.static_record)
    r, et = cal.angle_deviation_at_measured_tilt(rep.results, rd, proto)
    e = r.angle_deviation.table
    if not budget:
        return e["E_arcsec"].to_numpy(float)
    made = []
    orig = cal.annex_a_budget

    def keep(*a, **k):
        made.append(orig(*a, **k))
        return made[-1]

    cal.annex_a_budget = keep
    try:
        st, _ = cal.session_settings(rd, proto)
        b, _, _ = cal.deviation_budget(r, rd, proto, st, kind="physical", tilt_measured=et)
    finally:
        cal.annex_a_budget = orig
    n = len(e)
    subs = made[:n]                        # one per point, then the largest's again
    at = int(np.argmax([x.U_arcsec for x in subs]))
    subs[at] = made[n]
    lines = [{c.symbol: abs(c.c_i) * c.u_xi for c in x.gum.contributions} for x in subs]
    return e["E_arcsec"].to_numpy(float), e["position_deg"].to_numpy(float), lines, \
        np.array([p["u_c_arcsec"] for p in b.points])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=12)
    ap.add_argument("--seed", type=int, default=20261129)
    ap.add_argument("--case", default="typeb")
    ap.add_argument("--sample-rate-hz", type=float, default=100.0)
    a = ap.parse_args()
    proto = study.study_protocol("ogam-draft", True)
    bench = study.case_bench(a.case, study.study_bench(load_bench("rlg"), a.sample_rate_hz),
                             proto)
    eff = {k: [] for k in ("full", "table", "drift", "noise", "tilt")}
    lines, ucs = [], []
    for i in range(a.trials):
        sd = study.trial_seed(a.seed, a.case, i)
        dr = study.trial_bench(a.case, bench, proto, sd)
        ideal = study.ideal_bench(dr)
        e0 = _e(proto, ideal, sd)
        ef, pos, ln, uc = _e(proto, dr, sd, budget=True)
        lines.append(ln)
        ucs.append(uc)
        eff["full"].append(ef - e0)
        eff["table"].append(_e(proto, replace(ideal, table=dr.table), sd) - e0)
        d = dr.instrument
        one = {"drift": dict(bias_instability_dph=d.bias_instability_dph,
                             bias_instability_tau_s=d.bias_instability_tau_s),
               "noise": dict(arw_dpsh=d.arw_dpsh, rrw_dphsh=d.rrw_dphsh,
                             quantisation=d.quantisation),
               "tilt": dict(tilt_deg=d.tilt_deg, tilt_azimuth_deg=d.tilt_azimuth_deg,
                            bias_dph=d.bias_dph)}
        for k, kw in one.items():
            b = replace(ideal, instrument=replace(ideal.instrument, **kw),
                        earth_rate=(k == "tilt"))
            eff[k].append(_e(proto, b, sd) - e0)
    np.set_printoptions(precision=3, suppress=True, linewidth=120)
    print(f"case {a.case}, seed {a.seed}, {a.trials} trials; points (deg):", pos)
    for k, v in eff.items():
        print(f"effect {k:<7} rms  ", np.sqrt((np.array(v) ** 2).mean(axis=0)))
    for sym in sorted(lines[0][0]):
        print(f"line   {sym:<7} u    ",
              np.array([[p.get(sym, 0.0) for p in ln] for ln in lines]).mean(axis=0))
    ucs = np.array(ucs)
    print("u_c            ", ucs.mean(axis=0))
    z = np.array(eff["full"]) / ucs
    print(f"z over all points: mean {z.mean():+.2f}, sd {z.std(ddof=1):.2f}")


if __name__ == "__main__":
    main()
