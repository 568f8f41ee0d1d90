"""``gonio tilt``: the extreme tilt error over 0–360° (draft Annex A.4.2) and where it occurs.

``--model elliptic`` is the draft's elliptic-projection model; ``--model rigid`` the
rigid-body rate-gyro model (zero after scale-factor calibration, or θ(cos ψ − 1)
with ``--uncalibrated``). A thin layer over :mod:`gonio.physics.tilt`.
"""

from __future__ import annotations

import json
import math

from gonio.errors import GonioError
from gonio.cli.checks import float_range


def register(subparsers) -> None:
    """Add the ``tilt`` sub-command."""
    p = subparsers.add_parser(
        "tilt", help="extreme error from a sensing-plane tilt (Annex A.4.2)",
        description="Largest error over 0-360° caused by a tilt between the gyro's sensing "
                    "plane and the table plane, and the table angles where it occurs.")
    p.add_argument("--tilt-deg", type=float_range(0, 45), default=0.1, metavar="PSI",
                   help="tilt in degrees, 0 <= PSI < 90 (default 0.1)")
    p.add_argument("--model", choices=("elliptic", "rigid"), default="elliptic",
                   help="elliptic projection (the draft's) or rigid-body rate gyro")
    p.add_argument("--uncalibrated", action="store_true",
                   help="rigid model only: before the scale-factor calibration")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Compute and print the extreme tilt error."""
    from gonio.physics.tilt import elliptic_extreme, rigid_extreme

    t = args.tilt_deg
    if not (math.isfinite(t) and 0.0 <= t < 90.0):
        raise GonioError(f"--tilt-deg: must satisfy 0 <= tilt < 90 degrees, got {t}")
    if args.model == "elliptic":
        e = elliptic_extreme(t)
    else:
        e = rigid_extreme(t, calibrated=not args.uncalibrated)
    if args.json:
        print(json.dumps({"extreme_arcsec": e.extreme_arcsec, "at_deg": list(e.at_deg),
                          "model": e.model, "tilt_deg": e.tilt_deg}, indent=2))
    else:
        where = ", ".join(f"{a:.4f}°" for a in e.at_deg) or "(none: zero everywhere)"
        print(f"{e.model} model, tilt {e.tilt_deg:g}°: extreme error {e.extreme_arcsec:.4f}\u2033 "
              f"at {where}")
    return 0
