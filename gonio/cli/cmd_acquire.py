"""``gonio acquire``: run a protocol's programme on a rotary table and an acquisition module,
or a rate specification's on a rate table, gyro output reader, chamber and supply, through
VISA (:func:`gonio.pipeline.acquire.acquire`)."""

from __future__ import annotations

from gonio.errors import GonioError


def register(sub) -> None:
    p = sub.add_parser("acquire", help="run a protocol on the bench's instruments (VISA)",
                       description="Run a protocol's programme (zeroing, turns, rests, triggered "
                                   "reads) on a rotary table and the goniometer's acquisition "
                                   "module reached through VISA, writing readings.csv as the "
                                   "readings come (for gonio calibrate) and io.log (every "
                                   "command and answer). Ctrl-C, SIGTERM, a lost link or an "
                                   "instrument error stop the table and keep the readings, "
                                   "marked incomplete; --resume continues them. A rate "
                                   "specification's protocol runs its "
                                   "programme on a rate table, a gyro output reader, a chamber "
                                   "and a supply (--chamber, --supply).")
    p.add_argument("--protocol", required=True, help="protocol file or built-in name")
    p.add_argument("--table", required=True,
                   help="VISA resource of the table controller, e.g. TCPIP0::host::5025::SOCKET")
    p.add_argument("--gyro", required=True,
                   help="VISA resource of the acquisition module, e.g. ASRL/dev/ttyUSB0::INSTR")
    p.add_argument("--chamber", help="VISA resource of the temperature chamber (a rate "
                                     "specification's programme with temperature points)")
    p.add_argument("--supply", help="VISA resource of the gyro's power supply (a rate "
                                    "specification's programme: power cycles)")
    p.add_argument("--out", required=True, help="output folder (readings.csv, io.log)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted acquisition in --out from its last complete "
                        "round")
    p.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                   help="an extra metadata line, e.g. latitude_deg=40.2 (repeatable)")
    p.add_argument("--timezone", default=None, metavar="ZONE",
                   help="the laboratory's IANA time zone (the records' setting timezone, e.g. "
                        "Asia/Shanghai): the readings' # date: is its calendar date, and it "
                        "is written as # timezone:; default: this computer's local zone")
    p.add_argument("--timeout", type=float, default=10.0,
                   help="seconds an instrument may take to answer (default 10)")
    p.set_defaults(func=run)


def _meta(items: list[str]) -> dict:
    md = {}
    for it in items:
        k, sep, v = it.partition("=")
        if not sep or not k.strip():
            raise GonioError(f"--meta {it!r}: expected KEY=VALUE")
        md[k.strip()] = v.strip()
    return md


def run(args) -> int:
    from gonio.instruments.run import zone_info
    from gonio.pipeline.acquire import acquire

    md = _meta(args.meta)
    if args.timezone is not None:
        zone_info(args.timezone)            # an IANA zone, else one line, exit 2
        md["timezone"] = args.timezone
    res = acquire(args.protocol, {"table": args.table, "gyro": args.gyro,
                                  "chamber": args.chamber, "supply": args.supply},
                  args.out, metadata=md, resume=args.resume,
                  timeout_s=args.timeout)
    print(res.readings)
    print(res.io_log)
    return 0
