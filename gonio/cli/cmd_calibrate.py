"""``gonio calibrate``: readings → results.json, summary, tables and the certificate, by the
specification the readings name (:func:`gonio.pipeline.dispatch.calibrate`).

The options every specification takes are here; a specification adds its own through its
``arguments["calibrate"]`` hook (:mod:`gonio.cli.spec_options`, one argument group per
specification), and an option of another specification is refused naming it (exit 2)."""

from __future__ import annotations

import json
import sys

from gonio.cli.checks import int_range
from gonio.cli.spec_options import (given as spec_given, inputs as spec_inputs,
                                    no_spec_options, refuse)


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="calibrate a readings file to its specification",
                       description="Compute a specification's items and their uncertainties "
                                   "from a readings file; write results.json, summary.txt, "
                                   "tables/*.csv and the certificate into --out.")
    p.add_argument("readings", help="readings file (CSV, docs/formats.md#readings-file) or a stream (docs/formats.md#stream-file, "
                   "reduced with the protocol first; told apart by the header)")
    p.add_argument("--spec", default=None,
                   help="specification key (default: the readings' '# spec:' metadata, else "
                        "gonio.specs.DEFAULT_KEY)")
    p.add_argument("--protocol", default=None,
                   help="protocol file or built-in name (default: the specification's)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--json", action="store_true", help="print results.json on stdout")
    add_certificate_options(p)
    p.add_argument("--dcc", action="store_true",
                   help="also write certificate.dcc.xml, the PTB Digital Calibration "
                        "Certificate (DCC 3.3.0 XML)")
    p.add_argument("--monte-carlo", type=int_range(0), default=0, metavar="N",
                   help="also propagate the budget by JCGM 101 Monte Carlo with N trials")
    p.set_defaults(func=run)
    no_spec_options(p)


def add_certificate_options(p) -> None:
    """``--lab FILE`` and ``--lang en|zh`` (shared by calibrate and demo)."""
    p.add_argument("--lab", default=None, metavar="FILE",
                   help="laboratory, customer and signatory details (TOML, see "
                        "protocols/lab-example.toml); without it the certificate is marked as a "
                        "virtual-bench example")
    p.add_argument("--force", action="store_true",
                   help="replace an --out folder whose files were changed since gonio wrote "
                        "them, or that holds a readings/stream file")
    p.add_argument("--lang", choices=("en", "zh"), default="en",
                   help="certificate language (zh needs a CJK font, e.g. fonts-noto-cjk)")


def show(spec, result, as_json: bool, lab_d: dict | None = None, lang: str = "en") -> None:
    """Print the result's results.json (``--json``) or its summary, after its warnings and
    the one-line CJK font note, through the specification's renderer."""
    from gonio.report.render import cjk_notice

    r = spec.renderer()
    warn = spec.output_hook("warnings")
    for w in (warn(result) if warn is not None else []):
        print(w, file=sys.stderr)
    note = cjk_notice(lang)
    if note:
        sys.stderr.write(f"gonio: note: {note}\n")
    if as_json:
        sys.stdout.write(json.dumps(r.results_json(result, lab_d), indent=2, ensure_ascii=False,
                                    allow_nan=False) + "\n")
    else:
        sys.stdout.write(r.summary(result, lab_d))
    sys.stdout.flush()


def run(args) -> int:
    from gonio.atomic import check_output_dir
    from gonio.limits import check
    from gonio.pipeline.dispatch import calibrate, load_lab_file, readings_spec
    from gonio.progress import status
    from gonio.specs import DEFAULT_KEY, get

    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    given = spec_given(args)                         # refused by dispatch if foreign
    inputs = [args.readings, args.protocol, args.lab] + spec_inputs(args)
    check_output_dir(args.out, inputs=inputs, force=args.force)   # before the work
    spec = get(args.spec or readings_spec(args.readings) or DEFAULT_KEY)
    refuse(spec, "calibrate", given, args)                           # named as typed
    if spec.named_inputs is not None:                # never replaced or removed
        inputs += list(spec.named_inputs(args.readings))
        check_output_dir(args.out, inputs=inputs, force=args.force)
    lab_d = load_lab_file(args.lab, spec)                               # validated before the work
    registered = getattr(args, "registered_gyro_type", None)        # calibrate --record
    if registered and "gyro_type" in spec.calibrate_options and not (
            (lab_d or {}).get("instrument") or {}).get("gyro_type"):
        given["gyro_type"] = registered
    status("calibrating")
    from gonio.formats.lab import naming_lab_file
    with naming_lab_file(args.lab):
        result, _ = calibrate(args.readings, args.out, spec_key=spec.key, protocol=args.protocol,
                              lab=lab_d, lang=args.lang, dcc=args.dcc,
                              monte_carlo_trials=args.monte_carlo, inputs=inputs,
                              force=args.force, lab_file=args.lab,
                              record={"gyro_type": registered} if registered else None,
                              before_swap=getattr(args, "before_swap", None),  # --record
                              **given)
    status("")
    show(spec, result, args.json, lab_d, args.lang)
    return 0
