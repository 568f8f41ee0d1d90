"""``gonio sagnac``: Sagnac scale factor of a ring-laser or fibre-optic gyro.

RLG: K = 4A/(λP) pulses per radian; FOG: 2πLD/(λc) rad of phase per rad/s
(docs/draft-readings.md#sagnac-effect). A thin layer over
:func:`gonio.physics.sagnac.sagnac_rlg` and :func:`gonio.physics.sagnac.sagnac_fog`.
"""

from __future__ import annotations

import json
import math

from gonio.errors import GonioError
from gonio.cli.checks import float_range, json_safe


def register(subparsers) -> None:
    """Add the ``sagnac`` sub-command."""
    p = subparsers.add_parser(
        "sagnac", help="Sagnac scale factor of an RLG or FOG",
        description="Sagnac scale factor: --rlg with --area-m2 and --perimeter-m, or --fog "
                    "with --length-m and --diameter-m; also the signal of the full Earth rate.")
    kind = p.add_mutually_exclusive_group(required=True)
    kind.add_argument("--rlg", action="store_true", help="ring-laser gyro")
    kind.add_argument("--fog", action="store_true", help="fibre-optic gyro")
    # bounds from physics (positive, finite) and representability (checked on the result in
    # gonio.physics.sagnac), not from the instruments one has in mind: UG-2 encloses 834 m²
    positive = float_range(0, math.inf, lo_open=True)
    p.add_argument("--area-m2", type=positive, help="RLG: enclosed area, m² (> 0, ≤ P²/4π)")
    p.add_argument("--perimeter-m", type=positive, help="RLG: perimeter, m (> 0)")
    p.add_argument("--length-m", type=positive, help="FOG: fibre length, m (> 0)")
    p.add_argument("--diameter-m", type=positive, help="FOG: coil diameter, m (> 0)")
    p.add_argument("--wavelength-nm", type=positive, default=None,
                   help="wavelength, nm (> 0; default 632.8 for --rlg, 1550 for --fog)")
    p.add_argument("--latitude-deg", type=float_range(-90, 90), default=None, metavar="PHI",
                   help="also the signal of the Earth rate on a horizontal ring/coil (Ω sin φ)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Compute and print the scale factor."""
    from gonio.physics.sagnac import sagnac_fog, sagnac_rlg

    if args.rlg:
        for opt in ("area_m2", "perimeter_m"):
            if getattr(args, opt) is None:
                raise GonioError(f"--{opt.replace('_', '-')} is required with --rlg")
        lam = (args.wavelength_nm or 632.8) * 1e-9
        try:
            s = sagnac_rlg(args.area_m2, args.perimeter_m, lam, args.latitude_deg)
        except GonioError as exc:
            raise GonioError(f"--rlg: {exc.message}") from None
    else:
        for opt in ("length_m", "diameter_m"):
            if getattr(args, opt) is None:
                raise GonioError(f"--{opt.replace('_', '-')} is required with --fog")
        lam = (args.wavelength_nm or 1550.0) * 1e-9
        try:
            s = sagnac_fog(args.length_m, args.diameter_m, lam, args.latitude_deg)
        except GonioError as exc:
            raise GonioError(f"--fog: {exc.message}") from None
    if args.json:
        print(json.dumps(json_safe(s.to_dict()), indent=2, allow_nan=False))
        return 0
    if s.kind == "rlg":
        print(f"RLG at {s.wavelength_m * 1e9:g} nm: K = {s.scale_factor_counts_per_rad:.6g} "
              f"pulses/rad = {s.scale_factor_counts_per_deg:.6g} pulses/° "
              f"(one pulse = {s.resolution_arcsec:.6g}″)")
        print(f"full Earth rate: {s.earth_rate_signal:.6g} Hz beat frequency")
        if s.earth_rate_up_signal is not None:
            print(f"horizontal ring at latitude {s.latitude_deg:g}°: Sagnac frequency "
                  f"{s.earth_rate_up_signal:.6g} Hz (Ω sin φ)")
    else:
        print(f"FOG at {s.wavelength_m * 1e9:g} nm: Sagnac phase {s.phase_per_rate_s:.6g} "
              f"rad per rad/s")
        print(f"full Earth rate: {s.earth_rate_signal:.6g} rad of phase")
        if s.earth_rate_up_signal is not None:
            print(f"horizontal coil at latitude {s.latitude_deg:g}°: "
                  f"{s.earth_rate_up_signal:.6g} rad of phase (Ω sin φ)")
    return 0
