"""Speed and memory of gonio.analysis.noise.allan_deviation against allantools (same run).

Prints: 1e7-sample 'octave' OADEV time, ours vs allantools.oadev, and the ratio
(best of a few repeats each, same data); 'all'-τ time for 1e6 samples (white rate
noise, and white + rate random walk, which needs more direct recomputation), with
allantools' 'all' measured at a smaller N and extrapolated as O(N²); and the peak
memory allocated during our call (tracemalloc) relative to the input array.

Run: ``python benchmarks/bench_noise.py``
"""

from __future__ import annotations

import math
import time
import tracemalloc

import numpy as np

from gonio.analysis.noise import allan_deviation


def best_of(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def peak_ratio(fn, nbytes):
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / nbytes


def main() -> None:
    import allantools

    rng = np.random.default_rng(2024)
    tau0 = 0.001
    y = 3.0 + rng.standard_normal(10_000_000)
    # interleaved repeats, best of each: the machine may be shared
    t_ours, t_at = math.inf, math.inf
    for _ in range(3):
        t, r = best_of(lambda: allan_deviation(y, tau0, "rate", "octave"), 1)
        t_ours = min(t_ours, t)
        t, (_, dev, _, _) = best_of(
            lambda: allantools.oadev(y, rate=1 / tau0, data_type="freq", taus=r.tau_s), 1)
        t_at = min(t_at, t)
    print(f"octave, 1e7 samples: ours {t_ours:.3f} s, allantools.oadev {t_at:.3f} s, "
          f"ratio {t_at / t_ours:.2f}x (max rel diff {np.max(np.abs(dev / r.adev - 1)):.1e})")
    print(f"  peak memory (tracemalloc) / input array: "
          f"{peak_ratio(lambda: allan_deviation(y, tau0, 'rate', 'octave'), y.nbytes):.2f}")
    del y

    y6 = rng.standard_normal(1_000_000)
    t_all, r_all = best_of(lambda: allan_deviation(y6, tau0, "rate", "all"), 1)
    print(f"all tau, 1e6 samples, white rate noise: {t_all:.2f} s for {r_all.m.size} tau")
    y6r = y6 + 0.01 * np.cumsum(rng.standard_normal(y6.size))
    t_allr, _ = best_of(lambda: allan_deviation(y6r, tau0, "rate", "all"), 1)
    print(f"all tau, 1e6 samples, white + rate random walk: {t_allr:.2f} s")
    result_bytes = sum(v.nbytes for v in vars(r_all).values() if isinstance(v, np.ndarray))
    print(f"  peak memory / input array ('all', white): "
          f"{peak_ratio(lambda: allan_deviation(y6, tau0, 'rate', 'all'), y6.nbytes):.2f} "
          f"(of which the result's own arrays: {result_bytes / y6.nbytes:.2f})")

    n_small = 20_000
    ys = y6[:n_small]
    t_at_small, _ = best_of(
        lambda: allantools.oadev(ys, rate=1 / tau0, data_type="freq", taus="all"), 1)
    t_ours_small, _ = best_of(lambda: allan_deviation(ys, tau0, "rate", "all"), 3)
    extrap = t_at_small * (1_000_000 / n_small) ** 2
    print(f"all tau, {n_small} samples: ours {t_ours_small:.3f} s, allantools {t_at_small:.2f} s; "
          f"allantools at 1e6 extrapolated (O(N^2)): ~{extrap / 3600:.1f} h")


if __name__ == "__main__":
    main()
