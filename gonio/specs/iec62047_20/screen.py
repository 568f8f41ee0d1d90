"""Screening of IEC 62047-20 readings: each reading against what the rest of its
segment predicts, in every column, and the programme of the protocol (a rate point, set
point, supply voltage, stand angle or record planned and absent is named). The rules are
those of :mod:`gonio.specs._rate_family.screening`; this module gives them the IEC programme
(:func:`gonio.specs.iec62047_20.protocol.plan`) and the clause of each test.
"""

from __future__ import annotations

from gonio.result.findings import Finding
from gonio.specs._rate_family import screening
from gonio.specs._rate_family.rate_records import load_readings, protocol_named
from gonio.specs.iec62047_20.protocol import KEY, IECProtocol, load_protocol, plan

CLAUSES = {"scale_factor": "5.1.3.1", "sf_temperature": "5.1.3.3", "ratiometric": "5.1.3.5",
           "cross_axis": "5.2", "bias": "5.3.3.1", "warmup": "5.3.3.5",
           "bias_temperature": "5.3.3.6", "g_sensitivity": "5.3.3.8", "static": "5.4.5",
           "vibration": "5.5", "resolution": "5.6"}

#: The items a_TYP, the nominal scale factor, enters (a contradicted nominal is refused).
USED_BY = "a_TYP of 5.1.3.2 (initial scale-factor variation) and 5.1.3.8 (symmetry)"


def screen(readings, protocol=None, **_options) -> list[Finding]:
    """Findings of the screening of an IEC 62047-20 readings file (path or RateReadings)
    under ``protocol`` (file, built-in name or loaded; default the one the readings name, else
    the built-in programme, as :func:`calibrate` takes it). ``SPEC.screen``: the pipeline hands
    the findings to :func:`calibrate` (``findings=``)."""
    rd = load_readings(readings)
    proto = protocol if isinstance(protocol, IECProtocol) else \
        load_protocol(protocol_named(rd, protocol, KEY))
    P = proto.sections["protocol"]
    meta = screening.metadata_rules(rd, P["null_output"], P["nominal_scale_factor"], USED_BY)
    return meta + screening.screen(rd, plan(proto, None), CLAUSES) + screening.rate_table_unstated(
        rd.metadata, None if rd.path is None else str(rd.path),
        "the laboratory's assumption taken from JJF 1535 Table 2 (IEC 62047-20 states no "
        "requirement on the rate table's accuracy)")
