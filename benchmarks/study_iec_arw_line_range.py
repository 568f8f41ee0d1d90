"""IEC 62047-20 5.4.5.2 ARW on the built-in record (72 000 samples at 0.1 s) of the
ADXRS610 bench's own noise generator, against the bench's ARW parameter (a physical
parameter, not a gonio reading): per seed the certified value (−½ range from the fitted
model's curve, lift-corrected), its u_c and upper end, the standard's reading (the range
the data's slope gives, uncorrected), the band-limited and five-term lift factors over the
certified τ, and the band-limited fit's N (the estimator JJF 1535 7.2.13 certifies).

    nice python benchmarks/study_iec_arw_line_range.py FIRST COUNT OUT.jsonl
    python benchmarks/study_iec_arw_line_range.py --table 'OUT*.jsonl'
"""
from __future__ import annotations

import glob
import json
import sys

import numpy as np

TRUTH_FIELDS = ("value", "u_c", "upper", "std_reading", "ratio", "ratio_five", "fit_n", "fit_u_n")


def run(first: int, count: int, out: str) -> None:
    from gonio.analysis.noise import allan_deviation, fit_markov_model, fit_noise_model
    from gonio.bench.rate_gyro import NoiseState, load_rate_bench
    from gonio.specs.iec62047_20 import formulas as ief
    from gonio.specs.iec62047_20 import items as I

    g = load_rate_bench("mems-adxrs610").gyro
    lsb_dph = g.output_lsb / g.scale_factor * 3600.0
    with open(out, "a", encoding="utf-8") as f:
        for s in range(first, first + count):
            x = NoiseState(g, np.random.default_rng(s)).samples(
                72000, 0.1, g.reference_temperature_c) * 3600.0
            x = np.round(x / lsb_dph) * lsb_dph                 # the voltmeter's resolution
            a = allan_deviation(x, 0.1, "rate", "decade:10", unit="deg/h")
            five, shaped = fit_noise_model(a), fit_markov_model(a)
            value, _, ratio, _, mask = I.arw_reading(a, shaped)
            r5 = I.arw_lift_factor(a.tau_s, mask, five)
            u = I.arw_uncertainty(value, ratio, I.arw_line_edf(a, mask, five), r5)
            f.write(json.dumps({
                "seed": s, "truth": g.arw_deg_sqrt_h, "value": value, "u_c": u.u_c,
                "upper": u.interval[1], "std_reading": ief.arw_minus_half_line(a.tau_s, a.adev)[0],
                "ratio": ratio, "ratio_five": r5, "fit_n": shaped.N / 60.0,
                "fit_u_n": shaped.u_N / 60.0}) + "\n")
            f.flush()


def table(pattern: str) -> str:
    from scipy import stats

    r = [json.loads(x) for p in sorted(glob.glob(pattern)) for x in open(p, encoding="utf-8")]
    t = np.array([x["truth"] for x in r])
    v, u, up, sv, fn, fu = (np.array([x[k] for x in r]) for k in
                            ("value", "u_c", "upper", "std_reading", "fit_n", "fit_u_n"))
    n, z = t.size, (v - t) / u
    ex = int((up < t).sum())
    cp = stats.binomtest(n - ex, n).proportion_ci(0.95)
    zf = (fn - t) / fu
    return (f"n {n}: value/truth − 1 {100 * np.mean(v / t - 1):+.3f} % (se "
            f"{100 * np.std(v / t, ddof=1) / np.sqrt(n):.3f} %), z {z.mean():+.3f} (se "
            f"{z.std(ddof=1) / np.sqrt(n):.3f}), sd z {z.std(ddof=1):.3f}, upper end exceeded "
            f"{ex}/{n} = {ex / n:.3f}, cover CP 95 % [{cp.low:.3f}, {cp.high:.3f}]; standard's "
            f"reading/truth − 1 {100 * np.mean(sv / t - 1):+.3f} %; band-limited fit N/truth − 1 "
            f"{100 * np.mean(fn / t - 1):+.3f} % (se {100 * np.std(fn / t, ddof=1) / np.sqrt(n):.3f} %), "
            f"z on its u_N {zf.mean():+.3f}, sd {zf.std(ddof=1):.3f}\n")


if __name__ == "__main__":
    if sys.argv[1] == "--table":
        print(table(sys.argv[2]), end="")
    else:
        run(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3])
