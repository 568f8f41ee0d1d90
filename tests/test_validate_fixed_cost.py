"""What a coverage study pays once, kept small: one local worker runs its batches without
joblib, a Clopper–Pearson interval is computed once per (hits, n), and a study's report
computes each per-item table once for validation.json and the printed table."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from scipy.stats import beta

from gonio.analysis.coverage import _clopper_pearson, clopper_pearson
from gonio.pipeline.engine import run_parallel

ROOT = Path(__file__).resolve().parents[1]


def test_one_worker_runs_the_tasks_in_order_here():
    calls = []

    def fn(a, b):
        calls.append((a, b))
        return a * 10 + b

    tasks = [(1, 2), (3, 4), (0, 5)]
    assert list(run_parallel(fn, tasks, 1, None)) == [12, 34, 5]
    assert calls == tasks
    # tasks as a function of the worker count: called with one worker
    seen = []
    assert list(run_parallel(fn, lambda n: seen.append(n) or tasks[:1], 1, None)) == [12]
    assert seen == [1]
    # lazily: a task that fails stops the study where it fails, the earlier ones done
    def fail_on_second(a, b):
        if a == 3:
            raise KeyboardInterrupt
        return a

    got = run_parallel(fail_on_second, tasks, 1, None)
    assert next(got) == 1
    with pytest.raises(KeyboardInterrupt):
        next(got)


def test_two_workers_give_the_same_results_through_joblib():
    tasks = [(i, i + 1) for i in range(6)]
    one = list(run_parallel(pow, tasks, 1, None))
    two = sorted(run_parallel(pow, tasks, 2, None))
    assert sorted(one) == two == sorted(a ** b for a, b in tasks)


def test_a_one_worker_study_does_not_import_joblib(tmp_path):
    code = textwrap.dedent(f"""
        import sys
        from gonio.cli import main
        rc = main(["validate", "--spec", "ogam-draft", "--trials", "2", "--workers", "1",
                   "--sample-rate-hz", "5", "--out", {str(tmp_path / "o")!r}])
        assert rc == 0, rc
        assert "joblib" not in sys.modules, "a one-worker study imported joblib"
        print("ok")
    """)
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0 and r.stdout.strip().endswith("ok"), r.stderr[-2000:]
    assert (tmp_path / "o" / "validation.json").is_file()


@pytest.mark.parametrize("hits,n", [(0, 2), (2, 2), (1, 3), (95, 100), (190, 200), (40, 40)])
def test_clopper_pearson_is_the_exact_interval_and_kept(hits, n):
    # the exact interval in closed form: beta quantiles (Clopper and Pearson 1934)
    lo = 0.0 if hits == 0 else beta.ppf(0.025, hits, n - hits + 1)
    hi = 1.0 if hits == n else beta.ppf(0.975, hits + 1, n - hits)
    got = clopper_pearson(hits, n)
    assert got == pytest.approx((lo, hi), abs=1e-9)
    before = _clopper_pearson.cache_info().hits
    assert clopper_pearson(hits, n) == got and clopper_pearson(float(hits), n) == got
    assert _clopper_pearson.cache_info().hits == before + 2


def test_no_trials_no_interval():
    lo, hi = clopper_pearson(0, 0)
    assert lo != lo and hi != hi


def test_the_triad_report_computes_each_table_once(monkeypatch):
    import gonio.specs.triad_alignment.study as S

    calls = []
    real = S.coverage_table_from

    def counted(*a, **kw):
        calls.append(kw.get("judge_spread"))
        return real(*a, **kw)

    monkeypatch.setattr(S, "coverage_table_from", counted)
    trial = {"items": {"m_xy": {"clause": "c", "value": 1.0, "truth": 1.1, "U": 0.3,
                                "u_c": 0.15}}, "no_truth": []}
    case = next(c for c in S.CASES if not c.startswith("worst"))
    rep = S.TriadReport({"trials": 2, "seed": 0, "protocol": "p", "bench": "b"},
                        {case: [trial, trial]})
    d = rep.to_dict()
    text = rep.table()
    assert len(calls) == 1
    row = d["cases"][case]["items"][0]
    assert row["hits"] == 2 and row["n"] == 2 and "m_xy" in text
