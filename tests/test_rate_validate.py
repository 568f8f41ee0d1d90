"""``gonio validate --spec jjf1535-2015|iec62047-20``: the rate items' coverage study on the
validate engine — the same JSON on any number of workers and any batching, trial i seeded
by SeedSequence(seed, spawn_key=(SPEC.coverage.stream, i)), the per-item table printed, the
bench-case study's options refused with a specification whose study is per item."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gonio.pipeline.coverage import TrialJob, coverage_validate, run_batch, trial_records
from gonio.specs import get
from gonio.specs._rate_family.simulate import study_bench


def test_trial_seeds_are_seedsequence_children():
    from gonio.specs.iec62047_20.protocol import load_protocol
    job = TrialJob("iec62047-20", study_bench(), load_protocol("iec62047-20"), 5)
    key = get("iec62047-20").coverage.stream
    assert key == 1                        # fixed: a published study reproduces
    want = [int(np.random.SeedSequence(5, spawn_key=(key, i)).generate_state(1, np.uint32)[0])
            for i in (0, 1, 2)]
    # the seeds alone (no trial run): the batch function's seeding, from the index only
    from gonio.pipeline.validate import spawn_seed
    assert [spawn_seed(job.seed, key, i) for i in (0, 1, 2)] == want
    assert len(set(want)) == 3


def test_same_report_on_any_workers_and_batching(capsys):
    from gonio.cli import main
    # one worker through the CLI (which prints the report), two workers of one trial each
    # through the API: the same JSON
    capsys.readouterr()
    assert main(["validate", "--spec", "iec62047-20", "--trials", "2", "--seed", "3",
                 "--workers", "1", "--json"]) == 0
    ja = capsys.readouterr().out
    b = coverage_validate("iec62047-20", 2, seed=3, workers=2, batch_size=1, show_progress=False)
    assert ja == json.dumps(b.to_dict(), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    d = json.loads(ja)
    assert d["settings"]["trials"] == 2 and len(d["items"]) >= 20
    assert all(r["n"] == 2 for r in d["items"])
    # the coverage counts |value − truth| ≤ U of the trials themselves: rerun trial 0 alone
    from gonio.pipeline.validate import spawn_seed
    job = TrialJob("iec62047-20", study_bench(), None, 3)
    import tempfile
    from pathlib import Path

    from gonio.pipeline.coverage import reduced_protocol
    from gonio.specs.iec62047_20.protocol import load_protocol
    with tempfile.TemporaryDirectory() as t:
        proto = load_protocol(str(reduced_protocol("iec62047-20", Path(t) / "r.toml")))
    # trial 0 rerun alone; both through the batch function, whose text is trial 0's records
    batch = run_batch(TrialJob("iec62047-20", job.bench, proto, 3), 0, 2)
    recs = [trial_records("iec62047-20", job.bench, proto,
                          spawn_seed(3, get("iec62047-20").coverage.stream, 0))]
    assert batch[0][2] == json.dumps(recs[0], sort_keys=True)
    assert [(i, sd) for i, sd, _, _ in batch] == \
        [(i, spawn_seed(3, get("iec62047-20").coverage.stream, i)) for i in (0, 1)]
    recs.append(json.loads(batch[1][2]))
    # (an item stated by its interval alone: the truth inside that interval)
    for row in d["items"]:
        hits = sum(r[row["key"]]["interval"][0] <= r[row["key"]]["truth"]
                   <= r[row["key"]]["interval"][1] if r[row["key"]].get("interval")
                   else abs(r[row["key"]]["value"] - r[row["key"]]["truth"]) <= r[row["key"]]["U"]
                   for r in recs)
        assert row["hits"] == hits, row["key"]
    # the optical draft's options are refused
    capsys.readouterr()
    assert main(["validate", "--spec", "jjf1535-2015", "--trials", "2", "--truth",
                 "calibrated"]) == 2
    assert "--truth does not apply to 'gonio validate --spec jjf1535-2015'" in \
        capsys.readouterr().err
    assert main(["validate", "--spec", "nope", "--trials", "2"]) == 2
    assert "unknown specification 'nope'" in capsys.readouterr().err


def test_table_prints_every_item():
    from gonio.pipeline.coverage import CoverageReport, format_coverage, item_coverage
    import pandas as pd
    rows = [item_coverage([(1.0, 1.05, 0.1, 0.05)] * 9 + [(1.0, 1.5, 0.1, 0.05)], "bias",
                          "7.2.8").__dict__]
    txt = format_coverage(pd.DataFrame(rows), "t")
    assert "bias" in txt and "0.900" in txt and "FLAG" not in txt
    low = item_coverage([(1.0, 1.05, 0.1, 0.05)] * 8 + [(1.0, 1.5, 0.1, 0.05)] * 2, "bias",
                        "7.2.8").__dict__
    assert "FLAG: under-covers" in format_coverage(pd.DataFrame([low]), "t")
    rep = CoverageReport({"spec": "x", "trials": 10, "seed": 0, "protocol": "p",
                                "bench": "b"}, pd.DataFrame(rows))
    assert rep.table().startswith("x: 10 trials")
    with pytest.raises(Exception, match="trials"):
        coverage_validate("iec62047-20", 1)
