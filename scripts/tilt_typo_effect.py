"""What a typo below the tilt-estimate screen's floor does to ψ, its azimuth and K.

The tilt-estimate rows (``[tilt_estimate]``: N rests of dwell T) are screened by
``screen.tilt_estimate_rule``, whose threshold has a floor of 3 × the A.4.3 drift over the
dwell (1.8″ at 0.005 °/h and 120 s): a typo δ below it is used. It moves the rest's rate by
δ/T, so the first-harmonic coefficients (a, b) by (2/N)(δ/T)(cos θ_k, sin θ_k): the tilt
vector (ψ cos α, ψ sin α) by at most 2δ/(N T Ω_⊥ cos ψ) rad, whatever the position and
azimuth, and K's tilt correction, linear in that vector, by at most A_K at that tilt
(``budget_extra.scale_factor_tilt_bias``). The typo also widens the fit's residuals, so
u(ψ) grows with it. For simulated files (``gonio simulate --seed S`` of the built-in
programme, ``--bench``) each rest in turn gets +δ and −δ (whole counts); printed: the largest
|Δψ| and |Δα| over the plants, the closed-form bound, |Δψ| / U95(ψ) of the planted file (the
shift in the file's own interval), the largest shift of K's tilt correction against the bound
(relative, ppb) and U(K)/K of the clean calibration where given (``--uk-ppb``).

    python scripts/tilt_typo_effect.py /tmp/d7/readings.csv [--sizes 0.5,1,1.5,1.8]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from gonio.physics.earth import earth_rate_split
from gonio.specs.ogam_draft.budget_extra import scale_factor_tilt_bias
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs.ogam_draft.readings import Readings, read_readings
from gonio.specs.ogam_draft.screen import reference_scale_factor, tilt_estimate_rule
from gonio.specs.ogam_draft.tilt_estimate import tilt_estimate_from_readings
from gonio.units import ARCSEC_PER_DEG


def tilt_vector(e) -> np.ndarray:
    """(ψ cos α, ψ sin α), rad, α the tilt's azimuth in the table frame."""
    psi = math.radians(e.tilt_deg)
    az = math.radians(e.tilt_azimuth_table_deg)
    return np.array([psi * math.cos(az), psi * math.sin(az)])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("readings", nargs="+")
    ap.add_argument("--sizes", default="0.5,1,1.5,1.8")
    ap.add_argument("--protocol", default="ogam-draft")
    a = ap.parse_args(argv)
    protocol = load_protocol(a.protocol)
    for path in a.readings:
        r = read_readings(path)
        df, md = r.data, r.metadata
        k = float(md["nominal_scale_factor_counts_per_deg"])
        lat = float(md["latitude_deg"])
        rows = np.flatnonzero((df["test"] == "tilt_estimate").to_numpy())
        n, dwell = rows.size, float(np.median(df["time_s"].to_numpy()[rows]))
        e0 = tilt_estimate_from_readings(r)
        v0 = tilt_vector(e0)
        perp = earth_rate_split(lat, e0.orientation).perpendicular_dps * ARCSEC_PER_DEG
        sf = df[df["test"] == "scale_factor"]
        k_ref = reference_scale_factor(df, md)
        per_rad = scale_factor_tilt_bias(sf, protocol, lat, 1.0) / math.sin(math.radians(1.0))
        print(f"{path}: ψ = {e0.tilt_deg:.4f}° (U95 {e0.k95 * e0.u_tilt_deg:.4f}°), azimuth "
              f"{e0.tilt_azimuth_table_deg:.1f}°, N = {n}, T = {dwell:g} s, Ω_⊥ = {perp:.3f}″/s; "
              f"K's tilt coupling {per_rad / ARCSEC_PER_DEG * 1e9 * math.radians(0.01):.1f} ppb "
              f"per 0.01° of tilt")
        for size in (float(x) for x in a.sizes.split(",")):
            worst = dict(dpsi=0.0, daz=0.0, ratio=0.0, dvec=0.0, screened=0)
            for i in rows:
                for sgn in (1, -1):
                    d2 = df.copy()
                    d2.at[i, "gyro_counts"] += sgn * round(size / ARCSEC_PER_DEG * k)
                    r2 = Readings(d2, md, None)
                    if tilt_estimate_rule(d2, protocol, None, k_ref, set()):
                        worst["screened"] += 1
                        continue
                    e = tilt_estimate_from_readings(r2)
                    dpsi = abs(e.tilt_deg - e0.tilt_deg)
                    daz = abs((e.tilt_azimuth_table_deg - e0.tilt_azimuth_table_deg + 180) % 360
                              - 180)
                    dvec = float(np.hypot(*(tilt_vector(e) - v0)))
                    worst["dpsi"] = max(worst["dpsi"], dpsi)
                    worst["daz"] = max(worst["daz"], daz)
                    worst["ratio"] = max(worst["ratio"], dpsi / (e.k95 * e.u_tilt_deg))
                    worst["dvec"] = max(worst["dvec"], dvec)
            bound = 2 * size / (n * dwell * perp * math.cos(math.radians(e0.tilt_deg)))
            # K's tilt correction is linear in the tilt vector: its shift is at most A_K(|Δv|)
            dk_ppb = per_rad * worst["dvec"] / ARCSEC_PER_DEG * 1e9
            bk_ppb = per_rad * bound / ARCSEC_PER_DEG * 1e9
            print(f"  δ = {size:g}″: max |Δψ| {worst['dpsi']:.4f}°, max |Δα| {worst['daz']:.1f}°, "
                  f"max |Δ tilt vector| {math.degrees(worst['dvec']):.4f}° (bound "
                  f"{math.degrees(bound):.4f}°), max |Δψ|/U95(ψ) {worst['ratio']:.2f}; K's tilt "
                  f"correction moves ≤ {dk_ppb:.1f} ppb (bound {bk_ppb:.1f}); "
                  f"{worst['screened']} of {2 * n} plants set aside by the screen")


if __name__ == "__main__":
    main()
