"""The triad's coverage study (``gonio validate --spec triad-alignment``; ``SPEC.coverage.study``):
every certified item of the built-in programme — the system matrix M_ij, the biases b_i, the
cross-axis sensitivities S_ij, the residual leakage L_ij and the thermal values K(ϑ, U),
b(ϑ, U), ARW(ϑ) at the programme's set points — over many simulated calibrations, each against
the bench's own truth (``SPEC.truth``: its physical parameters in closed form, no estimator),
in two cases of what the laboratory knows of its rate table:

``typeb``
    the table's Type B errors drawn per trial from what its certificate and the fixture's
    bound state (:func:`gonio.specs.triad_alignment.simulate.for_trial`): the rate error
    normal with the certificate's u, each component of the spin axis's error δ_a at each
    orientation uniform within the fixture's bound. Coverage and the spread of z are both
    the test.
``worst``
    the table at its bounds with the worst signs (:func:`worst_table`): the rate error at the
    certificate's expanded uncertainty (k = 2, :data:`RATE_ERROR_BOUND_K`), every component
    of every δ_a at the fixture's bound, the signs chosen where the first-order bias they give
    the fitted M, measured in the table's own standard uncertainty per item, is largest. One
    fixed condition: coverage is the test; z's mean shows the offset the condition puts in,
    and z's spread is that of the noise alone.
``worst-axes``
    the reading of "worst" the optical draft's study takes (its tilt at the bound, the other
    Type B effects drawn): the bounded errors — every δ_aj at the fixture's bound, signs as
    above — at their bounds, the rate error, a normal error with no bound, drawn per trial.

A fixed error at k = 2 standard uncertainties meets an expanded uncertainty U ≈ 2 u_c of which
it is nearly the whole: the items whose U the rate error dominates (M_ii and every K) then sit
at z ≈ +2 and cover about half the trials in ``worst`` by construction; the report states, per
M item of the two worst cases, the closed-form offset the condition gives
(:func:`table_bias` / u_c, ``table_offset_z``) beside the measured z mean.

The trial (:func:`triad_trial`) runs the programme with ``SPEC.simulate`` (readings and the
chamber programme written as ``gonio simulate`` writes them), screens and calibrates them as
``gonio calibrate`` does (BIC orders, sensor temperature, no Monte Carlo), and compares every
item that has a truth; L_ij against what the trial's alignment really leaves
(:func:`realised_leakage`). The engine of :mod:`gonio.pipeline.validate` runs the trials in
batches (joblib or Dask, partial results, resume); trial i of a case is seeded by
``SeedSequence(seed, spawn_key=(CASE_KEYS[case], i))``, so validation.json is byte-identical
for any number of workers and any batching.
"""

from __future__ import annotations

import itertools
import json
import math
import tempfile
from dataclasses import dataclass, field, replace
from typing import Mapping

import numpy as np

from gonio.analysis.coverage import (bound_record, coverage_table_from, format_coverage,
                                     spawn_seed, stated_record)
from gonio.errors import GonioError
from gonio.specs.triad_alignment.analysis import RATE_ERROR_BOUND_K, table_type_b_cov
from gonio.specs.triad_alignment.bench import TriadBench, load_triad_bench, load_triad_protocol
from gonio.specs.triad_alignment.simulate import for_trial

__all__ = ["CASES", "CASE_KEYS", "GUM_SUFFIX", "gum_record", "FIXED_CONDITION_CASES", "RATE_ERROR_BOUND_K", "worst_table",
           "table_bias", "case_bench", "triad_trial", "realised_leakage", "TriadJob", "TriadStudy",
           "TriadReport", "plan_study"]

#: The study's cases (see the module docstring).
CASES = {
    "typeb": "the rate table's Type B errors drawn per trial: its rate error normal with the "
             "certificate's u (rate_table_u_rel), each component of its spin axis's error at "
             "each orientation uniform within the fixture's bound (orientation_bound_deg)",
    "worst": "the rate table at its bounds with the worst signs: rate error at the "
             "certificate's expanded uncertainty (k = 2), every axis-error component at the "
             "fixture's bound, the signs that bias the fitted M most in the table's own u "
             "(worst_table); one fixed condition, noise drawn per trial",
    "worst-axes": "the bounded errors at their bounds, the unbounded one drawn: every "
                  "axis-error component at the fixture's bound with the signs that bias the "
                  "fitted M most (worst_table at zero rate error), the rate error drawn per "
                  "trial (normal, the certificate's u; a normal error has no bound)",
}

#: The seed stream of each case: trial i of ``case`` is seeded by
#: SeedSequence(seed, spawn_key=(CASE_KEYS[case], i)) (``SPEC.coverage.stream`` = 2, times 16,
#: plus the case's place: no other study's stream).
CASE_KEYS = {"typeb": 32, "worst": 33, "worst-axes": 34}

#: Cases with the table's bounded errors fixed at one condition (the worst): there the axis
#: errors' Type B part of U is one fixed offset, z's spread is the noise's (and in
#: ``worst-axes`` the drawn rate error's) alone, so coverage is their test and the spread is
#: not flagged (:func:`gonio.analysis.coverage.coverage_table_from`'s ``judge_spread``).
FIXED_CONDITION_CASES = ("worst", "worst-axes")



def table_bias(m: np.ndarray, rate_error_rel: float,
               orientation_error_rad: np.ndarray) -> np.ndarray:
    """The first-order bias (3 × 3) the table's errors give the fitted M (the model of
    :func:`gonio.specs.triad_alignment.analysis.table_type_b_cov`): column a moves by
    M_·a ε + Σ_{j ≠ a} M_·j δ_aj, δ_a = ``orientation_error_rad[a]``.

    >>> round(float(table_bias(np.diag([2.0, 3.0, 4.0]), 0.1, np.zeros((3, 3)))[1, 1]), 12)
    0.3
    >>> float(table_bias(np.diag([2.0, 3.0, 4.0]), 0.0, np.array([[0, 0, 0], [0.01, 0, 0],
    ...                                                             [0, 0, 0]]))[0, 1])
    0.02
    """
    m = np.asarray(m, dtype=float)
    d = np.asarray(orientation_error_rad, dtype=float)
    return m * rate_error_rel + np.column_stack([m @ d[a] for a in range(3)])


def worst_table(bench, rate_error_rel: float | None = None) -> TriadBench:
    """``bench`` (a name, path or :class:`TriadBench`) with its rate table at the bounds the
    study's ``worst`` case takes: ε = :data:`RATE_ERROR_BOUND_K` × ``rate_table_u_rel`` and
    every component δ_aj (j ≠ a) at ±``orientation_bound_deg``, the signs those of the 2⁶
    (ε's own sign is immaterial: flipping every sign flips every bias) that maximise
    Σ_ia (bias_ia / u_b,ia)², bias the first-order bias of :func:`table_bias` and u_b the
    table's standard uncertainty of M_ia (:func:`table_type_b_cov` at the bench's true M,
    the readings' inputs) — the condition the certified Type B line is furthest from.
    ``rate_error_rel`` given: that rate error (the signs chosen with it), not the bound.

    >>> b = worst_table("mems-triad")
    >>> round(b.rate_error_rel / b.rate_table_u_rel, 12)
    2.0
    >>> at = math.radians(b.orientation_bound_deg) * (1 - np.eye(3))
    >>> bool(np.allclose(np.abs(b.orientation_error_rad), at))
    True
    """
    b = load_triad_bench(bench)
    m = b.system_matrix
    eps = RATE_ERROR_BOUND_K * b.rate_table_u_rel if rate_error_rel is None else \
        float(rate_error_rel)
    bound = math.radians(b.orientation_bound_deg)
    u_b = np.sqrt(np.diag(table_type_b_cov(m, b.rate_table_u_rel, bound / math.sqrt(3.0))))
    u_m = np.array([[u_b[4 * i + j] for j in range(3)] for i in range(3)])
    off = [(a, j) for a in range(3) for j in range(3) if j != a]
    best, best_d = -1.0, None
    for signs in itertools.product((1.0, -1.0), repeat=len(off)):
        d = np.zeros((3, 3))
        for (a, j), s in zip(off, signs):
            d[a, j] = s * bound
        score = float(np.sum(np.divide(table_bias(m, eps, d), u_m, out=np.zeros((3, 3)),
                                       where=u_m > 0) ** 2))
        if score > best:
            best, best_d = score, d
    return replace(b, rate_error_rel=eps, orientation_error_rad=best_d)


def worst_condition(bench, case: str, trials: list[dict]) -> dict:
    """What a worst case held the table at, and the offset it gives each M item in u_c units:
    {rate_error_rel (``worst``; ``worst-axes`` draws it), orientation_error_rad, table_offset_z:
    {M_ij: mean over the trials of :func:`table_bias` / u_c}} (the first-order, closed-form
    offset, beside which the study's z mean is measured)."""
    b = load_triad_bench(bench)
    w = worst_table(b) if case == "worst" else worst_table(b, rate_error_rel=0.0)
    out = {"rate_error_rel": w.rate_error_rel if case == "worst" else "drawn per trial",
           "orientation_error_rad": np.asarray(w.orientation_error_rad).tolist()}
    offs = {}
    for t in trials:
        eps = w.rate_error_rel if case == "worst" else \
            case_bench(case, b, t["seed"]).rate_error_rel
        bias = table_bias(b.system_matrix, eps, w.orientation_error_rad)
        for i, a in enumerate("xyz"):
            for j, c in enumerate("xyz"):
                rec = t["items"].get(f"M_{a}{c}")
                if rec is not None and rec["u_c"] > 0:
                    offs.setdefault(f"M_{a}{c}", []).append(bias[i, j] / rec["u_c"])
    out["table_offset_z"] = {k: float(np.mean(v)) for k, v in sorted(offs.items())}
    return out


def case_bench(case: str, bench, seed: int) -> TriadBench:
    """The bench trial ``seed`` of ``case`` runs on (:data:`CASES`)."""
    if case == "typeb":
        return for_trial(bench, int(seed))
    if case == "worst":
        return worst_table(bench)
    if case == "worst-axes":                 # the signs fixed (chosen at ε = 0), ε drawn
        return replace(worst_table(bench, rate_error_rel=0.0),
                       rate_error_rel=for_trial(bench, int(seed)).rate_error_rel)
    raise GonioError(f"unknown case {case!r} (known: {', '.join(CASES)})", key="cases")


def triad_trial(seed: int, protocol: str = "triad-alignment", bench="mems-triad",
                draw: bool = True) -> tuple[dict[str, dict], list[str]]:
    """One simulated + calibrated triad programme: ({item: {clause, value, truth, U, u_c}
    and, for an item stated by its interval alone, {interval, nu}}, [items without a
    truth]). ``bench`` a name, path or :class:`TriadBench` (run as given); ``draw``: the
    table's Type B errors drawn from the seed first (:func:`for_trial`). The truth is the
    bench's (``SPEC.truth``; the triad's own parameters, which the table leaves as they are)."""
    from gonio.specs import get
    from gonio.specs.triad_alignment.calibration import calibrate, screen_files

    spec = get("triad-alignment")
    b = for_trial(bench, int(seed)) if draw else load_triad_bench(bench)
    truth = spec.truth(b, load_triad_protocol(protocol))
    with tempfile.TemporaryDirectory() as d:
        files = spec.simulate(d, protocol=protocol, bench=b, seed=int(seed))
        res = calibrate(files["readings"], protocol,
                        findings=screen_files(files["readings"], protocol))
    out, no_truth = {}, []
    leak = realised_leakage(res, truth)
    for key, it in res.items.items():
        if key not in truth:
            no_truth.append(key)
            continue
        if not it.measured or it.uncertainty is None:
            continue
        out[key] = {"clause": it.clause, "value": float(it.value),
                    "truth": float(leak.get(key, truth[key]["value"])),
                    "U": float(it.uncertainty.U), "u_c": float(it.uncertainty.u_c),
                    **stated_record(it.uncertainty), **bound_record(it)}
        gum = ((it.details or {}).get("not_certified") or {}).get("gum")
        if gum:
            out[f"{key} {GUM_SUFFIX}"] = gum_record(out[key], gum)
    return out, no_truth


#: The suffix of an item's row for its JCGM 100 U, which the calibration keeps in the item's
#: details as not certified (:func:`gonio.specs.triad_alignment.calibration.not_certified`):
#: the item's own row is its certified statement (the bound-condition interval).
GUM_SUFFIX = "[gum, not certified]"


def gum_record(certified: dict, gum: dict) -> dict:
    """The study's record of an item's not-certified JCGM 100 U (``details.not_certified.
    gum``) beside its certified row: covered when |value − truth| ≤ U_GUM, z = (value −
    truth)/u_c — the same z as the certified row's (both on the budget's u_c), so the two
    rows differ in coverage only.

    >>> r = gum_record({"clause": "c", "value": 1.0, "truth": 0.9, "U": 0.5, "u_c": 0.1,
    ...                 "interval": [0.5, 1.5], "nu": None}, {"U": 0.2, "u_c": 0.1})
    >>> r["U"], r["u_c"], r["clause"], "interval" in r
    (0.2, 0.1, 'c (JCGM 100, not certified)', False)
    """
    return {"clause": f"{certified['clause']} (JCGM 100, not certified)",
            "value": certified["value"], "truth": certified["truth"],
            "U": float(gum["U"]), "u_c": float(gum["u_c"])}


def realised_leakage(res, truth: dict) -> dict[str, float]:
    """The leakage this trial's alignment leaves: (M̂⁻¹M − I)_ij with the certified M̂ and the
    bench's true M. The item L_ij states 0 ± U (zero for the estimate by construction;
    ``SPEC.truth`` gives the expectation 0), so its U is checked against what the alignment
    actually leaves, not against a constant that every trial matches."""
    ax = "xyz"
    if not all(res.items[f"M_{a}{b}"].measured for a in ax for b in ax):
        return {}
    m_hat = np.array([[res.items[f"M_{a}{b}"].value for b in ax] for a in ax], float)
    m = np.array([[truth[f"M_{a}{b}"]["value"] for b in ax] for a in ax], float)
    left = np.linalg.solve(m_hat, m) - np.eye(3)
    return {f"L_{a}{b}": float(left[i, j]) for i, a in enumerate(ax)
            for j, b in enumerate(ax) if i != j}


@dataclass(frozen=True)
class TriadJob:
    """What a worker needs to run trials of one case (picklable)."""

    case: str
    bench: str
    protocol: str
    seed: int

    def run(self, start: int, stop: int) -> dict:
        """Trials ``start`` … ``stop − 1`` of this case, packed as arrays (the records as
        JSON text: every float kept exactly)."""
        idx = list(range(start, stop))
        seeds = [spawn_seed(self.seed, CASE_KEYS[self.case], i) for i in idx]
        recs = []
        for sd in seeds:
            rec, no_truth = triad_trial(sd, self.protocol,
                                        case_bench(self.case, self.bench, sd), draw=False)
            recs.append(json.dumps({"items": rec, "no_truth": sorted(no_truth)},
                                   sort_keys=True))
        return {"case": np.array(self.case), "index": np.asarray(idx, dtype=np.int64),
                "seed": np.asarray(seeds, dtype=np.int64), "records": np.array(recs, dtype=str)}


def _unpack(packed: Mapping) -> dict[int, dict]:
    return {int(i): {"seed": int(s), **json.loads(str(r))}
            for i, s, r in zip(packed["index"], packed["seed"], packed["records"])}


@dataclass
class TriadReport:
    """The study's report: settings, and per case the drawn condition and the per-item table."""

    settings: dict
    done: dict
    _tables: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def _table(self, case: str):
        """The case's per-item table, computed once (``to_dict`` and ``table`` both show it)."""
        if case not in self._tables:
            self._tables[case] = coverage_table_from(
                [t["items"] for t in self.done[case]],
                judge_spread=case not in FIXED_CONDITION_CASES)
        return self._tables[case]

    def to_dict(self) -> dict:
        """Plain dict for ``validation.json`` (deterministic)."""
        from gonio import __version__

        cases = {}
        for case, trials in self.done.items():
            df = self._table(case)
            cases[case] = {"description": CASES[case],
                           "items_without_truth": sorted({k for t in trials
                                                          for k in t["no_truth"]}),
                           "items": json.loads(df.to_json(orient="records",
                                                          double_precision=15))}
            if case.startswith("worst"):
                cases[case]["table"] = worst_condition(self.settings["bench"], case, trials)
        return {"gonio_version": __version__, "settings": self.settings,
                "criterion": "|value - truth| <= U (or the truth inside the interval an item "
                             "is stated by alone); 95 % Clopper-Pearson interval of the "
                             "coverage; z = (value - truth)/u_c (chi-square z for a standard "
                             "deviation stated by its interval); flagged: coverage < 0.90, sd "
                             "z < 0.3 (not in the worst and worst-axes cases: at one fixed "
                             "condition the coverage is the test, z's spread being the noise's "
                             "alone)",
                "cases": cases}

    def table(self) -> str:
        s = self.settings
        out = []
        for case, trials in self.done.items():
            out.append(format_coverage(self._table(case), f"triad-alignment, case {case}: "
                                       f"{s['trials']} trials, seed {s['seed']}, protocol "
                                       f"{s['protocol']}, bench {s['bench']}: {CASES[case]}"))
            if case.startswith("worst"):
                offs = worst_condition(s["bench"], case, trials)["table_offset_z"]
                out.append("the table's closed-form offset of M at this condition, in u_c "
                           "(table_bias / u_c; compare z mean): " + ", ".join(
                               f"{k} {v:+.2f}" for k, v in offs.items()) + "\n")
        return "".join(out)


@dataclass
class TriadStudy:
    """The planned study (the engine's protocol, :mod:`gonio.pipeline.validate`)."""

    settings: dict
    jobs: dict

    @staticmethod
    def unpack(packed: Mapping) -> dict[int, dict]:
        return _unpack(packed)

    def report(self, done: dict) -> TriadReport:
        return TriadReport(self.settings, done)


def plan_study(trials: int, *, seed: int, bench="mems-triad", protocol="triad-alignment",
               cases: str | None = None) -> TriadStudy:
    """``SPEC.coverage.study``: the cases (comma-separated, ``all``; default both) over
    ``trials`` trials each. ``bench`` and ``protocol``: names or files (the bench's table is
    then drawn or set per case)."""
    names = list(CASES) if cases in (None, "", "all") else [c.strip() for c in cases.split(",")]
    bad = [c for c in names if c not in CASES]
    if bad or not names:
        raise GonioError(f"unknown case {', '.join(bad) or repr(cases)} (known: "
                         f"{', '.join(CASES)}, all)", key="cases")
    bench, protocol = str(bench), str(protocol)
    load_triad_bench(bench)                            # refused here, not in a worker
    load_triad_protocol(protocol)
    settings = {"spec": "triad-alignment", "trials": int(trials), "seed": int(seed),
                "bench": bench, "protocol": protocol, "cases": names,
                "calibration": "gonio calibrate defaults (screened; BIC orders, sensor "
                               "temperature, no Monte Carlo)",
                "truth": "SPEC.truth: the bench's physical parameters in closed form; L_ij "
                         "against M^-1 M - I of the trial's certified M",
                "seeding": "numpy SeedSequence(seed, spawn_key=(CASE_KEYS[case], trial "
                           f"index)), CASE_KEYS = {CASE_KEYS}"}
    return TriadStudy(settings, {c: TriadJob(c, bench, protocol, int(seed)) for c in names})
