"""Issue 24: the triad bias b_i certified as a long-term bias covers the bench's bias.

Truth: the bench's physical bias K_i·b_i (``TriadBench.bias_output``), not an estimate. The
built-in alignment protocol on the default MEMS triad, 40 fresh seeds; both sides checked
(coverage ≥ 90 %, sd of z = (b − truth)/u_c ≥ 0.3).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from gonio.specs.triad_alignment.bench import load_triad_bench, load_triad_protocol, run_alignment_session
from gonio.specs.triad_alignment.readings import TriadReadings
from gonio.specs.triad_alignment.analysis import estimate_alignment
from gonio.specs.triad_alignment.calibration import alignment_items


@pytest.mark.slow
def test_bias_u_covers_the_bench_bias_on_the_built_in_programme():
    bench = load_triad_bench("mems-triad")
    proto = load_triad_protocol("triad-alignment")
    truth = bench.bias_output
    hits, z, hits_in_run = [], [], []
    for seed in range(24_200, 24_240):
        ses = run_alignment_session(proto, bench, seed=seed)
        d = ses.readings.assign(line=np.arange(len(ses.readings)) + 17)
        rd = TriadReadings(d, dict(ses.metadata), None)
        al = estimate_alignment(rd)
        st = rd.rows("static")
        items = alignment_items(al, 0, float(st["duration_s"].sum()))
        for i, a in enumerate("xyz"):
            it = items[f"b_{a}"]
            u = it.uncertainty
            e = it.value - truth[i]
            hits.append(abs(e) <= u.U)
            z.append(e / u.u_c)
            hits_in_run.append(abs(e) <= u.components[0]["u"] * u.k)
    hits = np.array(hits)
    ci = stats.binomtest(int(hits.sum()), hits.size).proportion_ci(0.95, method="exact")
    msg = (f"coverage {hits.mean():.3f} [{ci.low:.3f}, {ci.high:.3f}], sd z "
           f"{np.std(z, ddof=1):.2f}")
    assert hits.mean() >= 0.90, msg
    assert np.std(z, ddof=1) >= 0.3, msg
    # the in-run u alone is what failed (33 % in the issue; 61 % since the in-run u holds
    # the bias offsets between the orientation blocks): the long-term term is needed
    assert np.mean(hits_in_run) < 0.75, msg
