"""The triad-alignment calibration: readings → alignment and (optionally) thermal model."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gonio.analysis.thermal_model import ThermalModelResult, identify_thermal_model
from gonio.analysis.triad_alignment import AlignmentResult, cross_axis_table, estimate_alignment
from gonio.errors import GonioError
from gonio.formats.triad import TriadReadings, json_safe, read_triad_readings
from gonio.physics.alignment import ARTICLE_WORKED_EXAMPLE, MisalignmentBudget, misalignment_budget


@dataclass
class TriadCalibration:
    """Alignment result (when the readings have alignment rows) and thermal model (when
    they have thermal rows)."""

    alignment: AlignmentResult | None
    thermal: ThermalModelResult | None
    source: str = ""

    def to_json(self) -> dict:
        out = {"spec": "triad-alignment", "source": self.source,
               "alignment": None if self.alignment is None else self.alignment.to_json(),
               "thermal_model": None if self.thermal is None else self.thermal.to_json()}
        if self.alignment is not None:
            out["cross_axis"] = cross_axis_table(self.alignment).to_dict(orient="records")
        return json_safe(out)


def _as_readings(readings) -> TriadReadings:
    if isinstance(readings, TriadReadings):
        return readings
    if isinstance(readings, (str, Path)):
        return read_triad_readings(readings)
    raise GonioError(f"triad-alignment needs a triad readings file or TriadReadings, got "
                     f"{type(readings).__name__}")


def calibrate(readings, protocol=None, *, robust: bool = False, monte_carlo: int = 0,
              seed: int = 0, target_deg: float = 0.1, criterion: str = "bic",
              temperature: str = "sensor") -> TriadCalibration:
    """Alignment (:func:`gonio.analysis.triad_alignment.estimate_alignment`) from the
    ``alignment`` rows and the extended model
    (:func:`gonio.analysis.thermal_model.identify_thermal_model`) from the ``thermal``
    rows of a triad readings file. ``protocol`` is accepted for the plug-in interface and
    not needed: everything the analysis uses is in the file."""
    r = _as_readings(readings)
    tests = set(r.data["test"])
    al = th = None
    if "alignment" in tests:
        al = estimate_alignment(r, robust=robust, monte_carlo=monte_carlo, seed=seed,
                                target_deg=target_deg)
    if "thermal" in tests:
        th = identify_thermal_model(r, criterion=criterion, temperature=temperature)
    if al is None and th is None:
        raise GonioError(f"{r.path}: no alignment or thermal rows")
    return TriadCalibration(al, th, str(r.path or ""))


def article_budget() -> MisalignmentBudget:
    """The alignment article's worked mechanical budget (eq. 5a–5c), exact values:
    ADIS16485 on ledges with 0.2 mm height tolerance over W = 44 mm, M2 screws in 2.85 mm
    holes spaced 39.6 mm × 42.6 mm, IMU axis-to-frame misalignment 1°. The article's
    printed values and where they differ: :data:`gonio.physics.alignment.ARTICLE_WORKED_EXAMPLE`."""
    return misalignment_budget(ledge_tolerance_mm=0.2, width_mm=44.0, hole_diameter_mm=2.85,
                               screw_diameter_mm=2.0, hole_spacing_mm=(39.6, 42.6),
                               psi_imu_deg=1.0)


__all__ = ["TriadCalibration", "calibrate", "article_budget", "ARTICLE_WORKED_EXAMPLE"]
