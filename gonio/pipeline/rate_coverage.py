"""Coverage of the rate-gyro uncertainty budgets on the virtual bench (issue 17: "coverage
checked on the bench, ≥ 90 % per item over many seeds").

:func:`coverage_study` runs a specification's programme on a rate bench for many seeds
(noise on), calibrates each readings set, and counts per item how often the bench's true
value lies within the reported expanded uncertainty, |value − truth| ≤ U. The coverage
c = hits/n is reported with its binomial standard uncertainty √(c(1 − c)/n) and the Wilson
95 % interval, and the normalised errors |value − truth|/u_c are summarised.

The bench of the study (:func:`study_bench`) is the named bench with the three
deterministic, history-dependent effects that the truth formulas of
:mod:`gonio.specs.jjf1535.truth` and :func:`gonio.specs.iec62047_20.truth.truth` leave out
switched off (power-on transient, thermal lag, cross-axis coupling of a turning Earth
rate); every random term (noise, power-cycle scatter, quantisation, equipment errors)
stays on. docs/jjf1535-readings.md#coverage-of-the-budgets states the truths used for the
noise-limited items.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

from pathlib import Path

import pandas as pd

from gonio.atomic import write_text

from gonio.errors import GonioError
from gonio.formats.rate_readings import RateReadings
from gonio.pipeline.item_coverage import two_sided
from gonio.pipeline.rate import RATE_SPECS, spec_module, spec_simulator
from gonio.specs import get

#: Wilson-interval coverage factor (95 %).
_Z95 = 1.959963984540054


@dataclass(frozen=True)
class ItemCoverage:
    """One item's coverage over the seeds."""

    key: str
    clause: str
    n: int
    hits: int
    coverage: float
    u_coverage: float
    wilson_low: float
    wilson_high: float
    median_norm_error: float
    max_norm_error: float
    cp_low: float = math.nan
    cp_high: float = math.nan
    z_mean: float | None = None
    z_sd: float | None = None
    flags: tuple = ()


def study_bench(name: str = "mems-adxrs610"):
    """The rate bench of the coverage study: ``name`` with the power-on transient, the thermal
    lag (τ = 1 s) and the cross-axis sensitivity switched off (see module docstring)."""
    from gonio.bench.rate_gyro import load_rate_bench

    b = load_rate_bench(name)
    g = replace(b.gyro, warmup_bias_dps=0.0, thermal_tau_s=1.0, cross_axis_x=0.0,
                cross_axis_y=0.0)
    return replace(b, gyro=g)


#: The reduced programme of the study ({section: {key: value}} over the built-in protocol):
#: small sample counts and short waits, every item still measured.
REDUCED = {
    "jjf1535-2015": {"protocol": {"warmup_s": 600.0},
                     "scale_factor": {"samples_below_100_dps": 5, "samples_from_100_dps": 5,
                                      "rest_samples": 5, "interval_s": 60.0},
                     "temperature": {"soak_s": 1800.0, "bias_samples": 100},
                     "threshold": {"samples": 5, "rest_samples": 5},
                     "resolution": {"samples": 5},
                     "bias": {"samples": 600, "off_time_s": 60.0},
                     "warmup": {"samples": 600, "window_samples": 100, "off_time_s": 60.0},
                     "g_sensitivity": {"samples": 60, "settle_s": 5.0},
                     "arw": {"samples": 6000},
                     "bandwidth": {"cycles": 8}},
    "iec62047-20": {"protocol": {"warmup_s": 600.0},
                    "scale_factor": {"samples": 5},
                    "temperature": {"soak_s": 1800.0, "bias_samples": 60},
                    "stability": {"samples": 50}, "bias": {"samples": 300, "off_time_s": 60.0},
                    "power_on": {"samples": 900, "off_time_s": 60.0},
                    "noise": {"samples": 6000}, "frequency": {"cycles": 8}},
}


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


def reduced_protocol(spec_key: str, path, changes: dict | None = None) -> Path:
    """Write the built-in protocol of ``spec_key`` with the study's reduced sizes
    (:data:`REDUCED`) and ``changes`` ({section: {key: value}}) to ``path``; returns it."""
    from gonio.formats.toml import read_toml
    from gonio.resources import resolve

    if spec_key not in REDUCED:
        raise GonioError(f"no reduced protocol for {spec_key!r}", key="--spec")
    d = read_toml(resolve(spec_key, kind="protocol"))
    for sec, kv in {**REDUCED[spec_key], **(changes or {})}.items():
        d.setdefault(sec, {}).update(kv)
    lines = []
    for sec, tab in d.items():
        lines.append(f"[{sec}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in tab.items()]
    write_text(Path(path), "\n".join(lines) + "\n")
    return Path(path)


def wilson_interval(hits: int, n: int, z: float = _Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion.

    >>> [round(v, 4) for v in wilson_interval(95, 100)]
    [0.8882, 0.9785]
    """
    if n < 1:
        raise GonioError("a coverage needs at least one trial")
    p = hits / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


def item_coverage(records: list[tuple[float, float, float, float]], key: str = "",
                  clause: str = "") -> ItemCoverage:
    """Coverage of one item from (value, truth, U, u_c) per seed.

    >>> c = item_coverage([(1.0, 1.1, 0.2, 0.1), (1.0, 1.3, 0.2, 0.1)])
    >>> c.hits, c.coverage, round(c.u_coverage, 4)
    (1, 0.5, 0.3536)
    """
    n = len(records)
    if n == 0:
        raise GonioError(f"item {key!r}: no seed gave a measured value with a truth")
    hits = sum(abs(v - t) <= U for v, t, U, _ in records)
    c = hits / n
    lo, hi = wilson_interval(hits, n)
    ne = sorted(abs(v - t) / u if u > 0 else (0.0 if v == t else math.inf)
                for v, t, _, u in records)
    both = two_sided([v - t for v, t, _, _ in records], [U for _, _, U, _ in records],
                     [u for _, _, _, u in records])
    return ItemCoverage(key, clause, n, hits, c, math.sqrt(c * (1 - c) / n), lo, hi,
                        ne[n // 2] if n % 2 else 0.5 * (ne[n // 2 - 1] + ne[n // 2]), ne[-1],
                        both["cp_low"], both["cp_high"], both["z_mean"], both["z_sd"],
                        tuple(both["flags"]))


def _rate_spec(spec_key: str):
    spec = get(spec_key)
    if spec.key not in RATE_SPECS:
        raise GonioError(f"{spec.key} is not a rate-gyro specification", key="--spec")
    return spec


def trial_records(spec_key: str, bench, protocol, seed: int) -> dict[str, dict]:
    """One virtual calibration (noise on): per item {clause, value, truth, U, u_c}; value
    etc. None when the item was not measured or has no truth in this trial."""
    spec = _rate_spec(spec_key)
    res = spec_simulator(spec)(bench, protocol, int(seed), noise=True)
    rd = RateReadings(res.data, {k: str(v) for k, v in res.metadata.items()})
    result = spec.calibrate(rd, protocol)
    truth = res.truth["items"]
    out = {}
    for key, it in result.items.items():
        t = truth.get(key, {}).get("value")
        ok = (it.measured and it.uncertainty is not None and t is not None
              and math.isfinite(t) and it.uncertainty.U is not None)
        out[key] = {"clause": it.clause,
                    **({"value": float(it.value), "truth": float(t),
                        "U": float(it.uncertainty.U), "u_c": float(it.uncertainty.u_c)}
                       if ok else {"value": None, "truth": None, "U": None, "u_c": None})}
    return out


def coverage_table_from(trials: list[dict], items: tuple[str, ...] | None = None) -> pd.DataFrame:
    """Per item over the trials (in order): :class:`ItemCoverage` rows."""
    recs: dict[str, list] = {}
    clauses: dict[str, str] = {}
    for tr in trials:
        for key, r in tr.items():
            if items is not None and key not in items:
                continue
            clauses[key] = r["clause"]
            if r["value"] is not None:
                recs.setdefault(key, []).append((r["value"], r["truth"], r["U"], r["u_c"]))
    rows = [item_coverage(v, k, clauses[k]).__dict__ for k, v in recs.items()]
    return pd.DataFrame(rows, columns=list(ItemCoverage.__dataclass_fields__))


def coverage_study(spec_key: str, seeds, *, bench=None, protocol=None,
                   items: tuple[str, ...] | None = None) -> pd.DataFrame:
    """Simulate (noise on) and calibrate ``spec_key`` for every seed; one row per item with
    n, hits, coverage, u_coverage (binomial), the Wilson 95 % interval and the median and
    largest |value − truth|/u_c. Items without a truth value or not measured in a seed do
    not count for that seed (``n`` says how many did)."""
    spec = _rate_spec(spec_key)
    b = bench if bench is not None else study_bench(spec.default_bench)
    proto = protocol or spec.default_protocol
    return coverage_table_from([trial_records(spec.key, b, proto, s) for s in seeds], items)


def format_coverage(df: pd.DataFrame, title: str) -> str:
    """The per-item coverage table as printed by ``gonio validate --spec`` and the benchmark."""
    lines = [title, f"{'item':32s} {'clause':10s} {'n':>4s} {'cover':>6s} "
             f"{'Clopper-Pearson 95 %':>20s} {'z mean':>7s} {'z sd':>6s} {'max|z|':>7s}"]
    for r in df.itertuples():
        flag = f"  FLAG: {', '.join(r.flags)}" if len(r.flags) else ""
        zm = "—" if r.z_mean is None or r.z_mean != r.z_mean else f"{r.z_mean:+.2f}"
        zs = "—" if r.z_sd is None or r.z_sd != r.z_sd else f"{r.z_sd:.2f}"
        lines.append(f"{r.key:32s} {r.clause:10s} {r.n:4d} {r.coverage:6.3f} "
                     f"      [{r.cp_low:.3f}, {r.cp_high:.3f}] {zm:>7s} {zs:>6s} "
                     f"{r.max_norm_error:7.2f}{flag}")
    lines.append("cover: fraction of trials with |value - truth| <= U (95 % Clopper-Pearson "
                 "interval); z = (value - truth)/u_c; flagged: coverage < 90 % (under-covers), "
                 "sd z < 0.3 (over-wide U)")
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- the study
# ``gonio validate --spec``: the trials of :func:`trial_records` run in batches through
# the engine of :mod:`gonio.pipeline.validate` (joblib locally or on Dask, batches of
# trials, trial i seeded by SeedSequence(seed, spawn_key=(spec index, i))); the records
# are put back in trial order, so the report does not depend on workers or batching.


@dataclass(frozen=True)
class RateTrialJob:
    """What a worker needs to run trials of one rate specification (picklable)."""

    spec_key: str
    bench: object
    protocol: object
    seed: int


def run_rate_batch(job: RateTrialJob, start: int, stop: int) -> list[tuple[int, int, str]]:
    """Trials ``start`` … ``stop − 1``: (index, seed, records as JSON text — lossless),
    with the numerical libraries' thread pools held to
    :data:`gonio.pipeline.validate.WORKER_THREADS`, as the optical study's batches are."""
    from threadpoolctl import threadpool_limits

    from gonio.pipeline.validate import WORKER_THREADS, spawn_seed

    key = RATE_SPECS.index(job.spec_key)
    out = []
    with threadpool_limits(limits=WORKER_THREADS):
        for i in range(start, stop):
            sd = spawn_seed(job.seed, key, i)
            out.append((i, sd, json.dumps(trial_records(job.spec_key, job.bench, job.protocol,
                                                        sd), sort_keys=True)))
    return out


@dataclass
class RateValidationReport:
    """A rate specification's coverage study: settings and the per-item table."""

    settings: dict
    coverage: pd.DataFrame

    def to_dict(self) -> dict:
        """Plain dict for ``validation.json`` (deterministic)."""
        from gonio import __version__
        return {"gonio_version": __version__, "settings": self.settings,
                "criterion": "|value - truth| <= U, U the item's own expanded uncertainty "
                             "(k = t95(nu_eff)); per item coverage >= 0.90 required and "
                             "sd of z = (value - truth)/u_c >= 0.3 (U not over-wide); "
                             "95 % Clopper-Pearson interval of the coverage",
                "items": json.loads(self.coverage.to_json(orient="records", double_precision=15))}

    def table(self) -> str:
        s = self.settings
        return format_coverage(self.coverage, f"{s['spec']}: {s['trials']} trials, seed "
                                              f"{s['seed']}, protocol {s['protocol']}, bench "
                                              f"{s['bench']} (study settings)")


def rate_validate(spec_key: str, trials: int, *, seed: int = 0, bench: str | None = None,
                  protocol: str | None = None, workers: int | None = None,
                  scheduler: str | None = None, batch_size: int | None = None,
                  show_progress: bool = True) -> RateValidationReport:
    """Coverage of every item of a rate specification over ``trials`` virtual calibrations.

    ``bench``: a rate bench name or file (default the specification's), made a study bench
    (:func:`study_bench`); ``protocol``: a protocol file or name (default: the built-in
    protocol reduced to :data:`REDUCED`). Runs through joblib (``workers`` local processes
    or a Dask ``scheduler``, ``batch_size`` trials per task); trial i is seeded by
    SeedSequence(``seed``, spawn_key=(spec index, i)), so the report is the same on any
    number of workers and any batching.
    """
    import tempfile

    from gonio.limits import check
    from gonio.pipeline.validate import run_parallel, study_workers
    from gonio.progress import Progress

    spec = _rate_spec(spec_key)
    if not isinstance(trials, int) or trials < 2:
        raise GonioError(f"--trials must be an integer >= 2, got {trials}", key="trials")
    check("GONIO_MAX_TRIALS", trials, "--trials", unit="calibrations")
    if seed < 0:
        raise GonioError(f"--seed must be >= 0, got {seed}", key="seed")
    workers, batch_size = study_workers(trials, workers, scheduler, batch_size)
    mod = spec_module(spec)
    b = study_bench(bench or spec.default_bench)
    if protocol is None:
        with tempfile.TemporaryDirectory() as d:
            proto = mod.load_protocol(str(reduced_protocol(spec.key, Path(d) / "reduced.toml")))
        proto_name = f"{spec.key} reduced (gonio.pipeline.rate_coverage.REDUCED)"
    else:
        proto = mod.load_protocol(protocol)
        proto_name = str(protocol)
    job = RateTrialJob(spec.key, b, proto, int(seed))
    tasks = [(job, a, min(a + batch_size, trials)) for a in range(0, trials, batch_size)]
    done: dict[int, dict] = {}
    prog = Progress(trials, label="validate: trials", force=False) if show_progress else None
    try:
        for batch in run_parallel(run_rate_batch, tasks, workers, scheduler):
            for i, _, text in batch:
                done[i] = json.loads(text)
            if prog is not None:
                prog.update(len(batch))
    finally:
        if prog is not None:
            prog.close()
    settings = {"spec": spec.key, "trials": trials, "seed": int(seed), "bench": b.name,
                "study_bench": "power-on transient, thermal lag and cross-axis switched off "
                               "(gonio.pipeline.rate_coverage.study_bench)",
                "protocol": proto_name,
                "seeding": "numpy SeedSequence(seed, spawn_key=(spec index, trial index))"}
    return RateValidationReport(settings, coverage_table_from([done[i] for i in range(trials)]))
