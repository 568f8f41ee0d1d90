"""Screening of JJF 1535 readings: each reading against what the rest of its
segment predicts, in every column, and the programme of the protocol (a rate point, record
or position planned and absent is named). The rules are those of
:mod:`gonio.specs._rate_family.screening`; this module gives them the JJF programme
(:func:`gonio.specs.jjf1535.protocol.plan`) and the clause of each test.
"""

from __future__ import annotations

from types import SimpleNamespace

from gonio.result.findings import Finding
from gonio.specs._rate_family import screening
from gonio.specs._rate_family.rate_records import load_readings, protocol_named
from gonio.specs.jjf1535.protocol import KEY, JJFProtocol, load_protocol, plan

CLAUSES = {"scale_factor": "7.2.1", "sf_temperature": "7.2.5", "threshold": "7.2.6",
           "resolution": "7.2.7", "bias": "7.2.8", "warmup": "7.2.9", "g_sensitivity": "7.2.12",
           "static": "7.2.13", "bias_temperature": "7.2.14", "vibration": "7.2.15"}


def screen(readings, protocol=None, **_options) -> list[Finding]:
    """Findings of the screening of a JJF 1535 readings file (path or RateReadings) under
    ``protocol`` (file, built-in name or loaded; default the built-in programme)."""
    rd = load_readings(readings)
    proto = protocol if isinstance(protocol, JJFProtocol) else \
        load_protocol(protocol_named(rd, protocol, KEY))
    # the plan needs a bench only for the vibration frequencies, which are not checked here
    stand_in = SimpleNamespace(gyro=SimpleNamespace(datasheet_bandwidth_hz=1.0))
    # the nominal scale factor enters no item (every one reads the measured K): flagged only
    meta = screening.metadata_rules(rd, proto.sections["protocol"]["null_output"], None)
    return meta + screening.screen(rd, plan(proto, stand_in), CLAUSES) + screening.rate_table_unstated(
        rd.metadata, None if rd.path is None else str(rd.path),
        "JJF 1535 Table 2's rate accuracy (the table is taken to conform to it)")
