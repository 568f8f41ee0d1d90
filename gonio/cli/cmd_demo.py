"""``gonio demo``: a complete virtual calibration on the default bench."""

from __future__ import annotations

from pathlib import Path

from gonio.errors import GonioError
from gonio.pipeline.demo import demo


def register(sub) -> None:
    p = sub.add_parser("demo", help="a complete virtual calibration (simulate + calibrate)",
                       description="Simulate the draft's whole calibration on the default "
                                   "virtual bench (RLG on a precision table) and calibrate it: "
                                   "readings.csv, truth.json, results.json, the certificate "
                                   "(HTML, PDF) and its DCC XML.")
    p.add_argument("--seed", type=int, default=0,
                   help="random seed of the virtual bench (≥ 0; same seed → byte-identical "
                        "outputs)")
    p.add_argument("--bench", default="rlg", help="bench file or built-in name (rlg, fog)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--json", action="store_true", help="print results.json on stdout")
    from gonio.cli.cmd_calibrate import add_certificate_options
    add_certificate_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    if args.seed < 0:
        raise GonioError(f"--seed must be ≥ 0, got {args.seed}")
    from gonio.cli.cmd_calibrate import print_outputs
    from gonio.progress import status
    from gonio.report.certificate import load_lab

    lab_d = load_lab(args.lab) if args.lab else None
    report, paths = demo(args.out, seed=args.seed, bench=args.bench, lab=args.lab,
                         lang=args.lang, on_stage=status)
    status("")
    print_outputs(report, args.json, lab_d, args.lang)
    if not args.json:
        out = Path(args.out)
        rel = sorted(p.relative_to(out).as_posix() for p in paths)
        print(f"wrote {', '.join(rel)} in {out}")
    return 0
