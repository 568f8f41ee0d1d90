"""A rate-gyro programme: the list of :class:`Segment` a specification plans from its protocol.

A programme says what is recorded and under which conditions (table rate, mounting, chamber
set point, supply, vibration); it is planned by a specification package (e.g.
a specification's ``plan``) and run on the virtual bench by
:func:`gonio.bench.rate_session.run_rate_session` (or on a real bench by the laboratory).
Planning never needs the simulator, so the calibration path can read a protocol without
importing :mod:`gonio.bench`.
"""

from __future__ import annotations

from dataclasses import dataclass

from gonio.errors import GonioError


@dataclass(frozen=True)
class Segment:
    """One recorded segment of a programme.

    ``delay_s`` passes unrecorded before it (settling, warm-up, soak); ``power_on`` starts
    a new power cycle first (after ``off_time_s`` switched off). ``temperature_c`` is the
    chamber set point (None: chamber off, room temperature); ``supply_v`` None: nominal.
    ``vib_amplitude_dps`` > 0 makes it a vibration segment at ``freq_hz`` (instantaneous
    samples); otherwise each sample is the mean output over ``interval_s``.
    """

    test: str
    run: int
    step: int
    role: str
    samples: int
    interval_s: float
    rate_dps: float = 0.0
    up_axis: str = "+z"
    north_axis: str = "+x"
    temperature_c: float | None = None
    ramp_c_per_min: float = 1.0
    supply_v: float | None = None
    freq_hz: float = 0.0
    vib_amplitude_dps: float = 0.0
    delay_s: float = 0.0
    power_on: bool = False
    off_time_s: float = 0.0
    stand_deg: float = 0.0
    stand_axis: str = "+x"


@dataclass(frozen=True)
class Programme:
    """What a rate specification's acquisition hook (``Specification.acquisition``) gives
    ``gonio acquire``: the segments to run in order and the readings' metadata lines (the
    specification, the protocol's name, what its calibration reads from the metadata). The
    temperature of a record with the chamber off is measured, not given here
    (:class:`gonio.instruments.rate_acquire.RateAcquisition`)."""

    segments: list
    metadata: dict


def check_rate_session_size(segments: list[Segment], *, where: str = "the programme") -> int:
    """Refuse a rate-gyro programme beyond the stated limits before simulating it.

    Every sample becomes a row of readings.csv and is held in memory until written, so
    the rows are checked against ``GONIO_MAX_READING_ROWS`` (the limit the readings
    reader applies to the same file) and the programme's duration against
    ``GONIO_MAX_SESSION_S`` (:mod:`gonio.limits`). The message names the protocol
    section (through the readings' ``test`` of the segments) contributing most rows. Returns the rows.

    >>> check_rate_session_size([Segment("arw", 1, 0, "rest", 1000, 0.1)])
    1000
    >>> check_rate_session_size([Segment("arw", 1, 0, "rest", 10**9, 0.1)])
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: key arw: the programme: 1e+09 samples (rows of readings.csv) exceed the limit of 1e+06 (set GONIO_MAX_READING_ROWS to raise it); most come from the test 'arw' (100%) — its protocol section's sample counts
    """
    from gonio.limits import check, limit

    per: dict[str, int] = {}
    dur = 0.0
    for seg in segments:
        per[seg.test] = per.get(seg.test, 0) + max(int(seg.samples), 0)
        dur += (float(seg.delay_s) + float(seg.off_time_s)
                + max(int(seg.samples), 0) * max(float(seg.interval_s), 0.0))
    n = sum(per.values())
    top = max(per, key=per.get) if per else "protocol"
    lim = limit("GONIO_MAX_READING_ROWS")
    if n > lim:
        raise GonioError(f"{where}: {n:.4g} samples (rows of readings.csv) exceed the limit of "
                         f"{lim:.4g} (set GONIO_MAX_READING_ROWS to raise it); most come from "
                         f"the test {top!r} ({per[top] / n:.0%}) — its protocol section's sample counts",
                         key=top)
    check("GONIO_MAX_SESSION_S", dur, f"{where}: the programme lasts", unit="s")
    return n


def calibration_segments(test: str, run: int, rates_one_dir: list[float], *, dt: float, rest_samples: int,
                n_low: int, n_high: int, settle_s: float, order: str, first_delay_s: float,
                power_on: bool, off_time_s: float, temperature_c=None, ramp=1.0,
                supply_v=None, include_zero: bool = False) -> list[Segment]:
    """One scale-factor calibration (JJF 7.2.1.1 c)–d) or IEC 5.1.4.1): rest, the rates in
    the given order (forward ascending then reverse ascending, or alternating ±Ω pairs),
    rest. ``include_zero`` adds a rest point in the middle (IEC: a fit point)."""
    if order == "ascending":
        seq = [r for r in rates_one_dir] + [-r for r in rates_one_dir]
    elif order == "alternating":
        seq = [s * r for r in rates_one_dir for s in (1, -1)]
    elif order == "iec":                      # x_1 = CCW max … rest … CW max
        seq = [-r for r in sorted(rates_one_dir, reverse=True)] + [0.0] + sorted(rates_one_dir)
    else:
        raise GonioError(f"order must be ascending or alternating, got {order!r}", key="order")
    segs = [Segment(test, run, 0, "rest", rest_samples, dt, 0.0, temperature_c=temperature_c,
                    ramp_c_per_min=ramp, supply_v=supply_v, delay_s=first_delay_s,
                    power_on=power_on, off_time_s=off_time_s)]
    for j, r in enumerate(seq, 1):
        n = n_low if abs(r) < 100 else n_high
        point = r != 0 or order == "iec"          # IEC 5.1.3.1: the rest is a fit point
        segs.append(Segment(test, run, j, "rate" if point else "rest", n if point else rest_samples,
                            dt, r, temperature_c=temperature_c, ramp_c_per_min=ramp,
                            supply_v=supply_v, delay_s=settle_s))
    segs.append(Segment(test, run, len(seq) + 1, "rest", rest_samples, dt, 0.0,
                        temperature_c=temperature_c, ramp_c_per_min=ramp, supply_v=supply_v,
                        delay_s=settle_s))
    return segs
