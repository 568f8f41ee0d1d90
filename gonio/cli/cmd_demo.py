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
    p.add_argument("--spec", default="ogam-draft",
                   help="specification (ogam-draft, jjf1535-2015, iec62047-20)")
    p.add_argument("--bench", default=None,
                   help="bench file or built-in name (default: rlg; rate specs: mems-adxrs610; "
                        "rlg and fog work as rate sensors too)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--json", action="store_true", help="print results.json on stdout")
    from gonio.cli.cmd_calibrate import add_certificate_options
    add_certificate_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    import json

    from gonio.atomic import check_output_dir
    check_output_dir(args.out, inputs=[args.lab, args.bench], force=args.force)
    if args.spec != "ogam-draft":
        from gonio.pipeline.rate import demo as rate_demo

        result, paths = rate_demo(args.spec, args.out, bench=args.bench, seed=args.seed,
                                  lab=args.lab, lang=args.lang)
        if args.json:
            print(json.dumps(result.to_json(), indent=2, ensure_ascii=False, allow_nan=False))
        else:
            print(result.summary(), end="")
            print(f"wrote {', '.join(sorted(Path(p).name for p in paths.values()))} in "
                  f"{Path(args.out)}")
        return 0
    report, paths = demo(args.out, seed=args.seed, bench=args.bench or "rlg", lab=args.lab,
                         lang=args.lang, force=args.force)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2, ensure_ascii=False, allow_nan=False))
    else:
        print(report.summary(), end="")
        print(f"wrote {', '.join(sorted(p.name for p in paths))} in {Path(args.out)}")
    return 0
