"""The optical draft's record of continuous instrument output over the 7.3 rest, cut from a
laboratory's stream or captured by the virtual bench.

A :class:`StaticRecord` is the instrument's output over a phase at rest (the 7.3
zero-stability phase), the input of the draft's noise analysis. It is plain data: the
calibration builds one from a laboratory's stream, the virtual bench from its own
simulation, and neither needs the other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class StaticRecord:
    """The instrument's record over the 7.3 zero-stability phase (at rest), for noise analysis.

    ``angle_deg`` is the pulse counter divided by the nominal scale factor (not
    compensated: the Allan deviation ignores a constant rate).
    """

    time_s: np.ndarray
    angle_deg: np.ndarray
    source: str = "virtual bench, 7.3 block"
