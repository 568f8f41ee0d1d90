"""Issue 24, optical draft: K as mounted against the bench's physical truth; the B_s floor.

The truths here are written out from the bench's physical parameters (nominal scale
factor, its error, the rate nonlinearity ε(ω), the tilt ψ), never taken from an estimator.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.calibration import calibrate
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.item_uncertainty import scale_factor_budget
from gonio.specs.ogam_draft.items import scale_factor

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "data" / "small-protocol.toml"


def coverage_verdict(hits, z) -> dict:
    """Two-sided coverage check: fraction with its 95 % Clopper–Pearson interval, sd of z."""
    hits = np.asarray(hits, bool)
    ci = stats.binomtest(int(hits.sum()), hits.size).proportion_ci(0.95, method="exact")
    return {"coverage": float(hits.mean()), "ci": (ci.low, ci.high), "n": hits.size,
            "sd_z": float(np.std(z, ddof=1)), "mean_z": float(np.mean(z))}


def k_as_mounted_truth(inst, rate_dps: float) -> float:
    """K_nominal (1 + e) (1 + ε(ω cos ψ)) cos ψ, written out from the bench's parameters:
    ε(w) = q (w/300)² + l exp(−w/s) ppm (the bench's documented rate nonlinearity)."""
    c = math.cos(math.radians(inst.tilt_deg))
    w = rate_dps * c
    eps = 1e-6 * (inst.sf_rate_quadratic_ppm * (w / 300.0) ** 2
                  + inst.sf_lowrate_ppm * math.exp(-w / inst.sf_lowrate_scale_dps))
    return inst.nominal_scale_factor_counts_per_deg * (1 + 1e-6 * inst.scale_factor_error_ppm) \
        * (1 + eps) * c


@pytest.mark.slow
def test_u_of_k_covers_k_as_mounted_on_the_built_in_7_1():
    """40 fresh seeds, the built-in 7.1 programme on the default RLG bench."""
    raw = tomllib.loads((ROOT / "protocols" / "ogam-draft.toml").read_text())
    proto = parse_protocol({k: raw[k] for k in ("protocol", "session", "scale_factor",
                                                "annex_a", "conditions")})
    bench = load_bench("rlg")
    inst = bench.instrument
    assert inst.tilt_deg > 0
    truth = k_as_mounted_truth(inst, proto.scale_factor.rate_dps)
    own = truth / math.cos(math.radians(inst.tilt_deg))
    z, z_own, hits = [], [], []
    for seed in range(24_100, 24_140):
        r = run_session(proto, bench, seed=seed)
        sf = scale_factor(r.readings.assign(line=np.arange(len(r.readings)) + 2))
        b = scale_factor_budget(sf.table["K_i_counts_per_deg"], sf.table["table_deg"],
                                proto.annex_a.table_mpe_arcsec)
        z.append((sf.value - truth) / b.u_c)
        z_own.append((sf.value - own) / b.u_c)
        hits.append(abs(sf.value - truth) <= b.U)
    v = coverage_verdict(hits, z)
    assert v["coverage"] >= 0.90, v
    assert v["sd_z"] >= 0.3, v                      # not over-wide
    # the instrument's own K is what the value is not centred on (the reason K is stated as
    # mounted): the value sits about two standard uncertainties below it (z −2.0 on seeds
    # 24100–24139), centred on K as mounted (z +0.08).
    # (A coverage count of the own K depends on U's table line, which holds the table at its
    # MPE bound and so is wide on this bench's good table: the own K fell inside U in 20 of 40.)
    assert np.mean(z_own) < -1.0 and abs(np.mean(z)) < 0.5, (np.mean(z_own), np.mean(z))


def test_certificate_states_k_as_mounted(tmp_path):
    from gonio.cli import main
    assert main(["simulate", "--protocol", str(SMALL), "--seed", "2412", "--out",
                 str(tmp_path / "s")]) == 0
    rep = calibrate(tmp_path / "s" / "readings.csv", SMALL).to_json()
    sf = rep["items"]["scale_factor"]["details"]
    assert sf["measurand"].startswith("K as mounted") and sf["tilt_bound_deg"] == 0.1
    assert sf["instrument_own_upper_counts_per_deg"] == pytest.approx(
        rep["items"]["scale_factor"]["value"] / math.cos(math.radians(0.1)), rel=1e-12)
    from gonio.specs.ogam_draft.certificate_pages import certificate_blocks
    from gonio.report.i18n import labels
    from gonio.specs.ogam_draft.phrases import LABELS     # the draft's own labels
    for lang, text in (("en", "stated as mounted"), ("zh", "安装状态下的值")):
        blocks = certificate_blocks(rep, labels(lang, LABELS), lab=None, truth=None,
                                    lang=lang)["blocks"]
        page = " ".join(str(b.data) for b in blocks)
        assert text in page and "1.5 ppm" in page


def _bs(tmp_path, edit):
    from gonio.cli import main
    if not (tmp_path / "s" / "readings.csv").exists():
        assert main(["simulate", "--protocol", str(SMALL), "--seed", "2413", "--out",
                     str(tmp_path / "s")]) == 0
    lines = (tmp_path / "s" / "readings.csv").read_text().splitlines(keepends=True)
    out = [edit(ln) if ln.startswith("zero_stability,") else ln for ln in lines]
    f = tmp_path / "z.csv"
    f.write_text("".join(out))
    return calibrate(f, SMALL).to_json()["items"]


def test_identical_7_3_readings_do_not_give_u_zero(tmp_path):
    def same(ln):
        p = ln.split(",")
        p[7] = "12"
        return ",".join(p)
    res = _bs(tmp_path, same)
    zs = res["zero_stability"]
    u = zs["uncertainty"]
    assert zs["value"] == 0.0
    # the floor written out: one count 1/K over T = 60 s, triangular (δ/√6), in °/h
    k = res["scale_factor"]["value"]
    b_res = (1 / k) / math.sqrt(6) / (60.0 / 3600.0)
    assert u["u_c"] == pytest.approx(b_res, rel=1e-9)
    assert u["U"] > 0 and u["interval"][1] > 0
    assert zs["nonnegative"] and zs["upper_bound"] >= u["U"]
    assert "resolution" in u["components"][0]["source"]


def test_floor_leaves_a_resolved_scatter_alone(tmp_path):
    spread = iter(["0", "40", "-30", "90"])

    def scatter(ln):
        p = ln.split(",")
        p[7] = next(spread)
        return ",".join(p)
    res = _bs(tmp_path, scatter)
    u = res["zero_stability"]["uncertainty"]
    nu = u["components"][0]["dof"]
    # u = B_s / √(2ν) (JCGM 100 E.4.3) when the scatter is above the floor
    assert u["u_c"] == pytest.approx(res["zero_stability"]["value"] / math.sqrt(2 * nu),
                                     rel=1e-9)
    assert "floored" not in u["components"][0]["source"]
