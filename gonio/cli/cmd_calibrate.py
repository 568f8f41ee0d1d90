"""``gonio calibrate``: readings → results.json (seven characteristics, Annex A budget)."""

from __future__ import annotations

import json

from gonio.pipeline.calibrate import calibrate, write_outputs
from gonio.cli.checks import int_range
from gonio.errors import GonioError


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="compute the seven characteristics from a readings file",
                       description="Compute the draft's seven characteristics and the Annex A "
                                   "uncertainty from a readings file; write results.json, "
                                   "summary.txt and tables/*.csv into --out.")
    p.add_argument("readings", help="readings file (CSV, docs/formats.md#readings-file) or a stream (docs/formats.md#stream-file, "
                   "reduced with the protocol first; told apart by the header)")
    p.add_argument("--spec", default=None,
                   help="specification (default: the readings' '# spec:' metadata, else "
                        "ogam-draft)")
    p.add_argument("--protocol", default=None,
                   help="protocol file or built-in name (default: the specification's)")
    p.add_argument("--budget", choices=("physical", "draft"), default="physical",
                   help="E's budget: physical (default: Annex A plus the lines beyond the draft "
                        "the validation showed to matter) or draft (the annex's four lines)")
    p.add_argument("--tilt", default=None, metavar="FILE",
                   help="a 'gonio tilt-estimate --json' result: bounds the tilt by psi + U95 "
                        "instead of the protocol's tilt bound")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--json", action="store_true", help="print results.json on stdout")
    add_certificate_options(p)
    p.add_argument("--dcc", action="store_true",
                   help="also write certificate.dcc.xml, the PTB Digital Calibration "
                        "Certificate (DCC 3.3.0 XML)")
    p.add_argument("--monte-carlo", type=int_range(0), default=0, metavar="N",
                   help="also propagate the budget by JCGM 101 Monte Carlo with N trials")
    p.add_argument("--thermal", default=None, metavar="FILE",
                   help="triad-alignment: the thermal-programme readings (default: the file "
                        "the readings' '# thermal_readings:' metadata names, or their own "
                        "thermal rows)")
    p.add_argument("--robust", action="store_true",
                   help="triad-alignment: robust alignment fit (IRLS), outlying dwells "
                        "down-weighted and listed")
    p.set_defaults(func=run)


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


def print_result(result, as_json: bool) -> None:
    """Print a per-item specification's results.json (``--json``) or its summary."""
    if as_json:
        print(json.dumps(result.to_json(), indent=2, ensure_ascii=False, allow_nan=False))
    else:
        print(result.summary(), end="")


def print_outputs(report, as_json: bool, lab_d: dict | None, lang: str) -> None:
    """Print results.json (``--json``) or the summary, and the one-line CJK font note."""
    import sys

    from gonio.report.certificate import cjk_notice

    note = cjk_notice(lang)
    if note:
        sys.stderr.write(f"gonio: note: {note}\n")
    if as_json:
        sys.stdout.write(json.dumps(report.decided_result(lab_d).to_json(), indent=2,
                                    ensure_ascii=False, allow_nan=False) + "\n")
    else:
        sys.stdout.write(report.summary(lab_d))
    sys.stdout.flush()


def emit(report, out, as_json: bool, *, lab=None, lang: str = "en", truth=None,
         dcc: bool = False, inputs=(), force: bool = False) -> None:
    """Write the whole output set (results, tables, certificate, optional DCC) as one staged
    set (:func:`gonio.pipeline.calibrate.write_outputs`) and print the summary (or JSON)."""
    from gonio.progress import status
    from gonio.report.certificate import load_lab

    import sys

    lab_d = load_lab(lab) if lab else None      # validate before anything is written
    for w in report.warnings():
        print(w, file=sys.stderr)
    status("writing the results and the certificate")
    write_outputs(report, out, truth=truth, lab=lab_d, lang=lang, dcc=dcc, inputs=inputs,
                  force=force)
    status("")
    print_outputs(report, as_json, lab_d, lang)


def run(args) -> int:
    from gonio.atomic import check_output_dir, output_set
    from gonio.limits import check

    check("GONIO_MAX_MONTE_CARLO", args.monte_carlo, "--monte-carlo", unit="trials")
    inputs = [args.readings, args.protocol, args.lab]
    check_output_dir(args.out, inputs=inputs, force=args.force)   # before the work
    from gonio.pipeline.rate import RATE_SPECS, calibrate as calibrate_rate, readings_spec
    from gonio.progress import status

    spec = args.spec or readings_spec(args.readings) or "ogam-draft"
    if spec == "triad-alignment":
        from gonio.pipeline.triad import calibrate as calibrate_triad

        for flag, given in (("--tilt", args.tilt),
                            ("--budget", args.budget != "physical"),
                            ("--protocol", args.protocol)):
            if given:
                raise GonioError(f"{flag} does not apply to the triad-alignment "
                                 "specification (no tilt file, draft budget or protocol "
                                 "for a triad calibration: the readings carry what it needs)",
                                 key=flag)

        from gonio.formats.triad import named_inputs
        inputs += [args.thermal, *named_inputs(args.readings)]   # never replaced or removed
        check_output_dir(args.out, inputs=inputs, force=args.force)
        with output_set(args.out, inputs=inputs, force=args.force):
            result, _ = calibrate_triad(args.readings, args.out, thermal=args.thermal,
                                        lab=args.lab, lang=args.lang,
                                        monte_carlo_trials=args.monte_carlo,
                                        robust=args.robust, dcc=args.dcc)
        print_result(result, args.json)
        return 0
    if args.thermal or args.robust:
        raise GonioError("--thermal and --robust apply to the triad-alignment specification "
                         f"only, not {spec}", key="--thermal" if args.thermal else "--robust")
    if spec != "ogam-draft":
        if spec not in RATE_SPECS:
            from gonio.specs import get
            get(spec)                                  # GonioError listing the keys
        with output_set(args.out, inputs=inputs, force=args.force):    # one whole set
            result, _ = calibrate_rate(args.readings, args.out, spec_key=spec,
                                       protocol=args.protocol, lab=args.lab, lang=args.lang,
                                       monte_carlo_trials=args.monte_carlo, dcc=args.dcc)
        print_result(result, args.json)
        return 0
    status("calibrating")
    report = calibrate(args.readings, args.protocol, monte_carlo_trials=args.monte_carlo,
                       budget=args.budget, tilt=args.tilt)
    emit(report, args.out, args.json, lab=args.lab, lang=args.lang, dcc=args.dcc,
         inputs=inputs, force=args.force)
    return 0
