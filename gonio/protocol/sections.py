"""Optional protocol sections beyond the draft's own: ``[equal_division]`` and ``[tilt_estimate]``.

They live here, in the protocol layer, so that the analyses that use them (the equal-division
averaging and the in-situ tilt estimate) import the protocol and never the other way round. Each section is registered
with :func:`gonio.protocol.model.register_section` when this module is imported
(``gonio.protocol`` imports it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gonio.physics.earth import NAMED_AXES
from gonio.formats.toml import Field, non_negative, positive
from gonio.protocol.model import ORIENTATIONS, register_section

@dataclass(frozen=True)
class EdaProtocol:
    """The ``[equal_division]`` protocol section (IEC 62047-20 Annex A.3 procedure).

    Attributes
    ----------
    starts, points, repeats : int
        ``n`` starts ``360°/n`` apart, ``m`` points per revolution, repeats.
    rate_dps, rest_s, read_delay_s : float
        Table rate, rest at each stop, reading delay after arrival.
    orientation : str
        Table-axis direction.
    """

    starts: int
    points: int
    repeats: int
    rate_dps: float
    rest_s: float
    read_delay_s: float
    orientation: str

    @property
    def step_deg(self) -> float:
        """The step ``Δ = 360°/m``."""
        return 360.0 / self.points

    @property
    def start_deg(self) -> np.ndarray:
        """Start positions ``k·360°/n``."""
        return np.arange(self.starts) * 360.0 / self.starts


def _is_int_ge(lo):
    return lambda x: x >= lo


EDA_PROTOCOL_SCHEMA: dict[str, Field] = {
    "starts": Field("int", 12, _is_int_ge(1), "an integer ≥ 1"),
    "points": Field("int", 12, _is_int_ge(2), "an integer ≥ 2"),
    "repeats": Field("int", 1, _is_int_ge(1), "an integer ≥ 1"),
    "rate_dps": Field("float", 60.0, positive, "> 0"),
    "rest_s": Field("float", 10.0, lambda x: x >= 0, "≥ 0"),
    "read_delay_s": Field("float", 5.0, lambda x: x >= 0, "≥ 0"),
    "orientation": Field("str", "up", choices=ORIENTATIONS),
}


def _eda_factory(v: dict) -> EdaProtocol:
    return EdaProtocol(**v)


register_section("equal_division", EDA_PROTOCOL_SCHEMA, _eda_factory)


@dataclass(frozen=True)
class TiltEstimatePlan:
    """The static multi-position test: N equally spaced rests of ``dwell_s`` each.

    Readings (one per position, test ``tilt_estimate``): ``round`` = position index
    (1…N), ``table_deg`` = position (360°·(i−1)/N), ``time_s`` = dwell time,
    ``gyro_counts`` = pulses accumulated over the dwell, *not* Earth-rate
    compensated (the Earth rate is the signal).
    """

    clause: str = "in-situ tilt estimate (gonio; supports Annex A.1/A.4.2)"
    positions: int = 12
    dwell_s: float = 60.0
    settle_s: float = 5.0
    orientation: str = "up"
    rate_dps: float = 60.0


SECTION_SCHEMA = {
    "clause": Field("str", TiltEstimatePlan.clause),
    "positions": Field("int", 12, lambda n: n >= 4, "an integer ≥ 4"),
    "dwell_s": Field("float", 60.0, positive, "> 0"),
    "settle_s": Field("float", 5.0, non_negative, "≥ 0"),
    "orientation": Field("str", "up", choices=tuple(NAMED_AXES)),
    "rate_dps": Field("float", 60.0, positive, "> 0"),
}


def _plan(d: dict) -> TiltEstimatePlan:
    return TiltEstimatePlan(**d)


register_section("tilt_estimate", SECTION_SCHEMA, _plan)
