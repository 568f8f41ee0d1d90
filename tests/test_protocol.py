"""The protocol loader: the draft's file, a laboratory's own protocol, and every kind of bad key."""

from __future__ import annotations

import dataclasses

import pytest

from gonio.errors import GonioError
from gonio.specs.ogam_draft.protocol import load_protocol, parse_protocol
from gonio.formats.toml import read_toml


def test_draft_protocol_holds_the_draft():
    p = load_protocol("ogam-draft")
    sf = p.scale_factor
    assert [r.stop_deg for r in sf.rounds] == [60, 120, 180, 240, 300, 360]        # 7.1
    assert [r.max_rotation_s for r in sf.rounds] == [3, 4, 5, 6, 7, 8]
    assert sf.rate_dps == 60 and sf.rest_s == 60
    ad = p.angle_deviation
    assert [r.stop_deg for r in ad.rounds] == [30.0 * i for i in range(1, 13)]     # 7.4
    assert [r.max_rotation_s for r in ad.rounds] == [2.5 + 0.5 * i for i in range(12)]
    assert ad.series == 10                                                         # 7.5
    assert p.zero_stability.readings == 15 and p.zero_stability.interval_s == 300  # 7.3
    assert p.session.warm_up_s == 3600
    assert p.rate_reference_dps == 60
    assert sorted({i.orientation for i in p.pointing_consistency} | {"up"}) == ["east", "north", "up"]
    assert dataclasses.asdict(p.annex_a) == {
        "table_mpe_arcsec": 0.1, "tilt_bound_deg": 0.1, "zero_stability_dph": 0.005,
        "duration_min": 0.5, "repeatability_arcsec": 0.096, "coverage_factor": None,
        # beyond the draft: K's chamber-temperature line, the per-type default bounds
        "sf_temperature_coeff_bound_rlg_ppm_per_c": 0.1,
        "sf_temperature_coeff_bound_fog_ppm_per_c": 1.0}
    assert p.conditions.table_axis_wobble_max_arcsec == 0.3
    te = p.tilt_estimate            # beyond the draft: the in-situ tilt estimate K is corrected by
    assert (te.positions, te.dwell_s, te.settle_s, te.orientation) == (12, 120.0, 5.0, "up")


def test_laboratory_protocol_24_points_5_repeats():
    p = parse_protocol({"protocol": {"name": "lab"},
                        "angle_deviation": {"series": 5,
                                            "rounds": [{"stop_deg": 15.0 * i} for i in range(1, 25)]}})
    assert p.angle_deviation.series == 5 and len(p.angle_deviation.rounds) == 24
    assert p.scale_factor is None and p.zero_stability is None


@pytest.mark.parametrize("raw, key", [
    ({"protocol": {"name": "x"}, "scale_factor": {"rounds": [{"stop_deg": 60}], "speed": 1}},
     "scale_factor.speed"),
    ({"protocol": {"name": "x"}, "scale_factor": {"rounds": [{"stop_deg": 60}], "rate_dps": "fast"}},
     "scale_factor.rate_dps"),
    ({"protocol": {"name": "x"}, "scale_factor": {"rounds": [{"stop_deg": 60}], "rate_dps": -60}},
     "scale_factor.rate_dps"),
    ({"protocol": {"name": "x"}, "angle_deviation": {"rounds": [{"stop_deg": 30}], "series": 0}},
     "angle_deviation.series"),
    ({"protocol": {"name": "x"}, "angle_deviation": {"rounds": [{"stop": 30}]}},
     "angle_deviation.rounds[0].stop"),
    ({"protocol": {"name": "x"}, "angle_deviation": {"rounds": [{"stop_deg": 0.0}]}},
     "angle_deviation.rounds[0]"),
    ({"protocol": {"name": "x"}, "zero_stability": {"readings": 1}}, "zero_stability.readings"),
    ({"protocol": {"name": "x"}, "pointing_consistency": {"orientations": ["up", "sideways"],
                                                          "rounds": [{"stop_deg": 30}]}},
     "pointing_consistency.orientations[1]"),
    ({"protocol": {"name": "x"}, "session": {"earth_compensation": "magic"}},
     "session.earth_compensation"),
    ({"protocol": {"name": "x"}, "rate_consistency": {"rates_dps": [1.0, 10.0], "rounds": [{"stop_deg": 30}]}},
     "rate_consistency.reference_rate_dps"),
    ({"protocol": {"name": "x"}, "annexa": {}}, "annexa"),
    ({"scale_factor": {}}, "protocol"),
])
def test_bad_protocol_names_the_key(raw, key):
    with pytest.raises(GonioError) as exc:
        parse_protocol(raw, "lab.toml")
    assert f"key {key}:" in str(exc.value) and str(exc.value).startswith("lab.toml: ")


def test_toml_syntax_error_names_file(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("[protocol\nname = 1\n")
    with pytest.raises(GonioError, match=r"p.toml:1: TOML syntax"):
        read_toml(f)
    with pytest.raises(GonioError, match="protocol file not found"):
        load_protocol(tmp_path / "missing.toml")


def test_optical_readings_protocol_name_from_the_one_header_reader(tmp_path):
    """The optical calibration reads '# protocol:' with the pipeline's header reader
    (gonio.formats.metadata.header_lines; its own copy is gone): BOM and blank lines skipped,
    the first line wins, a line after the data is no metadata; a file that is not text gives
    None and is left to the readings reader to name."""
    from gonio.specs.ogam_draft.calibration import file_protocol_name

    p = tmp_path / "r.csv"
    p.write_text("\ufeff# spec: ogam-draft\n\n# protocol: mylab\n# protocol: second\n"
                 "test,table_deg\n# protocol: after\n", encoding="utf-8")
    assert file_protocol_name(p) == "mylab"
    p.write_text("# spec: ogam-draft\ntest,table_deg\n# protocol: after\n", encoding="utf-8")
    assert file_protocol_name(p) is None
    p.write_bytes(b"PAR1\x00\x01\x02binary")
    assert file_protocol_name(p) is None
    assert file_protocol_name(tmp_path / "missing.csv") is None


def test_header_lines_yields_each_line_once_past_64_kib(tmp_path):
    """Review finding: a header over one 64 KiB piece re-yielded every earlier line with each
    new piece (3000 lines gave 5019 pairs); in file order, once each."""
    from gonio.formats.metadata import header_lines

    p = tmp_path / "long.csv"
    p.write_text("".join(f"# key{i}: {'v' * 40}{i}\n" for i in range(3000)) + "t,v\n1,2\n",
                 encoding="utf-8")
    pairs = list(header_lines(p))
    assert [k for k, _ in pairs] == [f"key{i}" for i in range(3000)]
