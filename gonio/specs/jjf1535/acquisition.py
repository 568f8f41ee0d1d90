"""JJF 1535-2015 on a laboratory's bench: the programme ``gonio acquire`` runs (the hook
``SPEC.acquisition``).

The same segments the virtual bench runs (:func:`gonio.specs.jjf1535.protocol.plan`); what
the simulation takes from the bench file, a laboratory states: the gyro's datasheet
bandwidth where the protocol sets no ``bandwidth.estimated_bandwidth_hz``
(``--meta datasheet_bandwidth_hz=…``), its null output and the site's latitude where the
protocol says ``"bench"`` (``--meta null_output=…``, ``--meta latitude_deg=…``, or what
the gyro output reader states of the gyro), its equipment's uncertainties
(``rate_table_u_rel``, ``rate_table_ripple_rel``, ``acquisition_u_rel``,
``chamber_deviation_bound_c``, ``chamber_uniformity_c``: defaults of
:func:`gonio.specs.jjf1535.make_context` otherwise).
"""

from __future__ import annotations

from gonio.errors import GonioError
from gonio.protocol.programme import Programme, check_rate_session_size
from gonio.specs.jjf1535.protocol import KEY, JJFProtocol, load_protocol, plan


def programme(protocol=None, metadata: dict | None = None) -> Programme:
    """The acquisition programme of ``protocol`` (file, built-in name or loaded) with the
    laboratory's ``metadata`` (strings, ``--meta``)."""
    proto = protocol if isinstance(protocol, JJFProtocol) else load_protocol(protocol or KEY)
    md = dict(metadata or {})
    f = md.pop("datasheet_bandwidth_hz", None)
    try:
        f_hz = float(f) if f not in (None, "") else None
    except ValueError:
        raise GonioError(f"--meta datasheet_bandwidth_hz={f!r}: expected a number in Hz") from None
    segs = plan(proto, datasheet_bandwidth_hz=f_hz)
    check_rate_session_size(segs, where="the acquisition programme")
    P = proto.sections
    # no "# room_temperature_c" line: the protocol's room temperature is a nominal, not a
    # measurement (the calibration takes it from the protocol); the room tests' rows log
    # the temperature the chamber measured, or nothing without one
    out = {"spec": KEY, "protocol": proto.path.stem if proto.path else KEY}
    for key, value in (("null_output", P["protocol"]["null_output"]),
                       ("latitude_deg", P["bias"]["latitude_deg"])):
        if value != "bench":
            out[key] = repr(float(value))
    out.update(md)
    return Programme(segs, out)
