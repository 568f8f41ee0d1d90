#!/usr/bin/env python
"""Mutation testing of the specifications' item formulas and budgets ("mutate a
formula now and then: a test must notice"). Not part of the default test run.

    python scripts/mutation.py --list                      # the mutants, no tests run
    python scripts/mutation.py --spec jjf1535-2015         # one specification (or: all)
    python scripts/mutation.py --spec iec62047-20 --function symmetry --function bias
    python scripts/mutation.py --spec all --sample 200 --out mutation.json

Each mutant changes ONE operator in ONE function of a target module (``TARGETS``):

* arithmetic swaps  ``+ ↔ −``, ``* ↔ /``, ``** → *``;
* comparison boundaries  ``>= ↔ >``, ``<= ↔ <``;
* constants  0 → 1, 1 → 2, any other number x → 2x (ints: x + 1);
* sign flips  ``−x → x``.

Strings, f-strings and the values of the keywords in ``SKIP_KEYWORDS`` (``details=``,
``source=`` …: text and extra detail, not a certified number) are not mutated.

How a mutant runs: the parent process imports the target modules and pytest once; for each
mutant it forks, the child compiles the mutated function and swaps its ``__code__`` into the
live function object (every reference — ``ITEMS`` tables, ``from … import`` names — sees the
mutation), then runs only the specification's fast tests (``TESTS``) with ``-x``; exit code
0 means the mutant SURVIVED. A child past ``--timeout`` seconds counts as killed (timeout).
The source files are never written. Before the mutants, the same tests run unmutated and
must pass. Survivors are listed with file:line, function and the change; docs/mutation.md
gives today's counts and the reason each remaining survivor cannot be observed.
"""

from __future__ import annotations

import argparse
import ast
import copy
import fnmatch
import importlib
import json
import os
import random
import signal
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Per specification: the modules whose functions are mutated (module, function patterns).
TARGETS: dict[str, list[tuple[str, list[str]]]] = {
    "jjf1535-2015": [("gonio.specs.jjf1535.items", ["*"]),
                     ("gonio.specs.jjf1535.budget", ["*"]),
                     ("gonio.specs.jjf1535.formulas", [
                         "rest_level", "fit_scale_factor",
                         "nonlinearity_jjf", "asymmetry_jjf", "relative_std", "sample_std",
                         "temperature_sensitivity", "fifty_percent_candidate",
                         "g_sensitivity_axis", "warmup_time_s"]),
                     ("gonio.specs._rate_family.formulas", [
                         "least_squares_line", "block_mean_stability",
                         "earth_rate_projection_dps", "minus3db_frequency",
                         "_log_crossing", "bias_drift_u", "block_mean_variogram",
                         "block_variogram_fit", "block_variogram_model", "block_std_dof",
                         "bias_stability_dofs", "bias_stability_dof"]),
                     ("gonio.analysis.conformity", ["*"])],
    "iec62047-20": [("gonio.specs.iec62047_20.items", ["*"]),
                    ("gonio.specs.iec62047_20.formulas", [
                        "linearity_errors_iec", "symmetry_iec",
                        "ratiometric_error_iec", "cross_axis_iec", "voltage_corrected",
                        "hysteresis_iec", "resolution_iec", "boxcar_noise_rms",
                        "broadband_noise_iec", "g_slope_iec", "arw_minus_half_line",
                        "bias_instability_floor"]),
                    ("gonio.specs._rate_family.formulas", [
                        "least_squares_line", "phase90_frequency", "minus3db_frequency"])],
    "ogam-draft": [("gonio.specs.ogam_draft.items", ["*"]),
                   ("gonio.specs.ogam_draft.budget", ["*"]),
                   ("gonio.specs.ogam_draft.item_uncertainty", ["*"])],
    "triad-alignment": [("gonio.specs.triad_alignment.calibration", ["*"]),
                        ("gonio.specs.triad_alignment.analysis", ["*"]),
                        ("gonio.specs.triad_alignment.thermal_model", [
                            "soak_covariance", "order_uncertainty", "fit_polynomial",
                            "design", "PolyFit.coefficients", "soak_parts", "linear_variance",
                            "criterion_weights", "point",
                            "certified_points"])],
}

#: Per specification: the fast tests that should notice (pytest arguments).
TESTS: dict[str, list[str]] = {
    "jjf1535-2015": ["tests/test_rate_formulas.py", "tests/test_rate_uncertainty_terms.py",
                     "tests/test_conformity.py",
                     "tests/test_rate_bench.py::test_jjf_noise_off_exact",
                     "tests/test_rate_bench.py::test_jjf_noise_off_zero_items_and_bandwidth",
                     "tests/test_rate_bench.py::test_jjf_bandwidth_noise_off_exact",
                     "tests/test_rate_bench.py::test_jjf_warmup_noise_off",
                     "tests/test_rate_bench.py::test_jjf_results_json_shape"],
    "iec62047-20": ["tests/test_iec_slope_u.py", "tests/test_iec_equipment_terms.py",
                    "tests/test_rate_formulas.py",
                    "tests/test_rate_iec_items.py",
                    "tests/test_rate_uncertainty_terms.py",
                    "tests/test_rate_bench.py::test_iec_noise_off_exact",
                    "tests/test_rate_bench.py::test_iec_power_on_items_noise_off",
                    "tests/test_rate_bench.py::test_iec_bias_erratum_detail",
                    "tests/test_rate_iec_truth.py::test_noise_off_recovery_exact"],
    "ogam-draft": ["tests/test_characteristics.py", "tests/test_budget.py"],
    "triad-alignment": ["tests/test_thermal_coverage.py::test_true_coefficients_re_expand_the_bench_polynomials",
                        "tests/test_thermal_coverage.py::test_soak_covariance_is_the_fit_of_the_soak_means_on_a_balanced_design",
                        "tests/test_thermal_coverage.py::test_order_term_closed_form_for_two_candidates",
                        "tests/test_thermal_coverage.py::test_soak_covariance_degrees_of_freedom_boundaries",
                        "tests/test_thermal_coverage.py::test_soak_covariance_one_within_degree_of_freedom",
                        "tests/test_thermal_coverage.py::test_point_variance_is_the_covariance_form_and_the_order_term_its_closed_form",
                        "tests/test_thermal_coverage.py::test_certified_points_of_a_set_point_measured_once",
                        "tests/test_spec_truth.py::test_triad_thermal_truth_is_what_a_noise_free_identification_finds",
                        "tests/test_triad_alignment.py"],
}

SKIP_KEYWORDS = {"details", "source", "reason", "title", "note", "how", "unit"}
SKIP_CALLS = {"GonioError", "not_measured", "ValueError", "TypeError"}

_BIN_SWAP = {ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult,
             ast.Pow: ast.Mult}
_CMP_SWAP = {ast.GtE: ast.Gt, ast.Gt: ast.GtE, ast.LtE: ast.Lt, ast.Lt: ast.LtE}
_SYM = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**",
        ast.GtE: ">=", ast.Gt: ">", ast.LtE: "<=", ast.Lt: "<"}


@dataclass(frozen=True)
class Mutant:
    spec: str
    module: str
    function: str            # qualified name inside the module (Class.method)
    index: int               # n-th mutable node of the function, in ast.walk order
    line: int
    change: str


def _mutable_nodes(fn: ast.AST) -> list[tuple[ast.AST, str]]:
    """(node, description) of every mutation site in a function, skipping text and details."""
    out: list[tuple[ast.AST, str]] = []

    def visit(node, skip=False):
        if isinstance(node, ast.JoinedStr):
            return
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")
            if name in SKIP_CALLS:
                return
        if isinstance(node, ast.keyword) and node.arg in SKIP_KEYWORDS:
            return
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) \
                and isinstance(node.value.value, str):
            return                                           # docstring
        if not skip:
            if isinstance(node, ast.BinOp) and type(node.op) in _BIN_SWAP:
                out.append((node, f"{_SYM[type(node.op)]} -> {_SYM[_BIN_SWAP[type(node.op)]]}"))
            elif isinstance(node, ast.Compare):
                for k, op in enumerate(node.ops):
                    if type(op) in _CMP_SWAP:
                        out.append((node, f"cmp{k}: {_SYM[type(op)]} -> "
                                          f"{_SYM[_CMP_SWAP[type(op)]]}"))
            elif isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
                    and not isinstance(node.value, bool):
                out.append((node, f"{node.value!r} -> {_const_mutant(node.value)!r}"))
            elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
                out.append((node, "-x -> x"))
        for child in ast.iter_child_nodes(node):
            visit(child)

    for stmt in fn.body:
        visit(stmt)
    return out


def _const_mutant(v):
    if v == 0:
        return type(v)(1)
    if v == 1:
        return type(v)(2)
    return v + 1 if isinstance(v, int) else 2.0 * v


def _functions(tree: ast.Module) -> dict[str, ast.FunctionDef]:
    out = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            out[node.name] = node
        elif isinstance(node, ast.ClassDef):
            for sub in node.body:
                if isinstance(sub, ast.FunctionDef):
                    out[f"{node.name}.{sub.name}"] = sub
    return out


def _source_tree(module: str) -> tuple[Path, ast.Module]:
    mod = importlib.import_module(module)
    path = Path(mod.__file__)
    return path, ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def enumerate_mutants(spec: str, functions: list[str] | None = None) -> list[Mutant]:
    out = []
    for module, patterns in TARGETS[spec]:
        _, tree = _source_tree(module)
        for qual, fn in _functions(tree).items():
            short = qual.split(".")[-1]
            if not any(fnmatch.fnmatch(short, p) for p in patterns):
                continue
            if functions and short not in functions and qual not in functions:
                continue
            for i, (node, desc) in enumerate(_mutable_nodes(fn)):
                out.append(Mutant(spec, module, qual, i, getattr(node, "lineno", fn.lineno), desc))
    return out


def _apply(m: Mutant) -> None:
    """Compile the mutated function and swap its code into the live function object."""
    path, tree = _source_tree(m.module)
    fn = copy.deepcopy(_functions(tree)[m.function])
    node, desc = _mutable_nodes(fn)[m.index]
    if isinstance(node, ast.BinOp):
        node.op = _BIN_SWAP[type(node.op)]()
    elif isinstance(node, ast.Compare):
        k = int(desc.split(":")[0][3:])
        node.ops[k] = _CMP_SWAP[type(node.ops[k])]()
    elif isinstance(node, ast.Constant):
        node.value = _const_mutant(node.value)
    elif isinstance(node, ast.UnaryOp):
        node.op = ast.UAdd()
    code = compile(ast.Module(body=[fn], type_ignores=[]), str(path), "exec")
    fcode = next(c for c in code.co_consts if hasattr(c, "co_name") and c.co_name == fn.name)
    obj = importlib.import_module(m.module)
    for part in m.function.split("."):
        obj = getattr(obj, part)
    obj = getattr(obj, "__wrapped__", obj)
    obj.__code__ = fcode


def _run_tests(spec: str, mutant: Mutant | None, timeout: float) -> str:
    """'killed', 'survived', 'timeout' or 'error' (baseline: 'survived' means it passes)."""
    pid = os.fork()
    if pid == 0:                                     # child
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 1)
            os.dup2(devnull, 2)
            if mutant is not None:
                _apply(mutant)
            import pytest
            tests = [t for t in TESTS[spec] if (ROOT / t.split("::")[0]).is_file()]
            rc = pytest.main(["-x", "-q", "-p", "no:cacheprovider", "-p", "no:randomly",
                              "--rootdir", str(ROOT), *tests])
            os._exit(0 if rc == 0 else (5 if rc == 5 else 1))
        except BaseException:                                     # noqa: BLE001
            os._exit(3)
    t0 = time.monotonic()
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            code = os.waitstatus_to_exitcode(status)
            return {0: "survived", 1: "killed", 5: "error"}.get(code, "killed")
        if time.monotonic() - t0 > timeout:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return "timeout"
        time.sleep(0.05)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spec", default="all", choices=["all", *TARGETS])
    ap.add_argument("--function", action="append", help="only these functions (repeatable)")
    ap.add_argument("--sample", type=int, default=0, help="a random sample of N mutants "
                    "(seeded by --seed) instead of all")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds per mutant")
    ap.add_argument("--list", action="store_true", help="list the mutants, run nothing")
    ap.add_argument("--out", help="write the results as JSON here")
    ap.add_argument("--tests", action="append", help="run only these tests (pytest "
                    "arguments, repeatable) instead of the specification's TESTS")
    a = ap.parse_args(argv)
    if a.tests:
        for spec in TESTS:
            TESTS[spec] = list(a.tests)
    os.chdir(ROOT)
    sys.path.insert(0, str(ROOT))
    specs = list(TARGETS) if a.spec == "all" else [a.spec]
    results = []
    for spec in specs:
        muts = enumerate_mutants(spec, a.function)
        if a.sample and len(muts) > a.sample:
            muts = sorted(random.Random(a.seed).sample(muts, a.sample),
                          key=lambda m: (m.module, m.line, m.index))
        print(f"{spec}: {len(muts)} mutants", flush=True)
        if a.list:
            for m in muts:
                print(f"  {m.module}:{m.line} {m.function} [{m.index}] {m.change}")
            continue
        base = _run_tests(spec, None, a.timeout * 3)
        if base != "survived":
            print(f"{spec}: the unmutated tests do not pass ({base}); fix that first")
            return 2
        for k, m in enumerate(muts, 1):
            t0 = time.monotonic()
            r = _run_tests(spec, m, a.timeout)
            results.append({**asdict(m), "result": r})
            mark = "SURVIVED" if r == "survived" else r
            print(f"  [{k}/{len(muts)}] {mark:8s} {m.module}:{m.line} {m.function} {m.change} "
                  f"({time.monotonic() - t0:.0f} s)", flush=True)
    if a.list:
        return 0
    surv = [r for r in results if r["result"] == "survived"]
    print(f"\n{len(results)} mutants, {len(surv)} survived")
    for spec in specs:
        n = sum(r["spec"] == spec for r in results)
        s = sum(r["spec"] == spec for r in surv)
        print(f"  {spec}: {n} mutants, {s} survived")
    for r in surv:
        print(f"  SURVIVOR {r['module']}:{r['line']} {r['function']} {r['change']}")
    if a.out:
        Path(a.out).write_text(json.dumps({"results": results}, indent=1), encoding="utf-8")
    return 1 if surv else 0


if __name__ == "__main__":
    sys.exit(main())
