"""``SPEC.screen`` is a hook of every specification: the pipeline screens first and hands the
findings to ``SPEC.calibrate`` (``findings=``), which applies them and states every one
(issue 23). Checked through the one pipeline function, on the built-in specifications."""

from __future__ import annotations

import dataclasses
import json

import pytest

from gonio.errors import GonioError
from gonio.pipeline.dispatch import screen_and_calibrate
from gonio.result.findings import Finding
from gonio.specs import available, get


def test_every_built_in_specification_has_a_screening_hook():
    from gonio.specs import BUILT_IN
    specs = available()
    assert all(specs[k].screen is not None for k in BUILT_IN)


def counting(spec, extra=()):
    """``spec`` with its screen wrapped: the calls are counted and ``extra`` findings added."""
    calls = []

    def screen(readings, protocol=None, **options):
        calls.append(options)
        return list(spec.screen(readings, protocol, **options)) + list(extra)
    return dataclasses.replace(spec, screen=screen), calls


@pytest.fixture(scope="module")
def triad(tmp_path_factory):
    out = tmp_path_factory.mktemp("triad")
    get("triad-alignment").simulate(out, seed=2)
    return out / "readings.csv"


def test_the_pipeline_hands_the_findings_to_calibrate(triad):
    spec = get("triad-alignment")
    base = screen_and_calibrate(spec, triad, None)
    flag = Finding("test-flag", "a flag raised by the screening hook", "flagged",
                   file=str(triad), line=7, column="out_x", test="alignment", clause="—",
                   rule="test")
    wrapped, calls = counting(spec, [flag])
    got = screen_and_calibrate(wrapped, triad, None)
    assert len(calls) == 1                            # screened once, by the pipeline
    assert [f.code for f in got.findings] == [f.code for f in base.findings] + ["test-flag"]
    assert json.dumps(got.items["M_xy"].to_json()) == json.dumps(base.items["M_xy"].to_json())
    # a refused finding of the hook stops the calibration, naming the file and line
    stop = dataclasses.replace(flag, action="refused", message="refused by the hook")
    refusing, _ = counting(spec, [stop])
    with pytest.raises(GonioError, match="refused by the hook") as e:
        screen_and_calibrate(refusing, triad, None)
    assert e.value.line == 7


def test_a_readings_file_is_read_once_for_screen_and_calibrate(tmp_path, monkeypatch):
    """The optical draft's screen keeps the file it read for the calibration that follows
    (a stream is reduced once); a changed file is read again."""
    from gonio.specs.ogam_draft.bench import Bench, InstrumentConfig, TableConfig, run_session, write_session
    from gonio.specs.ogam_draft.protocol import parse_protocol
    import gonio.specs.ogam_draft.calibration as cal

    proto = parse_protocol({
        "protocol": {"name": "tiny"}, "session": {"static_s": 5.0, "warm_up_s": 0.0},
        "scale_factor": {"rounds": [{"stop_deg": 180.0}, {"stop_deg": 360.0}],
                         "read_delay_s": 2.0, "rest_s": 3.0},
        "angle_deviation": {"series": 2, "rest_s": 3.0, "read_delay_s": 2.0,
                            "rounds": [{"stop_deg": 120.0 * i} for i in range(1, 4)]}})
    bench = Bench("small", InstrumentConfig(arw_dpsh=0.003), TableConfig(), latitude_deg=40.0,
                  sample_rate_hz=10.0)
    paths = write_session(run_session(proto, bench, seed=1), tmp_path)
    ptoml = tmp_path / "tiny.toml"
    ptoml.write_text('[protocol]\nname = "tiny"\n[session]\nstatic_s = 5.0\nwarm_up_s = 0.0\n'
                     '[scale_factor]\nread_delay_s = 2.0\nrest_s = 3.0\n'
                     'rounds = [{stop_deg = 180.0}, {stop_deg = 360.0}]\n'
                     '[angle_deviation]\nseries = 2\nrest_s = 3.0\nread_delay_s = 2.0\n'
                     'rounds = [{stop_deg = 120.0}, {stop_deg = 240.0}, {stop_deg = 360.0}]\n',
                     encoding="utf-8")
    reads = []
    real = cal._read
    monkeypatch.setattr(cal, "_read", lambda p, pr: (reads.append(p), real(p, pr))[1])
    spec, calls = counting(get("ogam-draft"))
    rep = screen_and_calibrate(spec, paths["readings"], str(ptoml))
    assert len(calls) == 1 and len(reads) == 1
    assert rep.items["scale_factor"].measured
    # the same result as a calibration that screens by itself
    alone = get("ogam-draft").calibrate(paths["readings"], str(ptoml))
    assert len(reads) == 2 and not cal._KEPT
    assert rep.to_json()["items"] == alone.to_json()["items"]
