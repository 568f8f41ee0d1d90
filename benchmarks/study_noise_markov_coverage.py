"""Coverage of the ARW's u(N) from :func:`gonio.analysis.noise.fit_markov_model` on simulated
2-h static records of the virtual bench (72 000 samples at 0.1 s, the JJF built-in τ grid
``decade:10``), the bench's bias instability scaled by a factor.

    nice python benchmarks/study_noise_markov_coverage.py SCALE TRIALS FIRST_SEED

prints one line per record (seed, N, u(N), u_N_selection, T_lo) and the coverage of
N ± 2u(N) of the bench's N (its ``arw_deg_sqrt_h``) with the Clopper–Pearson 95 % interval,
z mean and sd, for u(N) and for u(N) with the T_lo selection spread added in quadrature.
"""
import dataclasses
import math
import sys

import numpy as np
from scipy import stats
from gonio.analysis.noise import allan_deviation, fit_markov_model
from gonio.bench.rate_gyro import NoiseState, load_rate_bench
from gonio.units import S_PER_H
bscale = float(sys.argv[1]); ntr = int(sys.argv[2]); first = int(sys.argv[3])
g = load_rate_bench("mems-adxrs610").gyro
g = dataclasses.replace(g, bias_instability_dph=g.bias_instability_dph * bscale)
n_true = g.arw_deg_sqrt_h * math.sqrt(S_PER_H)
rows = []
for s in range(first, first + ntr):
    ns = NoiseState(g, np.random.default_rng(s)); ns.skip(600.0)
    r = ns.samples(72000, 0.1, g.reference_temperature_c) * S_PER_H
    f = fit_markov_model(allan_deviation(r, 0.1, "rate", "decade:10", unit="deg/h"))
    rows.append((f.N, f.u_N, f.u_N_selection, f.t_lo_s)); print(s, *[f"{v:.5g}" for v in rows[-1]], flush=True)
a = np.array(rows)
print(f"N/N_true mean {a[:,0].mean()/n_true:.5f} sd {a[:,0].std(ddof=1)/n_true*100:.3f} %; T_lo=0 in {np.sum(a[:,3]==0)}")
for lab, u in [("u_N", a[:,1]), ("u_N (+) selection", np.hypot(a[:,1], a[:,2]))]:
    z = (a[:,0]-n_true)/u; n=len(z); k = int(np.sum(np.abs(z) <= 2.0))
    lo = stats.beta.ppf(0.025, k, n-k+1) if k>0 else 0.0; hi = stats.beta.ppf(0.975, k+1, n-k) if k<n else 1.0
    print(f"bscale {bscale} {lab}: cover(k=2) {k/n:.3f} [{lo:.3f}, {hi:.3f}] z mean {z.mean():+.2f} sd {z.std(ddof=1):.2f} mean u/N {u.mean()/n_true*100:.3f} %")
