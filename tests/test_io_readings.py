"""Readings files (data-formats contract, section 1): parsing, validation, round trip."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import ORIENTATIONS, TEST_NAMES, parse_readings, read_readings, write_readings

DATA = Path(__file__).parent / "data"
HEADER = "test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg"


def test_constants():
    assert TEST_NAMES[:5] == ("scale_factor", "zero_stability", "angle_deviation",
                              "rate_consistency", "pointing_consistency")
    assert {"equal_division", "tilt_estimate"} <= set(TEST_NAMES)
    assert ORIENTATIONS == ("up", "north", "south", "east", "west")


def test_contract_example_parses():
    """The example of data-formats section 1, verbatim."""
    text = """# instrument: FOG goniometer
# serial: 0042
# nominal_scale_factor_counts_per_deg: 3600
# latitude_deg: 39.9
test,series,round,rate_dps,orientation,time_s,table_deg,gyro_counts,gyro_deg
scale_factor,1,1,60,up,3.0,60.0,216000,
angle_deviation,1,1,60,up,7.5,30.0,,30.0000417
zero_stability,1,1,,up,0,,,0.0
zero_stability,1,2,,up,300,,,0.0000625
"""
    r = parse_readings(text, path="example.csv")
    assert list(r.metadata) == ["instrument", "serial", "nominal_scale_factor_counts_per_deg",
                                "latitude_deg"]
    assert r.metadata["serial"] == "0042"          # text kept, not a number
    d = r.data
    assert d["line"].tolist() == [6, 7, 8, 9]
    assert d["rate_dps"].tolist() == [60.0, 60.0, 60.0, 60.0]   # empty -> 60
    assert d["gyro_counts"].iloc[0] == 216000.0 and math.isnan(d["gyro_counts"].iloc[1])
    assert d["gyro_deg"].iloc[1] == 30.0000417
    assert math.isnan(d["table_deg"].iloc[2])
    assert d["series"].dtype == np.int64 and d["round"].dtype == np.int64
    assert d["gyro_counts"].dtype == np.float64


def test_defaults_when_columns_absent():
    r = parse_readings("test,series,round,time_s,table_deg,gyro_deg\n"
                       "angle_deviation,2,3,1.5,30.0,30.0\n")
    assert r.data.loc[0, "rate_dps"] == 60.0 and r.data.loc[0, "orientation"] == "up"
    assert math.isnan(r.data.loc[0, "gyro_counts"])
    assert r.data.loc[0, "series"] == 2 and r.data.loc[0, "line"] == 2


def test_bom_and_crlf_accepted(tmp_path):
    r = read_readings(DATA / "bom_crlf.csv")
    assert r.metadata == {"serial": "7"}
    assert r.data["gyro_deg"].tolist() == [30.0001, 59.9999]
    assert r.data["line"].tolist() == [3, 4]
    # the same content made on the fly (in case a checkout normalised line ends)
    plain = (DATA / "partial.csv").read_bytes()
    p = tmp_path / "x.csv"
    p.write_bytes(b"\xef\xbb\xbf" + plain.replace(b"\n", b"\r\n"))
    a, b = read_readings(p), read_readings(DATA / "partial.csv")
    pd.testing.assert_frame_equal(a.data, b.data)
    assert a.metadata == b.metadata


def test_input_not_modified(tmp_path):
    src = DATA / "full.csv"
    before = src.read_bytes()
    read_readings(src)
    assert src.read_bytes() == before


def test_extra_columns_kept():
    r = parse_readings("test,series,round,time_s,table_deg,gyro_deg,note\n"
                       "angle_deviation,1,1,1.0,30.0,30.0,first\n"
                       "angle_deviation,1,2,2.0,60.0,60.0,\n")
    assert r.data["note"].tolist() == ["first", ""]


def test_fractional_counts_allowed_when_not_quantised():
    body = HEADER + "\nangle_deviation,1,1,60,up,1.0,30.0,108000.25,\n"
    with pytest.raises(GonioError, match="integer pulse count"):
        parse_readings(body, path="q.csv")
    r = parse_readings("# counts_quantised: false\n" + body, path="q.csv")
    assert r.data.loc[0, "gyro_counts"] == 108000.25


def test_large_integer_counts_exact():
    r = parse_readings(HEADER + "\nscale_factor,1,1,60,up,1.0,360.0,4503599627370497,\n")
    # 2**52 + 1 is exactly representable in float64
    assert int(r.data.loc[0, "gyro_counts"]) == 2 ** 52 + 1


GOOD = "angle_deviation,1,1,60,up,5.0,30.0,108000,30.0001"
# (description, file text, expected line, expected column or None, message fragment)
BAD = [
    ("missing column", "test,series,round,time_s,gyro_deg\nangle_deviation,1,1,5,30\n",
     1, "table_deg", "missing required column"),
    ("no gyro column", "test,series,round,time_s,table_deg\nangle_deviation,1,1,5,30\n",
     1, "gyro_counts", "need gyro_counts or gyro_deg"),
    ("unparsable time", HEADER + "\n" + GOOD.replace("5.0", "5.0s"), 2, "time_s",
     "expected a number"),
    ("nan text", HEADER + "\n" + GOOD.replace("30.0001", "nan"), 2, "gyro_deg", "finite"),
    ("inf text", HEADER + "\n" + GOOD.replace(",30.0,", ",inf,"), 2, "table_deg", "finite"),
    ("overflow", HEADER + "\n" + GOOD.replace("5.0", "1e999"), 2, "time_s", "finite"),
    ("series 0", HEADER + "\n" + GOOD.replace("angle_deviation,1,", "angle_deviation,0,"),
     2, "series", "integer >= 1"),
    ("round 1.5", HEADER + "\n" + GOOD.replace("deviation,1,1,", "deviation,1,1.5,"),
     2, "round", "integer >= 1"),
    ("series text", HEADER + "\n" + GOOD.replace("deviation,1,", "deviation,one,"),
     2, "series", "expected a number"),
    ("rate 0", HEADER + "\n" + GOOD.replace(",60,", ",0,"), 2, "rate_dps", "rate > 0"),
    ("rate negative", HEADER + "\n" + GOOD.replace(",60,", ",-60,"), 2, "rate_dps",
     "rate > 0"),
    ("unknown test", HEADER + "\n" + GOOD.replace("angle_deviation", "angle_dev"), 2,
     "test", "unknown test"),
    ("unknown orientation", HEADER + "\n" + GOOD.replace(",up,", ",down,"), 2,
     "orientation", "unknown orientation"),
    ("no gyro value", HEADER + "\n" + GOOD.replace("108000,30.0001", ","), 2,
     "gyro_counts", "neither"),
    ("fractional counts", HEADER + "\n" + GOOD.replace("108000", "108000.5"), 2,
     "gyro_counts", "integer pulse count"),
    ("scale_factor without counts",
     HEADER + "\n" + GOOD.replace("angle_deviation", "scale_factor").replace("108000", ""),
     2, "gyro_counts", "need gyro_counts"),
    ("empty table_deg", HEADER + "\n" + GOOD.replace(",30.0,", ",,"), 2, "table_deg",
     "empty cell"),
    ("duplicate key", HEADER + "\n" + GOOD + "\n" + GOOD.replace("5.0", "6.0"), 3, "round",
     "already on line 2"),
    ("duplicate key, defaults", "test,series,round,time_s,table_deg,gyro_deg\n"
     "zero_stability,1,1,0,,0\nzero_stability,1,1,300,,0\n", 3, "round", "duplicated"),
    ("wrong field count", HEADER + "\n" + GOOD + ",extra", 2, None, "expected 9 fields"),
    ("header only", "# a: b\n" + HEADER + "\n", 2, None, "no readings"),
    ("empty file", "", 1, None, "no readings"),
    ("metadata only", "# a: b\n# c: d\n", 2, None, "no readings"),
    ("bad metadata line", "# just a comment\n" + HEADER + "\n" + GOOD, 1, None,
     "bad metadata line"),
    ("metadata after header", HEADER + "\n# late: 1\n" + GOOD, 2, None, "metadata line"),
    ("duplicated header column", HEADER + ",time_s\n" + GOOD + ",1", 1, "time_s",
     "column given twice"),
]


@pytest.mark.parametrize("text,line,column,fragment", [b[1:] for b in BAD],
                         ids=[b[0] for b in BAD])
def test_validation_errors_name_file_line_column(tmp_path, text, line, column, fragment):
    p = tmp_path / "bad.csv"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(GonioError) as exc:
        read_readings(p)
    err = exc.value
    assert err.file == str(p)
    assert err.line == line
    assert err.column == column
    assert fragment in str(err)
    assert str(err).startswith(f"{p}:{line}: ")


@pytest.mark.parametrize("key,value", [
    ("nominal_scale_factor_counts_per_deg", "-3600"),
    ("nominal_scale_factor_counts_per_deg", "abc"),
    ("latitude_deg", "91"),
    ("humidity_pct", "150"),
    ("temperature_c", "nan"),
    ("table_mpe_arcsec", "-0.1"),
    ("tilt_bound_deg", "x"),
    ("counts_quantised", "maybe"),
])
def test_bad_numeric_metadata_names_key(tmp_path, key, value):
    p = tmp_path / "m.csv"
    p.write_text(f"# {key}: {value}\n{HEADER}\n{GOOD}\n")
    with pytest.raises(GonioError) as exc:
        read_readings(p)
    assert exc.value.key == key and exc.value.file == str(p)


def test_not_utf8(tmp_path):
    p = tmp_path / "l1.csv"
    p.write_bytes(("# operator: J\xfcrgen\n" + HEADER + "\n" + GOOD + "\n").encode("latin-1"))
    with pytest.raises(GonioError) as exc:
        read_readings(p)
    assert exc.value.line == 1


def test_missing_file(tmp_path):
    with pytest.raises(GonioError, match="cannot read"):
        read_readings(tmp_path / "nope.csv")


# ----------------------------------------------------------------------------- writing

def test_round_trip_full_file(tmp_path):
    a = read_readings(DATA / "full.csv")
    out = write_readings(a, tmp_path / "w.csv")
    b = read_readings(out)
    assert b.metadata == a.metadata
    pd.testing.assert_frame_equal(a.data.drop(columns="line"), b.data.drop(columns="line"))
    # writing what was read gives the same bytes again (deterministic, idempotent)
    out2 = write_readings(b, tmp_path / "w2.csv")
    assert out2.read_bytes() == out.read_bytes()
    text = out.read_text()
    assert "\r" not in text
    assert text.splitlines()[5] == HEADER  # no extra columns here
    assert "scale_factor,1,1,60.0,up,3.0,60.0,216030," in text
    assert "zero_stability,1,1,60.0,up,0.0,,,0.0" in text


def test_round_trip_floats_bit_exact(tmp_path):
    """Random floats survive write/read bit for bit (repr round-trips)."""
    rng = np.random.default_rng(20240501)
    n = 200
    df = pd.DataFrame({
        "test": ["angle_deviation"] * n, "series": np.arange(1, n + 1), "round": [1] * n,
        "rate_dps": rng.uniform(0.5, 300, n), "orientation": rng.choice(ORIENTATIONS, n),
        "time_s": rng.uniform(0, 1e5, n), "table_deg": rng.uniform(-720, 720, n),
        "gyro_counts": np.where(rng.random(n) < 0.5, np.nan,
                                rng.integers(-2**40, 2**40, n).astype(float)),
        "gyro_deg": rng.normal(0, 100, n) * 10.0 ** rng.integers(-12, 3, n),
        "note": [f"n{i}" for i in range(n)],
    })
    p = write_readings(df, tmp_path / "r.csv", {"instrument": "sim", "seed": "20240501"})
    back = read_readings(p)
    for col in ("rate_dps", "time_s", "table_deg", "gyro_counts", "gyro_deg"):
        a, b = df[col].to_numpy(float), back.data[col].to_numpy(float)
        assert np.array_equal(a, b, equal_nan=True), col
    assert back.data["orientation"].tolist() == df["orientation"].tolist()
    assert back.data["note"].tolist() == df["note"].tolist()
    assert list(back.metadata.items()) == [("instrument", "sim"), ("seed", "20240501")]
    assert p.read_text().splitlines()[2] == HEADER + ",note"


def test_write_fractional_counts_needs_metadata(tmp_path):
    df = pd.DataFrame({"test": ["angle_deviation"], "series": [1], "round": [1],
                       "time_s": [1.0], "table_deg": [30.0], "gyro_counts": [1.5],
                       "gyro_deg": [np.nan]})
    with pytest.raises(GonioError, match="counts_quantised"):
        write_readings(df, tmp_path / "f.csv", {})
    assert not (tmp_path / "f.csv").exists()
    p = write_readings(df, tmp_path / "f.csv", {"counts_quantised": "false"})
    assert read_readings(p).data.loc[0, "gyro_counts"] == 1.5


def test_write_rejects_metadata_with_newline(tmp_path):
    df = read_readings(DATA / "partial.csv").data
    with pytest.raises(GonioError):
        write_readings(df, tmp_path / "x.csv", {"operator": "a\nb"})
