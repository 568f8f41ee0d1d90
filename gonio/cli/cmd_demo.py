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
                                   "readings.csv, truth.json, results.json, the certificate "
                                   "(HTML, PDF) and its DCC XML.")
    p.add_argument("--seed", type=seed, default=0,
                   help="random seed of the virtual bench (≥ 0; same seed → byte-identical "
                        "outputs)")
    p.add_argument("--spec", default="ogam-draft",
                   help="specification (ogam-draft, jjf1535-2015, iec62047-20, triad-alignment)")
    p.add_argument("--bench", default=None,
                   help="bench file or built-in name (default: rlg; rate specs: mems-adxrs610; "
                        "rlg and fog work as rate sensors too; triad-alignment: mems-triad)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--json", action="store_true", help="print results.json on stdout")
    from gonio.cli.cmd_calibrate import add_certificate_options
    add_certificate_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    import json

    from gonio.atomic import check_output_dir
    check_output_dir(args.out, inputs=[args.lab, args.bench], force=args.force)
    if args.spec == "triad-alignment":
        from gonio.cli.cmd_calibrate import print_result
        from gonio.pipeline.triad import demo as triad_demo

        result, paths = triad_demo(args.out, bench=args.bench, seed=args.seed, lab=args.lab,
                                   lang=args.lang, force=args.force)
        print_result(result, args.json)
        if not args.json:
            print(f"wrote {', '.join(sorted(Path(p).name for p in paths.values()))} in "
                  f"{Path(args.out)}")
        return 0
    if args.spec != "ogam-draft":
        import json

        from gonio.pipeline.rate import demo as rate_demo

        result, paths = rate_demo(args.spec, args.out, bench=args.bench, seed=args.seed,
                                  lab=args.lab, lang=args.lang, force=args.force)
        if args.json:
            print(json.dumps(result.to_json(), indent=2, ensure_ascii=False, allow_nan=False))
        else:
            print(result.summary(), end="")
            print(f"wrote {', '.join(sorted(Path(p).name for p in paths.values()))} in "
                  f"{Path(args.out)}")
        return 0
    from gonio.cli.cmd_calibrate import print_outputs
    from gonio.progress import status
    from gonio.report.certificate import load_lab

    lab_d = load_lab(args.lab) if args.lab else None
    report, paths = demo(args.out, seed=args.seed, bench=args.bench or "rlg", lab=args.lab,
                         lang=args.lang, on_stage=status, force=args.force)
    status("")
    print_outputs(report, args.json, lab_d, args.lang)
    if not args.json:
        out = Path(args.out)
        rel = sorted(p.relative_to(out).as_posix() for p in paths)
        print(f"wrote {', '.join(rel)} in {out}")
    return 0
