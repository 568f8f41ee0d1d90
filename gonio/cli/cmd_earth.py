"""``gonio earth``: the Earth rate on a table axis at a latitude (draft 4.5, 7.7).

A thin layer over :func:`gonio.physics.earth.earth_rate`.
"""

from __future__ import annotations

import json
import math

from gonio.errors import GonioError
from gonio.cli.checks import float_range


def register(subparsers) -> None:
    """Add the ``earth`` sub-command."""
    p = subparsers.add_parser(
        "earth", help="Earth rate on an axis at a latitude",
        description="Earth rate on an axis (up, north, south, east, west or AZ,EL in degrees) "
                    "at a latitude, in deg/h, arcsec/s and rad/s, with its parts along and "
                    "across the axis.")
    p.add_argument("--latitude-deg", type=float_range(-90, 90), required=True, metavar="PHI",
                   help="latitude in degrees, north positive (within ±90)")
    p.add_argument("--axis", default="up", metavar="AXIS",
                   help="up, north, south, east, west, or AZ,EL in degrees (default up)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Compute and print the Earth rate on the axis."""
    from gonio.physics.earth import earth_rate

    if not math.isfinite(args.latitude_deg) or abs(args.latitude_deg) > 90:
        raise GonioError(f"--latitude-deg: must be within ±90°, got {args.latitude_deg}")
    try:
        r = earth_rate(args.latitude_deg, args.axis)
    except GonioError as exc:
        raise GonioError(f"--axis: {exc.message}") from None
    if args.json:
        print(json.dumps(r.to_dict(), indent=2))
        return 0
    print(f"latitude {r.latitude_deg:g}°, axis azimuth {r.axis_azimuth_deg:g}° elevation "
          f"{r.axis_elevation_deg:g}°")
    print(f"Earth rate on the axis: {r.rate_dph:.6f} °/h = {r.rate_arcsec_s:.6f} ″/s "
          f"= {r.rate_rad_s:.6e} rad/s")
    print(f"parallel {r.parallel_dph:.6f} °/h, perpendicular {r.perpendicular_dph:.6f} °/h "
          f"({r.perpendicular_arcsec_s:.6f} ″/s)")
    return 0
