"""``gonio validate``: coverage of the Annex A budget over many virtual calibrations."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

from gonio.atomic import output_dir, write_text
from gonio.errors import GonioError
from gonio.cli.checks import float_range, int_range, seed
from gonio.pipeline.validate import CASES, EXTRA_SYMBOLS, PARTIAL_DIR, TRUTHS, validate


def register(sub) -> None:
    p = sub.add_parser("validate", help="test the Annex A budget against virtual calibrations",
                       description="Run N virtual calibrations per case (7.1 + 7.4 with 10 series) "
                                   "and report how often |E - truth| <= U, U the calibration's own "
                                   "Annex A expanded uncertainty (k = 2).")
    p.add_argument("--trials", type=int_range(2), required=True, help="calibrations per case (>= 2)")
    p.add_argument("--seed", type=seed, default=0, help="master seed (same seed -> same JSON)")
    p.add_argument("--spec", default="ogam-draft",
                   help="specification: ogam-draft (default; the Annex A budget of E) or a "
                        "rate-gyro specification, jjf1535-2015 or iec62047-20 (the coverage "
                        "of every item's U, printed per item)")
    p.add_argument("--bench", default=None,
                   help="bench file or built-in name (default rlg; rlg, fog; rate specs: "
                        "mems-adxrs610, as a study bench)")
    p.add_argument("--protocol", default=None,
                   help="protocol (default ogam-draft, restricted to 7.1 and 7.4/7.5; rate "
                        "specs: the built-in programme reduced to the study's sizes)")
    p.add_argument("--cases", default="default",
                   help=f"comma-separated cases, or 'all' ({', '.join(CASES)})")
    p.add_argument("--truth", default="systematic", choices=TRUTHS,
                   help="truth of the printed table (all are in the JSON)")
    p.add_argument("--extra-components", nargs="?", const="all", default=None, metavar="NAMES",
                   help="also evaluate the budget with the components the annex lacks: all, or "
                        f"a comma-separated subset of {','.join(EXTRA_SYMBOLS)}")
    p.add_argument("--u-scale", type=float_range(0, 100, lo_open=True), default=1.0,
                   help="multiply U (default 1; < 1 deliberately breaks the budget)")
    p.add_argument("--sample-rate-hz", type=float_range(1, 1e5), default=100.0,
                   help="simulation rate (default 100 Hz; the RLG counter is exact at any rate)")
    p.add_argument("--workers", type=int, default=None,
                   help="local processes (default min(2, cores), at most the machine's cores; "
                        "results do not depend on it)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on a Dask cluster: tcp://host:8786, or local:N to start a "
                        "LocalCluster of N processes, N at most the machine's cores "
                        "(GONIO_MAX_WORKERS raises it; needs pip install 'gonio[dask]'; "
                        "results do not depend on it)")
    p.add_argument("--batch", type=int, default=None, metavar="N",
                   help="trials per task (default: about 4 tasks per worker over all cases, "
                        "at most 250; results do not depend on it)")
    p.add_argument("--out", default=None,
                   help="folder for validation.json; finished batches are kept in "
                        "OUT/.validate-partial until the study completes")
    p.add_argument("--resume", action="store_true",
                   help="continue the interrupted study in --out (same settings): run only the "
                        "trials it has not finished")
    p.add_argument("--all-items", action="store_true",
                   help="keep 7.3, 7.6 and 7.7 so that every item's coverage is measured")
    p.add_argument("--monte-carlo", type=int_range(0), default=0, metavar="N",
                   help="also run the JCGM 101 Monte Carlo (N trials) of every item budget of "
                        "each case's first calibration and validate its GUM result (JCGM 101 "
                        "8.2: pass/fail, d_low, d_high); 0 (default) off")
    p.add_argument("--json", action="store_true", help="print validation.json on stdout")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.trials < 2:
        raise GonioError(f"--trials must be an integer >= 2, got {args.trials}")
    from gonio.limits import check

    check("GONIO_MAX_TRIALS", args.trials, "--trials", unit="calibrations per case")
    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    if args.workers is not None and args.workers < 1:
        raise GonioError(f"--workers must be >= 1, got {args.workers}")
    if args.resume and not args.out:
        raise GonioError("--resume needs --out (the folder of the interrupted study)")
    cases = list(CASES) if args.cases.strip() == "all" else \
        [c.strip() for c in args.cases.split(",") if c.strip()]
    if args.extra_components is None:
        extras = False
    elif args.extra_components.strip() == "all":
        extras = True
    else:
        extras = [e.strip() for e in args.extra_components.split(",") if e.strip()]
    if args.out is not None:
        from gonio.atomic import check_output_folder_place
        check_output_folder_place(args.out)          # before any batch is written there
    if args.spec != "ogam-draft":
        return run_rate(args, extras)
    partial = Path(args.out) / PARTIAL_DIR if args.out is not None else None
    try:
        report = validate(args.trials, seed=args.seed, bench=args.bench or "rlg", cases=cases,
                          sample_rate_hz=args.sample_rate_hz,
                          protocol=args.protocol or "ogam-draft",
                          extra_components=extras, truth=args.truth,
                          u_scale=args.u_scale, workers=args.workers, scheduler=args.scheduler,
                          batch_size=args.batch, partial_dir=partial, resume=args.resume,
                          all_items=args.all_items, monte_carlo=args.monte_carlo)
    except KeyboardInterrupt:
        if partial is not None and partial.exists():
            sys.stderr.write(f"gonio: interrupted: the finished trials are kept in {partial}; "
                             "rerun the same command with --resume to continue\n")
        else:
            sys.stderr.write("gonio: interrupted (nothing kept: give --out to keep partial "
                             "results)\n")
        return 130
    emit(report, args)
    if partial is not None:                          # the study is complete
        shutil.rmtree(partial, ignore_errors=True)
    return 0


def emit(report, args) -> None:
    """Write ``validation.json`` into --out (atomically) and print the table or the JSON."""
    text = json.dumps(report.to_dict(), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    if args.out is not None:
        with output_dir(Path(args.out)) as stage:     # the partial batches live in --out
            write_text(stage / "validation.json", text)
    if args.json:
        print(text, end="")
    else:
        print(report.table(), end="")


#: Options of the optical draft's study, with their defaults (refused with a rate --spec).
OPTICAL_ONLY = {"cases": "default", "truth": "systematic", "u_scale": 1.0,
                "sample_rate_hz": 100.0, "all_items": False, "resume": False}


def run_rate(args, extras) -> int:
    """``gonio validate --spec jjf1535-2015|iec62047-20``: the coverage of every item
    (:func:`gonio.pipeline.rate_coverage.rate_validate`)."""
    from gonio.pipeline.rate import RATE_SPECS
    from gonio.pipeline.rate_coverage import rate_validate

    if args.spec not in RATE_SPECS:
        from gonio.specs import get
        get(args.spec)                                   # GonioError listing the keys
        raise GonioError(f"{args.spec} has no coverage study", key="--spec")
    given = [k for k, v in OPTICAL_ONLY.items() if getattr(args, k) != v]
    if extras:
        given.append("extra_components")
    if given:
        raise GonioError("--" + ", --".join(g.replace("_", "-") for g in given)
                         + f" apply to the optical draft only, not to --spec {args.spec}")
    try:
        report = rate_validate(args.spec, args.trials, seed=args.seed, bench=args.bench,
                               protocol=args.protocol, workers=args.workers,
                               scheduler=args.scheduler, batch_size=args.batch)
    except KeyboardInterrupt:
        sys.stderr.write("gonio: interrupted (a rate study keeps no partial results)\n")
        return 130
    emit(report, args)
    return 0
