"""JJF 1535 truths of the bias-stability family in bounded memory (issue 26).

``block_mean_moments`` gives the trace and the sum of the block-mean covariance by lag, in
O(n + P); checked here against the n×n matrix built entry by entry (the definition: white,
each Gauss–Markov term σ²a^|i−j| averaged over the two blocks' samples, the random walk
q²·dt·(min(i, j) + k0) averaged alike), on small sizes where that matrix is cheap. A
``stability_block_samples`` that leaves fewer than two blocks is refused naming the key
(before: a P×P temporary, "out of memory" at 3 GB with no key named)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gonio.bench.rate_gyro import NoiseState, load_rate_bench
from gonio.cli import main
from gonio.specs.jjf1535.truth import block_mean_moments
from gonio.units import S_PER_H


def dense(bench, dt, n, P, t_start_s):
    """The covariance of n block means of P samples, by the definition on sample indices."""
    g = bench.gyro
    ns = NoiseState(g, np.random.default_rng(0), enabled=True)
    idx = np.arange(n * P)
    blk = idx // P
    A = np.zeros((n, n * P))
    A[blk, idx] = 1.0 / P                                     # sample -> block mean
    S = np.eye(n * P) * (g.arw_deg_sqrt_h / math.sqrt(S_PER_H)) ** 2 / dt
    lag = np.abs(idx[:, None] - idx[None, :])
    for tau, s in zip(ns.taus, ns.sig):
        S += s ** 2 * math.exp(-dt / tau) ** lag
    q2 = (g.rrw_dph_sqrt_h / S_PER_H / math.sqrt(S_PER_H)) ** 2
    # sample i carries i + 1 random-walk steps after the start value, k0 = t_start/dt before
    S += q2 * dt * (np.minimum(idx[:, None], idx[None, :]) + 1.0 + t_start_s / dt)
    return A @ S @ A.T


@pytest.mark.parametrize("n,P,dt,t0", [(2, 1, 1.0, 0.0), (7, 10, 1.0, 1800.0),
                                       (12, 3, 0.1, 50.0), (1, 25, 0.5, 0.0),
                                       (30, 17, 2.0, 7.0)])
@pytest.mark.parametrize("bench", ["mems-adxrs610", "fog"])
def test_moments_match_the_dense_covariance(bench, n, P, dt, t0):
    try:
        b = load_rate_bench(bench)
    except Exception:                                   # noqa: BLE001 - bench not shipped
        pytest.skip(f"no rate bench {bench}")
    C = dense(b, dt, n, P, t0)
    tr, tot = block_mean_moments(b, dt, n, P, t0)
    assert tr == pytest.approx(np.trace(C), rel=1e-10)
    assert tot == pytest.approx(C.sum(), rel=1e-10)


def test_large_block_is_bounded():
    """P = 10^5 and 10^4 blocks: finite, no P×P or n×n temporary (would be 80 GB)."""
    b = load_rate_bench("mems-adxrs610")
    tr, tot = block_mean_moments(b, 0.001, 10_000, 100_000, 0.0)
    assert math.isfinite(tr) and math.isfinite(tot) and tr > 0 and tot > 0


def test_block_larger_than_half_the_record_is_refused(tmp_path, capsys):
    src = (__import__("pathlib").Path(__file__).resolve().parents[1] / "protocols"
           / "jjf1535-2015.toml").read_text(encoding="utf-8")
    assert "stability_block_samples = 10 " in src
    p = tmp_path / "big.toml"
    p.write_text(src.replace("stability_block_samples = 10 ", "stability_block_samples = 100000 "),
                 encoding="utf-8")
    capsys.readouterr()
    assert main(["simulate", "--spec", "jjf1535-2015", "--protocol", str(p),
                 "--out", str(tmp_path / "S")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bias.stability_block_samples" in err[0], err
    assert not (tmp_path / "S").exists()
