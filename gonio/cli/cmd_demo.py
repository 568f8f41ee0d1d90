"""``gonio demo``: a complete virtual calibration on the default bench."""

from __future__ import annotations

from pathlib import Path

from gonio.errors import GonioError
from gonio.pipeline.demo import demo
from gonio.cli.checks import seed


def register(sub) -> None:
    p = sub.add_parser("demo", help="a complete virtual calibration (simulate + calibrate)",
                       description="Simulate the draft's whole calibration on the default "
                                   "virtual bench (RLG on a precision table) and calibrate it: "
                                   "readings.csv, truth.json, results.json and the certificate.")
    p.add_argument("--seed", type=seed, default=0)
    p.add_argument("--bench", default="rlg", help="bench file or built-in name (rlg, fog)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--json", action="store_true", help="print results.json on stdout")
    from gonio.cli.cmd_calibrate import add_certificate_options
    add_certificate_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    import json

    from gonio.atomic import check_output_dir
    check_output_dir(args.out, inputs=[args.lab, args.bench], force=args.force)
    report, paths = demo(args.out, seed=args.seed, bench=args.bench, lab=args.lab, lang=args.lang,
                         force=args.force)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2, ensure_ascii=False, allow_nan=False))
    else:
        print(report.summary(), end="")
        print(f"wrote {', '.join(sorted(p.name for p in paths))} in {Path(args.out)}")
    return 0
