"""Speed and memory of gonio.analysis.noise against allantools (same run).

Prints:
* 10⁷ samples, octave τ: overlapping ADEV (with Greenhall edf and noise
  identification) against allantools.oadev (which computes no edf), best of 3,
  interleaved; and tracemalloc's peak over the input's size;
* every τ ("all") for 10⁶ samples of white rate noise and of white + rate random
  walk: ADEV and HDEV by the correlation expansion, MDEV by the expansion on local
  segments — wall and CPU time, the number of τ recomputed directly for rounding,
  and tracemalloc's peak / input size (the result itself included);
* MDEV "all" at 10⁵ and 10⁶ samples (white): the growth with N (O(N log³ N));
* allantools' "all"-τ oadev/mdev at 2·10⁴ samples, extrapolated as O(N²).

* the all-τ ADEV of 10⁶ white samples for seeds 2024, 0, 1, each in a fresh process
  (issue 26: its time must depend on N only; ``--seeds`` runs only this part).

The octave comparison first: ADEV, MDEV and HDEV at 10⁷ samples against allantools'
oadev, mdev and ohdev (``--octave`` runs only this part).

Run: ``python benchmarks/bench_noise.py [--seeds | --octave]``
"""

from __future__ import annotations

import math
import time
import tracemalloc

import numpy as np

import gonio.analysis.noise.allan as allan_mod
from gonio.analysis.noise import allan_deviation


def best_of(fn, repeats):
    times = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def peak_ratio(fn, nbytes):
    tracemalloc.start()
    tracemalloc.reset_peak()
    out = fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / nbytes, out


def count_redo(fn):
    """Run fn, counting the τ the expansion recomputed directly."""
    orig = allan_mod._direct_sums
    count = [0]

    def wrap(kind, x, ms):
        count[0] += len(ms)
        return orig(kind, x, ms)

    allan_mod._direct_sums = wrap
    try:
        t0 = time.perf_counter()
        out = fn()
        return time.perf_counter() - t0, count[0], out
    finally:
        allan_mod._direct_sums = orig


def seed_times() -> None:
    """issue 26: the time of the all-τ ADEV must depend on N, not on the realisation. Each
    seed's record of white rate noise runs in a fresh process (the capped-branch edf grid
    is kept per process: a fresh one pays for it as a user's first run does)."""
    import subprocess
    import sys
    code = ("import sys, time, numpy as np; from gonio.analysis.noise import allan_deviation; "
            "s = int(sys.argv[1]); r = np.random.default_rng(s); "
            "_ = r.standard_normal(10_000_000) if s == 2024 else None; "
            "w = r.standard_normal(1_000_000); c = time.process_time(); "
            "t = time.perf_counter(); a = allan_deviation(w, 1e-3, 'rate', 'all'); "
            "print(f'{time.perf_counter() - t:.2f} {time.process_time() - c:.2f} '"
            "      f'{sorted(set(a.alpha[-1000:].tolist()))}')")
    for seed in (2024, 0, 1):
        out = subprocess.run([sys.executable, "-c", code, str(seed)], capture_output=True,
                             text=True, check=True).stdout.split(maxsplit=2)
        print(f"all tau ADEV, 1e6 white samples, seed {seed:4d}: {out[0]} s (CPU {out[1]} s);"
              f" noise type identified at the largest tau: alpha {out[2].strip()}")


def octave_against_allantools(y: np.ndarray, tau0: float) -> None:
    """ADEV, MDEV and HDEV at octave τ against allantools' oadev, mdev and ohdev on the same
    record, interleaved three times; the best CPU time (process_time) and wall time of each,
    and the load average (CPU time is the figure a shared machine hides least)."""
    import os

    import allantools

    import platform

    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, numpy {np.__version__}, allantools "
          f"{getattr(allantools, '__version__', '?')}", flush=True)
    peers = {"adev": allantools.oadev, "mdev": allantools.mdev, "hdev": allantools.ohdev}
    for kind, peer in peers.items():
        best = {"ours": [math.inf, math.inf], "allantools": [math.inf, math.inf]}
        load = os.getloadavg()[0]
        for _ in range(3):  # interleaved: the machine may be shared
            for who in ("ours", "allantools"):
                c0, w0 = time.process_time(), time.perf_counter()
                if who == "ours":
                    r = allan_deviation(y, tau0, "rate", "octave", kind=kind)
                else:
                    _, dev, _, _ = peer(y, rate=1 / tau0, data_type="freq", taus=r.tau_s)
                cpu, wall = time.process_time() - c0, time.perf_counter() - w0
                best[who] = [min(best[who][0], cpu), min(best[who][1], wall)]
        (c_o, w_o), (c_a, w_a) = best["ours"], best["allantools"]
        print(f"octave {kind.upper()}, {y.size:.0e} samples ({r.tau_s.size} tau): ours CPU "
              f"{c_o:.3f} s (wall {w_o:.3f} s; with Greenhall edf and noise id), "
              f"allantools.{peer.__name__} CPU {c_a:.3f} s (wall {w_a:.3f} s): "
              f"{c_a / c_o:.2f}x in CPU, {w_a / w_o:.2f}x in wall; max rel diff "
              f"{np.max(np.abs(dev / r.adev - 1)):.1e}; load {load:.1f} "
              f"to {os.getloadavg()[0]:.1f}", flush=True)


def main() -> None:
    import allantools

    rng = np.random.default_rng(2024)
    tau0 = 0.001
    y = 3.0 + rng.standard_normal(10_000_000)
    octave_against_allantools(y, tau0)
    ratio, _ = peak_ratio(lambda: allan_deviation(y, tau0, "rate", "octave"), y.nbytes)
    print(f"  peak memory (tracemalloc) / input: {ratio:.2f}")
    del y

    n = 1_000_000
    white = rng.standard_normal(n)
    mixed = white + 0.01 * np.cumsum(rng.standard_normal(n))
    for name, data in (("white", white), ("white + RRW", mixed)):
        for kind in ("adev", "mdev", "hdev"):
            c0 = time.process_time()
            t, redo, res = count_redo(
                lambda: allan_deviation(data, tau0, "rate", "all", kind=kind))
            cpu = time.process_time() - c0
            print(f"all tau, 1e6 samples, {name:11s} {kind}: {t:6.2f} s (CPU {cpu:5.2f} s) "
                  f"for {res.m.size} tau, {redo} recomputed directly")
    for name, data in (("white", white), ("white + RRW", mixed)):
        for kind in ("adev", "mdev", "hdev"):
            ratio, res = peak_ratio(
                lambda: allan_deviation(data, tau0, "rate", "all", kind=kind), data.nbytes)
            own = sum(v.nbytes for v in vars(res).values() if isinstance(v, np.ndarray))
            print(f"  peak memory / input ('all', {kind}, {name}): {ratio:.2f} "
                  f"(of which the result's own arrays: {own / data.nbytes:.2f})")

    seed_times()

    t5, _ = best_of(lambda: allan_deviation(white[:100_000], tau0, "rate", "all",
                                            kind="mdev"), 1)
    t6, _ = best_of(lambda: allan_deviation(white, tau0, "rate", "all", kind="mdev"), 1)
    print(f"MDEV all tau, white: 1e5 samples {t5:.2f} s, 1e6 samples {t6:.2f} s "
          f"(x{t6 / t5:.1f} for 10x N; O(N^2) would be x100)")
    print("  (CPU time is the better figure on a shared machine: wall time includes "
          "waiting for a core)")

    n_small = 20_000
    ys = white[:n_small]
    for kind, fn in (("adev", allantools.oadev), ("mdev", allantools.mdev)):
        t_at_small, _ = best_of(
            lambda: fn(ys, rate=1 / tau0, data_type="freq", taus="all"), 1)
        t_ours_small, _ = best_of(lambda: allan_deviation(ys, tau0, "rate", "all",
                                                          kind=kind), 1)
        extrap = t_at_small * (1_000_000 / n_small) ** 2
        print(f"all tau {kind}, {n_small} samples: ours {t_ours_small:.3f} s, allantools "
              f"{t_at_small:.2f} s; allantools at 1e6 extrapolated (O(N^2)): "
              f"~{extrap / 3600:.1f} h")


if __name__ == "__main__":
    import sys as _sys
    if "--seeds" in _sys.argv[1:]:
        seed_times()
    elif "--octave" in _sys.argv[1:]:
        octave_against_allantools(3.0 + np.random.default_rng(2024).standard_normal(10**7),
                                  0.001)
    else:
        main()
