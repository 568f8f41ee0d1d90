"""The item coverage study of any specification (``gonio validate --spec KEY`` where
``SPEC.coverage.engine == "items"``): coverage checked on the bench, per item, over many
seeds.

:func:`coverage_study` runs a specification's programme on its study bench for many seeds
(noise on; ``SPEC.run_trial``), calibrates each readings set (``SPEC.calibrate``), and
counts per item how often the bench's true value (``truth["items"][key]["value"]``, from the
bench's physical parameters) lies within the reported expanded uncertainty,
|value − truth| ≤ U. The coverage c = hits/n is reported with its binomial standard
uncertainty √(c(1 − c)/n) and the Wilson 95 % interval, and the normalised errors
|value − truth|/u_c are summarised (:func:`gonio.analysis.coverage.item_coverage`, the
statistics every study of ``gonio validate`` uses).

The study's bench is ``SPEC.coverage.study_bench(name)`` (a specification switches off there
what its truth leaves out) and its programme the built-in protocol changed by
``SPEC.coverage.reduced``. A specification's clause document states the truths it uses for
its noise-limited items.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.analysis.coverage import (ItemCoverage, bound_record, coverage_table_from,
                                     format_coverage, item_coverage, level_z_at,
                                     level_z_discrete, spawn_seed, stated_record,
                                     wilson_interval)
from gonio.atomic import write_text
from gonio.errors import GonioError
from gonio.pipeline.dispatch import screen_and_calibrate
from gonio.specs import Specification, get

__all__ = ["coverage_study", "coverage_validate", "coverage_table_from", "trial_records",
           "reduced_protocol", "study_bench", "format_coverage", "CoverageReport", "TrialJob",
           "run_batch", "ItemCoverage", "item_coverage", "wilson_interval"]

def study_bench(spec: Specification, name=None, case: str | None = None):
    """The bench of ``spec``'s coverage study: ``name`` (default the specification's bench)
    through ``SPEC.coverage.study_bench`` (``case``: one of ``SPEC.coverage.cases``, passed
    on as its ``case`` keyword; None: the study bench's own default)."""
    name = name or spec.default_bench
    if not spec.coverage.study_bench:
        return name
    return spec.coverage.study_bench(name) if case is None else \
        spec.coverage.study_bench(name, case=case)


#: The case of an item study whose trials keep the seeding the study had before it had
#: cases (spawn key = ``SPEC.coverage.stream``); every other case ``c`` of
#: ``SPEC.coverage.cases`` (in its order, 1, 2, …) draws from the spawn key
#: ``CASE_STREAM_STEP``·index + stream: one trial set per case, none sharing draws.
CASE_STREAM_STEP = 16


def study_cases(spec: Specification, cases) -> list[str]:
    """The cases of ``spec``'s item study asked for: None → the first of
    ``SPEC.coverage.cases`` (or the one unnamed case of a study without cases), the
    command line's text (comma-separated, or ``all``) or a sequence of names; an unknown
    one is a GonioError naming the known ones."""
    known = list(spec.coverage.cases)
    if cases is None:
        return known[:1] or [""]
    if not known:
        raise GonioError(f"--cases does not apply to 'gonio validate --spec {spec.key}' (its "
                         "item study has no cases)", key="cases")
    if isinstance(cases, str):
        cases = known if cases.strip() == "all" else \
            [c.strip() for c in cases.split(",") if c.strip()]
    cases = list(dict.fromkeys(cases))
    if not cases:
        raise GonioError("no cases given", key="cases")
    for c in cases:
        if c not in known:
            raise GonioError(f"unknown case {c!r} of {spec.key} (known: {', '.join(known)})",
                             key="cases")
    return cases


def case_stream(spec: Specification, case: str) -> int:
    """The spawn key of ``case``'s trials (:data:`CASE_STREAM_STEP`)."""
    known = list(spec.coverage.cases)
    i = known.index(case) if case in known else 0
    return spec.coverage.stream + CASE_STREAM_STEP * i


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


def reduced_protocol(spec_key: str, path, changes: dict | None = None) -> Path:
    """Write the built-in protocol of ``spec_key`` with the study's programme
    (``SPEC.coverage.reduced``) and ``changes`` ({section: {key: value}}) to ``path``;
    returns it."""
    from gonio.formats.toml import read_toml
    from gonio.resources import resolve

    spec = _studied(spec_key)
    d = read_toml(resolve(spec.default_protocol, kind="protocol"))
    for sec, kv in {**spec.coverage.reduced, **(changes or {})}.items():
        d.setdefault(sec, {}).update(kv)
    lines = []
    for sec, tab in d.items():
        lines.append(f"[{sec}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in tab.items()]
    write_text(Path(path), "\n".join(lines) + "\n")
    return Path(path)


def _studied(spec_key: str) -> Specification:
    """The specification, refused when it has no item coverage study."""
    spec = get(spec_key)
    if spec.coverage is None or spec.coverage.engine != "items" or spec.run_trial is None:
        raise GonioError(f"{spec.key} has no item coverage study (SPEC.coverage, "
                         "SPEC.run_trial)", key="--spec")
    return spec


def trial_records(spec_key: str, bench, protocol, seed: int) -> dict[str, dict]:
    """One virtual calibration (noise on): per item {clause, value, truth, U, u_c} and, for
    an item stated by its interval alone, {interval, nu}
    (:func:`gonio.analysis.coverage.stated_record`); value etc. None
    when the item was not measured or has no truth in this trial."""
    spec = _studied(spec_key)
    readings, truth_d = spec.run_trial(bench, protocol, int(seed))
    result = screen_and_calibrate(spec, readings, protocol)
    truth = truth_d["items"]
    out = {}
    for key, it in result.items.items():
        t = truth.get(key, {}).get("value")
        ok = (it.measured and it.uncertainty is not None and t is not None
              and math.isfinite(t) and it.uncertainty.U is not None)
        out[key] = {"clause": it.clause,
                    **({"value": float(it.value), "truth": float(t),
                        "U": float(it.uncertainty.U), "u_c": float(it.uncertainty.u_c),
                        **stated_record(it.uncertainty), **bound_record(it),
                        **_level_record(it, float(t) if ok else None, int(seed), key)}
                       if ok else {"value": None, "truth": None, "U": None, "u_c": None})}
    return out


def _level_record(it, truth, seed: int, key: str) -> dict:
    """{"z_level": the interval's level z at the truth} for an item stated by an interval
    whose details give its level table (``level_z_grid``,
    :func:`gonio.analysis.coverage.level_z_at`) or its discrete stated distribution
    (``level_distribution``, :func:`gonio.analysis.coverage.level_z_discrete`, its uniform
    v drawn from SeedSequence(seed, spawn_key=(crc32 of the item's key,)): the same seed,
    the same z); {} otherwise."""
    import zlib

    u = it.uncertainty
    if u is None or u.k is not None or u.interval is None:
        return {}
    d = it.details or {}
    z = level_z_at(d.get("level_z_grid"), truth)
    if z is None and d.get("level_distribution"):
        ss = np.random.SeedSequence(int(seed), spawn_key=(zlib.crc32(key.encode()),))
        v = float(np.random.default_rng(ss).random())
        z = level_z_discrete(d["level_distribution"], truth, v)
    return {} if z is None else {"z_level": z}


def coverage_study(spec_key: str, seeds, *, bench=None, protocol=None,
                   items: tuple[str, ...] | None = None) -> pd.DataFrame:
    """Simulate (noise on) and calibrate ``spec_key`` for every seed; one row per item with
    n, hits, coverage, u_coverage (binomial), the Wilson 95 % interval and the median and
    largest |value − truth|/u_c. Items without a truth value or not measured in a seed do
    not count for that seed (``n`` says how many did)."""
    spec = _studied(spec_key)
    b = bench if bench is not None else study_bench(spec)
    proto = protocol or spec.default_protocol
    return coverage_table_from([trial_records(spec.key, b, proto, s) for s in seeds], items)


# ----------------------------------------------------------------------------- the study
# ``gonio validate --spec``: the trials of :func:`trial_records` run in batches through
# the engine of :mod:`gonio.pipeline.engine` (joblib locally or on Dask, batches of
# trials, trial i seeded by SeedSequence(seed, spawn_key=(spec index, i))); the records
# are put back in trial order, so the report does not depend on workers or batching.


@dataclass(frozen=True)
class TrialJob:
    """What a worker needs to run trials of one specification (picklable)."""

    spec_key: str
    bench: object
    protocol: object
    seed: int
    stream: int | None = None        # spawn key of the trials (None: SPEC.coverage.stream)


def run_batch(job: "TrialJob", start: int, stop: int) -> list[tuple[int, int, str, int]]:
    """Trials ``start`` … ``stop − 1``: (index, seed, records as JSON text — lossless, the
    trials' spawn key),
    with the numerical libraries' thread pools held to
    :data:`gonio.pipeline.engine.WORKER_THREADS`, as the optical study's batches are."""
    from threadpoolctl import threadpool_limits

    from gonio.pipeline.engine import WORKER_THREADS

    key = get(job.spec_key).coverage.stream if job.stream is None else job.stream
    out = []
    with threadpool_limits(limits=WORKER_THREADS):
        for i in range(start, stop):
            sd = spawn_seed(job.seed, key, i)
            out.append((i, sd, json.dumps(trial_records(job.spec_key, job.bench, job.protocol,
                                                        sd), sort_keys=True), key))
    return out


@dataclass
class CoverageReport:
    """A specification's item coverage study: settings and the per-item table (one case), or
    a table per case (``cases``: case → table; ``coverage`` then the first case's)."""

    settings: dict
    coverage: pd.DataFrame
    cases: dict | None = None

    CRITERION = ("|value - truth| <= U, U the item's own expanded uncertainty "
                 "(k = t95(nu_eff)), or for an item stated by its interval alone "
                 "(k none) the truth inside that interval; per item coverage >= "
                 "0.90 required and sd of z >= 0.3 (U not over-wide), z = (value "
                 "- truth)/u_c or, for a standard deviation stated by its "
                 "chi-square interval (statistic 'chi-square'), "
                 "Phi^-1(F_chi2(nu value^2/truth^2; nu)) with z on u_c kept as "
                 "z_uc_mean, z_uc_sd, max_norm_error_uc; "
                 "95 % Clopper-Pearson interval of the coverage")
    FIXED_CRITERION = ("; a case at one fixed condition (each Type B effect at its bound) is "
                       "judged on coverage only: a Type B line is one fixed offset there, so "
                       "z's spread is information, not a test")

    def to_dict(self) -> dict:
        """Plain dict for ``validation.json`` (deterministic): ``items`` for one case,
        ``cases`` {case: items} for several."""
        from gonio import __version__

        def rows(df):
            return json.loads(df.to_json(orient="records", double_precision=15))
        fixed = bool(self.settings.get("fixed_condition_cases"))
        out = {"gonio_version": __version__, "settings": self.settings,
               "criterion": self.CRITERION + (self.FIXED_CRITERION if fixed else "")}
        if self.cases is not None and len(self.cases) > 1:
            out["cases"] = {c: rows(df) for c, df in self.cases.items()}
        else:
            out["items"] = rows(self.coverage)
        return out

    def table(self) -> str:
        s = self.settings
        head = (f"{s['spec']}: {s['trials']} trials, seed {s['seed']}, protocol "
                f"{s['protocol']}, bench {s['bench']} (study settings)")
        if self.cases is None:
            return format_coverage(self.coverage, head)
        return "\n".join(format_coverage(df, f"{head}, case {c}: "
                                             f"{s['case_descriptions'][c]}")
                         for c, df in self.cases.items())


def _study_protocol(spec: Specification, protocol):
    """(the loaded protocol of ``spec``'s item study, its name in the settings)."""
    import tempfile

    load = spec.load_protocol or (lambda p: p)
    if protocol is None and not spec.coverage.reduced:
        return load(spec.default_protocol), spec.default_protocol
    if protocol is None:
        with tempfile.TemporaryDirectory() as d:
            proto = load(str(reduced_protocol(spec.key, Path(d) / "reduced.toml")))
        return proto, f"{spec.key} reduced (SPEC.coverage.reduced)"
    return load(protocol), str(protocol)


def coverage_validate(spec_key: str, trials: int, *, seed: int = 0, bench: str | None = None,
                  protocol: str | None = None, workers: int | None = None,
                  scheduler: str | None = None, batch_size: int | None = None,
                  show_progress: bool = True, cases=None) -> CoverageReport:
    """Coverage of every item of a specification over ``trials`` virtual calibrations (per
    case).

    ``bench``: a bench name or file (default the specification's), made a study bench
    (:func:`study_bench`); ``protocol``: a protocol file or name (default: the built-in
    protocol with the study's programme, ``SPEC.coverage.reduced``); ``cases``: the study
    cases (``SPEC.coverage.cases``; :func:`study_cases`: None → the first, e.g. the rate
    specifications' ``typeb``). Runs through joblib (``workers`` local processes or a Dask
    ``scheduler``, ``batch_size`` trials per task); trial i of a case is seeded by
    SeedSequence(``seed``, spawn_key=(:func:`case_stream`, i)) — the first case's key is
    ``SPEC.coverage.stream`` — so the report is the same on any number of workers and any
    batching. A case named in ``SPEC.coverage.fixed_cases`` (one fixed condition) is judged
    on coverage only (no ``over-wide`` flag).
    """
    from gonio.limits import check
    from gonio.pipeline.engine import run_parallel, study_workers
    from gonio.progress import Progress

    spec = _studied(spec_key)
    if not isinstance(trials, int) or trials < 2:
        raise GonioError(f"--trials must be an integer >= 2, got {trials}", key="trials")
    check("GONIO_MAX_TRIALS", trials, "--trials", unit="calibrations")
    if seed < 0:
        raise GonioError(f"--seed must be >= 0, got {seed}", key="seed")
    names = study_cases(spec, cases)
    workers, batch_size = study_workers(trials, workers, scheduler, batch_size, len(names))
    proto, proto_name = _study_protocol(spec, protocol)
    benches = {c: study_bench(spec, bench, c or None) for c in names}
    tasks = [(TrialJob(spec.key, benches[c], proto, int(seed), case_stream(spec, c)), a,
              min(a + batch_size, trials)) for c in names for a in range(0, trials, batch_size)]
    done: dict[int, dict[int, dict]] = {}
    prog = Progress(trials * len(names), label="validate: trials", force=False) \
        if show_progress else None
    try:
        for batch in run_parallel(run_batch, tasks, workers, scheduler):
            for i, _, text, stream in batch:
                done.setdefault(stream, {})[i] = json.loads(text)
            if prog is not None:
                prog.update(len(batch))
    finally:
        if prog is not None:
            prog.close()
    b = benches[names[0]]
    fixed = [c for c in names if c in spec.coverage.fixed_cases]
    settings = {"spec": spec.key, "trials": trials, "seed": int(seed),
                "bench": getattr(b, "name", str(b)),
                "study_bench": f"SPEC.coverage.study_bench = {spec.coverage.study_bench!r}"
                if spec.coverage.study_bench else "the bench as loaded",
                "protocol": proto_name,
                "equipment": "type-B errors drawn per trial from the trial's seed "
                             "(gonio.bench.equipment.draw_equipment)"
                if getattr(b, "draw_equipment", False) else "as the bench states",
                "seeding": f"numpy SeedSequence(seed, spawn_key=({spec.coverage.stream}, "
                           "trial index))"}
    if names != [""] and (len(names) > 1 or names[0] != list(spec.coverage.cases)[0]):
        settings.update({
            "cases": names, "case_descriptions": {c: spec.coverage.cases[c] for c in names},
            "fixed_condition_cases": fixed,
            "equipment": {c: spec.coverage.cases[c] for c in names},
            "seeding": {c: f"numpy SeedSequence(seed, spawn_key=({case_stream(spec, c)}, "
                           "trial index))" for c in names}})
    tables = {c: coverage_table_from([done[case_stream(spec, c)][i] for i in range(trials)],
                                     judge_spread=c not in fixed) for c in names}
    if "cases" not in settings:
        return CoverageReport(settings, tables[names[0]])
    return CoverageReport(settings, tables[names[0]], tables)
