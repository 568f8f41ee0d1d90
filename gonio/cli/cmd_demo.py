"""``gonio demo``: a complete virtual calibration of a specification on its default bench
(:func:`gonio.pipeline.dispatch.demo`)."""

from __future__ import annotations

from pathlib import Path

from gonio.cli.checks import seed
from gonio.specs import DEFAULT_KEY


def register(sub) -> None:
    p = sub.add_parser("demo", help="a complete virtual calibration (simulate + calibrate)",
                       description="Simulate a specification's whole calibration on its "
                                   "default virtual bench and calibrate it: readings, "
                                   "truth.json, results.json, the certificate (HTML, PDF) and, "
                                   "where the specification has one, its DCC XML.")
    p.add_argument("--seed", type=seed, default=0,
                   help="random seed of the virtual bench (≥ 0; same seed → byte-identical "
                        "outputs)")
    p.add_argument("--spec", default=DEFAULT_KEY,
                   help=f"specification key (gonio.specs.available(); default {DEFAULT_KEY})")
    p.add_argument("--bench", default=None,
                   help="bench file or built-in name (default: the specification's)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--json", action="store_true", help="print results.json on stdout")
    from gonio.cli.cmd_calibrate import add_certificate_options
    add_certificate_options(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from gonio.atomic import check_output_dir
    from gonio.cli.cmd_calibrate import show
    from gonio.pipeline.dispatch import demo, load_lab_file
    from gonio.progress import status
    from gonio.specs import get

    check_output_dir(args.out, inputs=[args.lab, args.bench], force=args.force)
    spec = get(args.spec)
    lab_d = load_lab_file(args.lab, spec)
    from gonio.formats.lab import naming_lab_file
    with naming_lab_file(args.lab):
        result, paths = demo(spec.key, args.out, bench=args.bench, seed=args.seed, lab=args.lab,
                             lang=args.lang, force=args.force, on_stage=status)
    status("")
    show(spec, result, args.json, lab_d, args.lang)
    if not args.json:
        out = Path(args.out)
        names = sorted({Path(p).relative_to(out).as_posix() if Path(p).is_relative_to(out)
                        else Path(p).name for p in paths.values()})
        print(f"wrote {', '.join(names)} in {out}")
    return 0
