"""The validation's execution engine: batches on joblib and on Dask give the same bytes; an
interrupted study keeps its finished batches and --resume neither repeats nor loses a trial."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

import gonio.pipeline.validate as V
from gonio.bench import Bench, InstrumentConfig, TableConfig
from gonio.cli import main
from gonio.progress import Progress
from gonio.protocol import parse_protocol


def tiny_protocol():
    return parse_protocol({
        "protocol": {"name": "tiny"},
        "session": {"static_s": 5.0, "warm_up_s": 0.0},
        "scale_factor": {"rounds": [{"stop_deg": 180.0}, {"stop_deg": 360.0}],
                         "read_delay_s": 2.0, "rest_s": 3.0},
        "angle_deviation": {"series": 2, "rest_s": 3.0, "read_delay_s": 2.0,
                            "rounds": [{"stop_deg": 120.0 * i} for i in range(1, 4)]},
    })


def bench():
    inst = InstrumentConfig(nominal_scale_factor_counts_per_deg=76434.87, arw_dpsh=0.003,
                            quantisation=True)
    return Bench("small", inst, TableConfig(positioning_random_arcsec=0.05), latitude_deg=40.0,
                 sample_rate_hz=10.0)


def run(**kw):
    r = V.validate(kw.pop("trials", 6), seed=3, bench=bench(), protocol=tiny_protocol(),
                   sample_rate_hz=10.0, show_progress=False, **kw)
    return json.dumps(r.to_dict(), indent=2, allow_nan=False)


def test_seeds_by_trial_index_match_spawned_children():
    # SeedSequence(seed, spawn_key=(case, i)) is the i-th spawned child (numpy's own spawn).
    for case_i, case in enumerate(V.CASES):
        kids = np.random.SeedSequence(11, spawn_key=(case_i,)).spawn(5)
        assert [V.trial_seed(11, case, i) for i in range(5)] == \
            [int(k.generate_state(1, np.uint32)[0]) for k in kids]


def test_bytes_identical_for_workers_batches_and_a_dask_cluster():
    pytest.importorskip("distributed")
    one = run(workers=1, batch_size=6)
    assert run(workers=1, batch_size=4) == one
    assert run(workers=2, batch_size=3) == one
    assert run(scheduler="local:2", batch_size=2) == one
    # the trials really differ (a seed change changes the bytes)
    assert json.loads(one)["cases"][0]["seeds_first"] == \
        [V.trial_seed(3, "default", i) for i in range(3)]


def test_interrupted_study_resumes_without_repeating_or_losing(tmp_path, monkeypatch):
    ref = run(workers=1, batch_size=2)
    calls = []
    real = V.run_batch

    def flaky(job, a, b):
        calls.append((a, b))
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(job, a, b)

    monkeypatch.setattr(V, "run_batch", flaky)
    part = tmp_path / V.PARTIAL_DIR
    with pytest.raises(KeyboardInterrupt):
        run(workers=1, batch_size=2, partial_dir=part)
    kept = sorted(p.name for p in part.glob("*.npz"))
    assert kept == ["default_0000000000_0000000002.npz", "default_0000000002_0000000004.npz"]
    # without --resume an unfinished study is not overwritten
    with pytest.raises(V.GonioError, match="--resume"):
        run(workers=1, batch_size=2, partial_dir=part)
    calls.clear()
    monkeypatch.setattr(V, "run_batch", lambda job, a, b: (calls.append((a, b)), real(job, a, b))[1])
    assert run(workers=1, batch_size=2, partial_dir=part, resume=True) == ref
    assert calls == [(4, 6)]            # only the missing trials ran
    # other settings cannot resume this study
    with pytest.raises(V.GonioError, match="other settings"):
        V.validate(6, seed=4, bench=bench(), protocol=tiny_protocol(), sample_rate_hz=10.0,
                   show_progress=False, partial_dir=part, resume=True)


def test_cli_keeps_partial_results_and_resumes(tmp_path, capsys, monkeypatch):
    proto = tmp_path / "p.toml"
    proto.write_text('[protocol]\nname = "t"\n[session]\nstatic_s = 5.0\nwarm_up_s = 0.0\n'
                     '[scale_factor]\nread_delay_s = 2.0\nrest_s = 3.0\n'
                     'rounds = [{stop_deg = 180.0}, {stop_deg = 360.0}]\n'
                     '[angle_deviation]\nseries = 2\nrest_s = 3.0\nread_delay_s = 2.0\n'
                     'rounds = [{stop_deg = 120.0}, {stop_deg = 240.0}]\n')
    out = tmp_path / "o"
    argv = ["validate", "--trials", "4", "--protocol", str(proto), "--sample-rate-hz", "10",
            "--workers", "1", "--batch", "1", "--out", str(out)]
    real = V.run_batch
    n = []

    def flaky(job, a, b):
        n.append(a)
        if len(n) == 2:
            raise KeyboardInterrupt
        return real(job, a, b)

    monkeypatch.setattr(V, "run_batch", flaky)
    assert main(argv) == 130
    assert "--resume" in capsys.readouterr().err
    assert not (out / "validation.json").exists()
    assert len(list((out / V.PARTIAL_DIR).glob("*.npz"))) == 1
    monkeypatch.setattr(V, "run_batch", real)
    assert main(argv + ["--resume"]) == 0
    assert not (out / V.PARTIAL_DIR).exists()
    first = (out / "validation.json").read_bytes()
    assert main(argv[:-2] + ["--out", str(tmp_path / "fresh")]) == 0
    assert (tmp_path / "fresh" / "validation.json").read_bytes() == first
    # too many local workers is refused (a scheduler is needed for more)
    assert main(argv[:-4] + ["--workers", "100000", "--out", str(tmp_path / "x")]) == 2
    assert "cores" in capsys.readouterr().err


def test_progress_shows_rate_and_eta_only_when_asked():
    buf = io.StringIO()
    clock = iter([0.0, 10.0, 20.0, 20.0]).__next__
    p = Progress(100, label="t", done=20, stream=buf, force=True, min_interval_s=0.0, clock=clock)
    p.update(30)          # 30 done by this run in 10 s: 3/s, 50 left → 17 s
    p.update(30)          # 60 in 20 s: 3/s, 20 left → 7 s
    p.close()
    lines = [x.strip() for x in buf.getvalue().split("\r") if x.strip()]
    assert lines == ["t 50/100  3.00/s  ETA 17 s", "t 80/100  3.00/s  ETA 7 s"]
    quiet = io.StringIO()              # not a terminal: nothing written
    q = Progress(5, stream=quiet)
    q.update(5)
    q.close()
    assert quiet.getvalue() == ""
