"""``gonio validate``: the coverage of a specification's uncertainties over many virtual
calibrations (``SPEC.coverage``, run by :func:`gonio.pipeline.validate.validate`: the generic
item study of :mod:`gonio.pipeline.coverage`, or a study the specification describes itself,
whose settings are options the specification adds: ``arguments["validate"]``,
:mod:`gonio.cli.spec_options`)."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

from gonio.atomic import output_dir, write_text
from gonio.errors import GonioError
from gonio.cli.checks import int_range, seed
from gonio.cli.spec_options import given as spec_given, no_spec_options, refuse
from gonio.specs import DEFAULT_KEY


def register(sub) -> None:
    p = sub.add_parser("validate", help="test a specification's uncertainties against virtual "
                                        "calibrations",
                       description="Run N virtual calibrations and report how often |value - "
                                   "truth| <= U, U the calibration's own expanded uncertainty: "
                                   "per item (the generic item study), or as the "
                                   "specification's own study describes (its options below).")
    p.add_argument("--trials", type=int_range(2), required=True, help="calibrations per case (>= 2)")
    p.add_argument("--seed", type=seed, default=0, help="master seed (same seed -> same JSON)")
    p.add_argument("--spec", default=DEFAULT_KEY,
                   help=f"specification key (default {DEFAULT_KEY}; a specification with an "
                        "item study: the coverage of every item's U, printed per item)")
    p.add_argument("--bench", default=None,
                   help="bench file or built-in name (default: the specification's, as a study "
                        "bench)")
    p.add_argument("--protocol", default=None,
                   help="protocol (default: the specification's, restricted or reduced to the "
                        "study's programme)")
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
                        "trials it has not finished (a study the specification describes)")
    p.add_argument("--json", action="store_true", help="print validation.json on stdout")
    p.set_defaults(func=run)
    no_spec_options(p)


def run(args) -> int:
    if args.trials < 2:
        raise GonioError(f"--trials must be an integer >= 2, got {args.trials}")
    from gonio.limits import check
    from gonio.specs import get

    check("GONIO_MAX_TRIALS", args.trials, "--trials", unit="calibrations per case")
    if args.workers is not None and args.workers < 1:
        raise GonioError(f"--workers must be >= 1, got {args.workers}")
    if args.resume and not args.out:
        raise GonioError("--resume needs --out (the folder of the interrupted study)")
    spec = get(args.spec)
    if spec.coverage is None:
        raise GonioError(f"{spec.key} has no coverage study (SPEC.coverage is None)",
                         key="--spec")
    given = refuse(spec, "validate", {"resume": args.resume, **spec_given(args)}, args)
    if args.out is not None:
        from gonio.atomic import check_output_folder_place
        check_output_folder_place(args.out)          # before any batch is written there
    if spec.coverage.engine == "items":
        return run_items(spec, args, given)
    return run_study(spec, args, given)


def run_study(spec, args, opts: dict) -> int:
    """A study the specification describes (:func:`gonio.pipeline.validate.validate`), with
    its partial results kept in ``--out``."""
    from gonio.pipeline.validate import PARTIAL_DIR, validate

    opts = dict(opts)
    resume = bool(opts.pop("resume", False))
    partial = Path(args.out) / PARTIAL_DIR if args.out is not None else None
    try:
        report = validate(args.trials, spec=spec, seed=args.seed, bench=args.bench,
                          protocol=args.protocol, workers=args.workers,
                          scheduler=args.scheduler, batch_size=args.batch, partial_dir=partial,
                          resume=resume, **opts)
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


def run_items(spec, args, opts: dict | None = None) -> int:
    """The item coverage study (:func:`gonio.pipeline.validate.validate` →
    :func:`gonio.pipeline.coverage.coverage_validate`), with the specification's options
    given (``--cases``)."""
    from gonio.pipeline.validate import validate

    try:
        report = validate(args.trials, spec=spec, seed=args.seed, bench=args.bench,
                          protocol=args.protocol, workers=args.workers,
                          scheduler=args.scheduler, batch_size=args.batch, **(opts or {}))
    except KeyboardInterrupt:
        sys.stderr.write("gonio: interrupted (an item study keeps no partial results)\n")
        return 130
    emit(report, args)
    return 0
