"""``gonio tilt-estimate``: ψ and α from the static multi-position rows of a readings file.

A thin layer over :func:`gonio.analysis.tilt_estimate.tilt_estimate_from_readings` (protocol
``protocols/tilt-estimate.toml``; the bench writes such files with ``gonio simulate``).
"""

from __future__ import annotations

import json

from gonio.cli.checks import float_range, positive_magnitude


def register(subparsers) -> None:
    """Add the ``tilt-estimate`` sub-command."""
    p = subparsers.add_parser(
        "tilt-estimate", help="estimate the sensing-axis tilt from a static multi-position test",
        description="Fit c0 + a cos θ + b sin θ to the mean rates of the tilt_estimate rows "
                    "and report ψ = asin(hypot(a, b)/Ω_⊥) and the tilt azimuth α with their "
                    "standard uncertainties (residual-based covariance).")
    p.add_argument("file", metavar="FILE", help="readings CSV with tilt_estimate rows")
    p.add_argument("--scale-factor", type=positive_magnitude, default=None, metavar="K",
                   help="counts/° (default: the file's nominal_scale_factor_counts_per_deg)")
    p.add_argument("--latitude-deg", type=float_range(-90, 90), default=None, metavar="PHI",
                   help="site latitude (default: the file's latitude_deg)")
    p.add_argument("--u-latitude-deg", type=float_range(0, 90), default=0.0, metavar="U",
                   help="standard uncertainty of the latitude, degrees (default 0)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Read the file, estimate, print."""
    from gonio.analysis.tilt_estimate import tilt_estimate_from_readings
    from gonio.formats.readings import read_readings

    r = read_readings(args.file)
    e = tilt_estimate_from_readings(r, args.scale_factor, args.latitude_deg, args.u_latitude_deg)
    if args.json:
        print(json.dumps(e.to_dict(), indent=2))
        return 0
    print(f"in-situ tilt estimate: {e.n_positions} positions, axis {e.orientation}, "
          f"latitude {e.latitude_deg:g}°, Ω_⊥ = {e.perpendicular_arcsec_s:.4f}″/s")
    print(f"first harmonic {e.amplitude_arcsec_s:.5f}″/s (u {e.u_amplitude_arcsec_s:.5f}), "
          f"residual s = {e.residual_sd_arcsec_s:.5f}″/s, ν = {e.dof}")
    print(f"tilt ψ = {e.tilt_deg:.4f}°, u(ψ) = {e.u_tilt_deg:.4f}° "
          f"(U95 = {e.k95 * e.u_tilt_deg:.4f}°, k = {e.k95:.2f})")
    print(f"tilt azimuth relative to Ω_⊥ at table 0°: {e.phase_deg:.2f}°, u = {e.u_phase_deg:.2f}°")
    return 0
