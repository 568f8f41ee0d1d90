"""Coverage of every JJF 1535 / IEC 62047-20 item on the BUILT-IN programme (issue 24), on
fresh seeds no test uses: per item the coverage of U with its Clopper–Pearson 95 %
interval, and the mean and spread of z = (value − truth)/u_c (two-sided: sd z < 0.3 flags
an over-wide U, coverage < 0.90 a narrow one) — the table of ``gonio validate --spec``
(``format_coverage``): a standard deviation stated by its one-sided χ² interval (K_r, B_r,
B_s; Noise,RMS) is judged by that interval and its z is the χ² z, with z on u_c beside it.

    PYTHONPATH=$PWD python benchmarks/bench_rate_coverage_builtin.py --spec iec62047-20 \
        --seeds 100 --first 910000 [--fixed-equipment] [--records out.jsonl]

Bench: the default bench (mems-adxrs610) as the specification's study bench makes it
(``SPEC.coverage.study_bench``: thermal lag off, and for JJF 1535 the cross-axis coupling of a turning
Earth rate: history effects the truths leave out; IEC 62047-20's truths carry the cross-axis) but WITH the power-on transient, so the warm-up and start-up items are measured.
Equipment: by default (as in the tests and ``gonio validate``) each trial draws every
type-B equipment error from its seed — rate-table rate error and voltmeter gain (normal,
their certificates' u), chamber deviation per set point (uniform ±2 °C), the gyro's
misalignment in its fixture (uniform ±0.05° about body x and y):
gonio.bench.equipment.draw_equipment. ``--fixed-equipment``: the bench file's one
realisation in every trial (``--draw-equipment`` is accepted and is the default).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace



def bench_for(spec: str, draw: bool = True):
    """The study bench of ``spec`` (``SPEC.coverage.study_bench``) with the power-on transient
    back on; ``draw``: equipment drawn per trial (from the trial's seed, in SPEC.run_trial)."""
    from gonio.bench.rate_gyro import load_rate_bench
    from gonio.kit import get

    b = get(spec).coverage.study_bench("mems-adxrs610", draw_equipment=draw)
    return replace(b, gyro=replace(b.gyro, warmup_bias_dps=load_rate_bench("mems-adxrs610")
                                   .gyro.warmup_bias_dps))


def table(records: list[dict], title: str = "") -> str:
    """The per-item table of ``gonio validate --spec`` (:func:`gonio.pipeline.coverage.
    format_coverage`): an item stated by its interval alone is judged by that interval, and a
    standard deviation stated by its one-sided χ² interval (JJF K_r, B_r, B_s; IEC Noise,RMS)
    by its χ² z, Φ⁻¹(F_χ²(ν s²/σ²; ν)), the interval's own scale, with z on u_c beside it
    (for ν = 2, z on u_c = 2(1 − σ/s) is unbounded below and says nothing of the interval)."""
    from gonio.pipeline.coverage import coverage_table_from, format_coverage

    return format_coverage(coverage_table_from([r["r"] for r in records]), title)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--spec", default="iec62047-20")
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--first", type=int, default=910000)
    ap.add_argument("--draw-equipment", action="store_true", help="the default")
    ap.add_argument("--fixed-equipment", action="store_true",
                    help="the bench file's equipment errors in every trial")
    ap.add_argument("--records", help="append each trial's records (JSON lines) here")
    ap.add_argument("--table-only", help="print the table of a records file and exit")
    a = ap.parse_args(argv)
    if a.table_only:
        recs = [json.loads(x) for x in open(a.table_only, encoding="utf-8")]
        print(table(recs, f"records {a.table_only}"), end="")
        return 0
    from gonio.pipeline.coverage import trial_records

    recs = []
    t0 = time.perf_counter()
    bench = bench_for(a.spec, not a.fixed_equipment)
    for s in range(a.first, a.first + a.seeds):
        r = {"seed": s, "r": trial_records(a.spec, bench, a.spec, s)}
        recs.append(r)
        if a.records:
            with open(a.records, "a", encoding="utf-8") as f:
                f.write(json.dumps(r) + "\n")
    print(table(recs, f"{a.spec}: built-in programme, {a.seeds} seeds from {a.first}, "
                f"{'fixed equipment' if a.fixed_equipment else 'equipment drawn per trial'}, "
                f"{time.perf_counter() - t0:.0f} s"), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
