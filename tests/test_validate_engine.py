"""The validation's execution engine: batches on joblib and on Dask give the same bytes; an
interrupted study keeps its finished batches and --resume neither repeats nor loses a trial."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

import gonio.pipeline.validate as V
import gonio.specs.ogam_draft.study as S
from gonio.cli import main
from gonio.progress import Progress
# (bench and tiny_protocol: also read by the fuzz tests from this module)
from tests._helpers import small_ogam_bench as bench, tiny_ogam_protocol as tiny_protocol


def run(**kw):
    r = V.validate(kw.pop("trials", 6), seed=3, bench=bench(), protocol=tiny_protocol(),
                   sample_rate_hz=10.0, show_progress=False, **kw)
    return json.dumps(r.to_dict(), indent=2, allow_nan=False)


def test_seeds_by_trial_index_match_spawned_children():
    # SeedSequence(seed, spawn_key=(case, i)) is the i-th spawned child (numpy's own spawn).
    for case_i, case in enumerate(S.CASES):
        kids = np.random.SeedSequence(11, spawn_key=(case_i,)).spawn(5)
        assert [S.trial_seed(11, case, i) for i in range(5)] == \
            [int(k.generate_state(1, np.uint32)[0]) for k in kids]


def test_bytes_identical_for_workers_batches_and_a_dask_cluster():
    pytest.importorskip("distributed")
    one = run(workers=1, batch_size=6)
    assert run(workers=1, batch_size=4) == one
    assert run(workers=2, batch_size=3) == one
    assert run(scheduler="local:2", batch_size=2) == one
    # the trials really differ (a seed change changes the bytes)
    assert json.loads(one)["cases"][0]["seeds_first"] == \
        [S.trial_seed(3, "default", i) for i in range(3)]


def test_local_cluster_workers_run_with_the_quiet_settings():
    """Issue 26: the worker processes of ``local:N`` run with the engine's settings (the
    profiler off, the event-loop tick, memory and system monitors slowed), not Dask's
    defaults (True, 20 ms, 100 ms, 500 ms), and without the nanny's MALLOC_TRIM_THRESHOLD_
    (set at all, it switches off glibc's dynamic mmap threshold: 3× the system time):
    read back in a worker through the trial path."""
    pytest.importorskip("distributed")
    import os

    import dask
    from dask.utils import parse_timedelta
    from gonio.pipeline.engine import LOCAL_CLUSTER_CONFIG, run_parallel
    keys = sorted(k for k, v in LOCAL_CLUSTER_CONFIG.items() if v is not None)
    if "MALLOC_TRIM_THRESHOLD_" in os.environ:
        pytest.skip("this process's environment sets MALLOC_TRIM_THRESHOLD_ itself")
    # local:2: with one worker joblib runs the tasks in this process (its n_jobs = 1)
    got = list(run_parallel(dask.config.get, [(k,) for k in keys], None, "local:2"))
    assert sorted(map(str, got)) == sorted(str(LOCAL_CLUSTER_CONFIG[k]) for k in keys)
    assert sorted(map(str, got)) != sorted(str(dask.config.get(k)) for k in keys)
    env = list(run_parallel(os.environ.get, [("MALLOC_TRIM_THRESHOLD_",)] * 2, None,
                            "local:2"))
    assert env == [None, None]
    assert dask.config.get("distributed.nanny.pre-spawn-environ")["MALLOC_TRIM_THRESHOLD_"]
    assert LOCAL_CLUSTER_CONFIG["distributed.worker.profile.enabled"] is False
    assert min(parse_timedelta(v) for k, v in LOCAL_CLUSTER_CONFIG.items()
               if "interval" in k) >= 1.0 and len(keys) == 4


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


def test_study_stopped_before_its_first_batch_does_not_block_the_rerun(tmp_path, monkeypatch):
    """Hostile round 3: a study that finished no batch (a cluster that never answered, a
    Ctrl-C at start-up) left a study.json that refused the corrected rerun without
    --resume; nothing is lost by starting afresh, so it no longer does. A study with a
    finished batch, or an unreadable record, still refuses (the test above)."""
    ref = run(workers=1, batch_size=2)
    real = V.run_batch

    def stop(job, a, b):
        raise KeyboardInterrupt

    monkeypatch.setattr(V, "run_batch", stop)
    part = tmp_path / V.PARTIAL_DIR
    with pytest.raises(KeyboardInterrupt):
        run(workers=1, batch_size=2, partial_dir=part)
    assert [p.name for p in part.iterdir()] == ["study.json"]
    monkeypatch.setattr(V, "run_batch", real)
    assert run(workers=1, batch_size=2, partial_dir=part) == ref
    (part / "study.json").write_text("[]", encoding="utf-8")      # unreadable: still refused
    with pytest.raises(V.GonioError, match="--resume"):
        run(workers=1, batch_size=2, partial_dir=part)


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


@pytest.mark.parametrize("scheduler", ["local:100000", "local:3"])
def test_local_cluster_capped_at_the_cores_before_anything_starts(monkeypatch, scheduler):
    """issue 26: `--scheduler local:100000` ran for minutes, > 1.5 GB, no result; local:64
    on 2 cores printed ~140 lines of tracebacks. Refused at once, one line naming the key."""
    import time

    monkeypatch.delenv("GONIO_MAX_WORKERS", raising=False)
    monkeypatch.setattr(V, "available_cores", lambda: 2)
    t0 = time.perf_counter()
    with pytest.raises(V.GonioError) as e:
        V.validate(4, seed=3, bench=bench(), protocol=tiny_protocol(), sample_rate_hz=10.0,
                   show_progress=False, scheduler=scheduler)
    assert time.perf_counter() - t0 < 5
    assert e.value.key == "scheduler" and "2 cores" in str(e.value)
    assert "\n" not in str(e.value) and "GONIO_MAX_WORKERS" in str(e.value)
    buf = io.StringIO()
    import contextlib
    with contextlib.redirect_stderr(buf):
        assert main(["validate", "--trials", "4", "--scheduler", scheduler]) == 2
    assert len(buf.getvalue().strip().splitlines()) == 1 and "Traceback" not in buf.getvalue()
    monkeypatch.setenv("GONIO_MAX_WORKERS", "100000")      # the cap can be raised
    assert V.study_workers(4, None, scheduler, None)[1] >= 1


def test_default_batches_give_several_tasks_per_worker(monkeypatch):
    """The default batch size comes from the trials and the workers: about 4 tasks per
    worker over all cases (issue 26: 320 trials must not become 2 tasks for 16 workers)."""
    monkeypatch.setenv("GONIO_MAX_WORKERS", "64")
    for trials, workers, cases in [(320, 16, 1), (3200, 16, 1), (320, 16, 5), (50, 2, 1),
                                   (100_000, 16, 1)]:
        _, b = V.study_workers(trials, workers, None, None, cases)
        tasks = cases * len(V.batches(range(trials), b))
        assert tasks >= min(trials * cases, 4 * workers), (trials, workers, cases, b)
        assert b <= V.MAX_BATCH
    _, b = V.study_workers(320, None, "local:16", None)
    assert len(V.batches(range(320), b)) >= 4 * 16


def test_bytes_identical_with_default_batches_on_any_workers():
    one = run(workers=1)
    assert run(workers=2) == one
    assert run(workers=2, batch_size=1) == one


def test_cluster_by_address_sized_by_its_workers_and_reused(monkeypatch):
    """issue 26: a study on a cluster given by its address cuts its default batches for the
    cluster's own worker count (not a guess of 2: 320 trials on 16 workers must not be 8
    tasks), and a second study on the same cluster reuses the client and its warmed
    workers; the bytes stay those of one local worker."""
    pytest.importorskip("distributed")
    import logging

    import gonio.pipeline.engine as E
    from distributed import LocalCluster

    _, b = V.study_workers(320, None, "tcp://127.0.0.1:1", None, 1, cluster_workers=16)
    assert len(V.batches(range(320), b)) >= 4 * 16
    assert V.study_workers(320, None, "tcp://127.0.0.1:1", None)[1] == 40   # before connecting
    sizes = []
    real = E.study_workers
    monkeypatch.setattr(V, "study_workers", lambda *a, **k: sizes.append(a) or real(*a, **k))
    one = run(workers=1)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.ERROR) as cluster:
        addr = cluster.scheduler_address
        try:
            assert run(scheduler=addr) == one
            client = E._CLIENTS[addr]
            warmed = set(E._WARMED[addr])
            assert len(warmed) == 2 and sizes[-1][-1] == 2      # the cluster's own count
            assert run(scheduler=addr) == one
            assert E._CLIENTS[addr] is client and E._WARMED[addr] == warmed
        finally:
            E._forget(addr)
