"""The seven characteristics of draft clause 7 against values worked by hand.

Every expected number below is computed here from the literal numbers of the
hand-made files in tests/data, with plain arithmetic and the standard
library's ``statistics`` module (not numpy/pandas code paths of the package).
"""

from __future__ import annotations

import json
import math
import statistics as st
from pathlib import Path

import pandas as pd
import pytest

from gonio.specs.ogam_draft.items import (
    angle_deviation, compute_characteristics, indicated_angle_deg, pointing_consistency,
    rate_consistency, repeatability, scale_factor, scale_factor_nonlinearity, signed_extreme,
    summary_table, zero_stability,
)
from gonio.errors import GonioError
from gonio.specs.ogam_draft.readings import parse_readings, read_readings

DATA = Path(__file__).parent / "data"
AS = 3600.0  # arcsec per degree


def extreme(values):
    """Hand version of "E = ± max|E_i|" keeping the sign (first on ties)."""
    best = values[0]
    for v in values[1:]:
        if abs(v) > abs(best):
            best = v
    return best


# ---- the numbers of tests/data/full.csv, retyped -------------------------------------
K_I = [216030 / 60.0, 432000 / 120.0, 648180 / 180.0]
K = sum(K_I) / 3                                           # 3600.5
ZS_M = [0.0, 0.00005, 0.00002, 0.00009]                     # deg at 0, 300, 600, 900 s
AD = {  # series -> [(table_deg, M_deg)] for rounds 1..3
    1: [(120.0, 120.0001), (240.0, 239.99985), (360.0, 360.0002)],
    2: [(120.0, 120.00015), (240.0, 239.9999), (360.0, 1296181 / K)],
    3: [(120.00001, 120.00005), (240.0, 239.9998), (360.0, 360.00025)],
}
E_IJ = {j: [(m - s) * AS for s, m in pts] for j, pts in AD.items()}
E_I = [st.mean(E_IJ[j][i] for j in (1, 2, 3)) for i in range(3)]
E_60 = extreme(E_I)
REF_ANGLE = st.mean(AD[j][2][1] for j in (1, 2, 3)) * AS   # mean M at 360 deg, arcsec
E_10 = extreme([(120.0003 - 120) * AS, (240.0001 - 240) * AS, (360.0004 - 360) * AS])
E_100 = extreme([(119.9998 - 120) * AS, (239.9997 - 240) * AS, (359.9999 - 360) * AS])
E_EAST = extreme([(120.0004 - 120) * AS, (240.0002 - 240) * AS, (360.0003 - 360) * AS])
E_NORTH = extreme([(119.9997 - 120) * AS, (240.0001 - 240) * AS, (360.0 - 360) * AS])


@pytest.fixture(scope="module")
def full():
    return read_readings(DATA / "full.csv")


@pytest.fixture(scope="module")
def res(full):
    return compute_characteristics(full)


def test_scale_factor(res):
    sf = res.scale_factor
    assert sf.measured and sf.unit == "counts/deg" and sf.clause == "7.1"
    assert sf.value == pytest.approx(K, rel=1e-15)
    assert sf.table["K_i_counts_per_deg"].tolist() == pytest.approx(K_I, rel=1e-15)
    assert sf.table["line"].tolist() == [7, 8, 9]


def test_scale_factor_several_series_mean_over_all_rounds():
    df = pd.DataFrame({"test": ["scale_factor"] * 3, "series": [1, 1, 2], "round": [1, 2, 1],
                       "table_deg": [60.0, 120.0, 60.0],
                       "gyro_counts": [216000.0, 432120.0, 216090.0], "line": [2, 3, 4]})
    sf = scale_factor(df)
    assert sf.value == pytest.approx((3600 + 3601 + 3601.5) / 3, rel=1e-15)
    assert len(sf.table) == 3 and sf.details["n_series"] == 2


def test_nonlinearity(res):
    nl = res.scale_factor_nonlinearity
    assert nl.unit == "%" and nl.clause == "7.2"
    assert nl.value == pytest.approx((max(K_I) - min(K_I)) / K * 100, rel=1e-12)


def test_nonlinearity_needs_two_rounds():
    df = pd.DataFrame({"test": ["scale_factor"], "series": [1], "round": [1],
                       "table_deg": [60.0], "gyro_counts": [216000.0], "line": [2]})
    nl = scale_factor_nonlinearity(scale_factor(df))
    assert not nl.measured and nl.value is None and "2" in nl.reason


def test_zero_stability(res):
    z = res.zero_stability
    t_h = 900 / 3600
    assert z.unit == "deg/h" and z.measured
    assert z.value == pytest.approx(st.stdev(ZS_M) / t_h, rel=1e-12)
    assert z.details["range_deg_per_h"] == pytest.approx((max(ZS_M) - min(ZS_M)) / t_h,
                                                          rel=1e-12)
    assert z.details["n_readings"] == 4 and z.details["duration_s"] == 900.0


def test_zero_stability_counts_and_worst_series():
    # series 1 in counts (K = 4000), series 2 in degrees; value is the worse series
    df = pd.DataFrame({"test": ["zero_stability"] * 5, "series": [1, 1, 1, 2, 2],
                       "round": [1, 2, 3, 1, 2], "time_s": [0.0, 1800.0, 3600.0, 0.0, 7200.0],
                       "gyro_counts": [0.0, 2.0, 1.0, float("nan"), float("nan")],
                       "gyro_deg": [float("nan")] * 3 + [0.0, 0.01], "line": [2, 3, 4, 5, 6]})
    z = zero_stability(df, 4000.0)
    s1 = st.stdev([0.0, 2 / 4000, 1 / 4000]) / 1.0
    s2 = st.stdev([0.0, 0.01]) / 2.0
    assert z.table["B_s_deg_per_h"].tolist() == pytest.approx([s1, s2], rel=1e-12)
    assert z.value == pytest.approx(max(s1, s2), rel=1e-12)
    assert z.details["series"] == 2


def test_zero_stability_zero_duration_is_an_error(tmp_path):
    p = tmp_path / "z.csv"
    p.write_text("test,series,round,time_s,table_deg,gyro_deg\n"
                 "zero_stability,1,1,5,,0\nzero_stability,1,2,5,,0.001\n")
    with pytest.raises(GonioError) as exc:
        compute_characteristics(read_readings(p))
    assert exc.value.file == str(p) and exc.value.line == 3 and exc.value.column == "time_s"


def test_indicated_angle():
    df = pd.DataFrame({"gyro_deg": [1.5, float("nan")], "gyro_counts": [9.0, 7201.0],
                       "line": [2, 3]})
    assert indicated_angle_deg(df, 3600.0).tolist() == [1.5, 7201 / 3600]
    with pytest.raises(GonioError) as exc:
        indicated_angle_deg(df, None)
    assert exc.value.line == 3 and exc.value.column == "gyro_counts"


def test_signed_extreme():
    assert signed_extreme([0.1, -0.3, 0.2]) == -0.3
    assert signed_extreme([0.3, -0.3]) == 0.3           # first on a tie
    assert math.isnan(signed_extreme([]))


def test_angle_deviation(res):
    e = res.angle_deviation
    assert e.unit == "arcsec" and e.clause == "7.4"
    assert e.value == pytest.approx(E_60, abs=1e-9)
    assert e.details["max_abs_arcsec"] == pytest.approx(abs(E_60), abs=1e-9)
    assert e.table["E_arcsec"].tolist() == pytest.approx(E_I, abs=1e-9)
    assert e.table["n_series"].tolist() == [3, 3, 3]
    assert e.table["position_deg"].iloc[0] == pytest.approx((120 + 120 + 120.00001) / 3)
    # the full E_ij matrix
    m = e.tables["matrix"]
    for j in (1, 2, 3):
        assert m[f"series_{j}"].tolist() == pytest.approx(E_IJ[j], abs=1e-9)
    assert e.details["scale_factor_for_angles_counts_per_deg"] == pytest.approx(K)


def test_repeatability(res):
    r = res.repeatability
    r_i = [st.stdev([E_IJ[j][i] for j in (1, 2, 3)]) for i in range(3)]
    assert r.unit == "arcsec" and r.clause == "7.5"
    assert r.table["R_arcsec"].tolist() == pytest.approx(r_i, abs=1e-9)
    assert r.value == pytest.approx(max(r_i), abs=1e-9)


def test_rate_consistency(res):
    c = res.rate_consistency
    spread = max(E_10, E_100, E_60) - min(E_10, E_100, E_60)
    assert c.unit == "ppm" and c.clause == "7.6"
    assert c.details["spread_arcsec"] == pytest.approx(spread, abs=1e-9)
    assert c.details["reference_angle_arcsec"] == pytest.approx(REF_ANGLE, rel=1e-15)
    assert c.value == pytest.approx(spread / REF_ANGLE * 1e6, rel=1e-9)
    t = c.table.set_index("rate_dps")
    assert t.loc[60.0, "source_test"] == "angle_deviation" and bool(t.loc[60.0, "reference"])
    assert t.loc[10.0, "E_arcsec"] == pytest.approx(E_10, abs=1e-9)
    assert t.loc[100.0, "E_arcsec"] == pytest.approx(E_100, abs=1e-9)
    assert len(c.tables["points"]) == 9      # 3 rates x 3 common positions


def test_pointing_consistency(res):
    c = res.pointing_consistency
    spread = max(E_EAST, E_NORTH, E_60) - min(E_EAST, E_NORTH, E_60)
    assert c.unit == "%" and c.clause == "7.7"
    assert c.details["spread_arcsec"] == pytest.approx(spread, abs=1e-9)
    assert c.value == pytest.approx(spread / REF_ANGLE * 100, rel=1e-9)
    assert set(c.table["orientation"]) == {"up", "east", "north"}


def test_rate_consistency_own_reference_rows_preferred():
    text = ("test,series,round,rate_dps,time_s,table_deg,gyro_deg\n"
            "angle_deviation,1,1,60,5,360,360.001\n"
            "rate_consistency,1,1,60,5,360,360.0001\n"
            "rate_consistency,1,1,10,5,360,359.9999\n")
    c = rate_consistency(parse_readings(text).data)
    assert c.details["spread_arcsec"] == pytest.approx(0.72, abs=1e-9)
    assert c.details["reference_angle_arcsec"] == pytest.approx(360.0001 * AS, rel=1e-15)
    assert set(c.table["source_test"]) == {"rate_consistency"}


def test_consistency_without_reference_not_measured():
    text = ("test,series,round,rate_dps,orientation,time_s,table_deg,gyro_deg\n"
            "pointing_consistency,1,1,60,east,5,360,360.001\n"
            "pointing_consistency,1,1,60,north,5,360,360.0\n")
    c = pointing_consistency(parse_readings(text).data)
    assert not c.measured and "reference" in c.reason and set(c.unused) == {2, 3}


def test_unused_readings_all_accounted(full, res):
    u = res.unused_readings.set_index("line")["reason"]
    assert sorted(u.index) == [14, 24, 28, 38, 39]
    assert "only one reading" in u[14]
    assert "7.4 condition" in u[24]
    assert "counterpart" in u[28]
    assert "60 deg/s" in u[38]
    assert "equal_division" in u[39]
    used = set().union(*(c.used_lines for c in res.items()))
    assert used | set(u.index) == set(full.data["line"])    # nothing dropped silently


def test_partial_file_uses_metadata_nominal():
    r = compute_characteristics(read_readings(DATA / "partial.csv"))
    e_i = [(108001 / 3600 - 30) * AS, (215998 / 3600 - 60) * AS, (324003 / 3600 - 90) * AS]
    assert r.angle_deviation.value == pytest.approx(extreme(e_i), abs=1e-9)   # +3″
    assert r.scale_factor_for_angles_source == "metadata"
    for c in (r.scale_factor, r.scale_factor_nonlinearity, r.zero_stability,
              r.repeatability, r.rate_consistency, r.pointing_consistency):
        assert not c.measured and c.value is None and c.reason
    assert r.scale_factor.reason == "no scale_factor rows in file"
    assert "2 angle_deviation series" in r.repeatability.reason
    # an explicit nominal K overrides the metadata one
    r2 = compute_characteristics(read_readings(DATA / "partial.csv"),
                                 nominal_scale_factor_counts_per_deg=3600.5)
    assert r2.angle_deviation.value == pytest.approx(
        extreme([(108001 / 3600.5 - 30) * AS, (215998 / 3600.5 - 60) * AS,
                 (324003 / 3600.5 - 90) * AS]), abs=1e-9)
    assert r2.scale_factor_for_angles_source == "argument"


def test_counts_without_any_scale_factor_not_measured():
    r = compute_characteristics(read_readings(DATA / "counts_no_k.csv"))
    assert not r.zero_stability.measured and "scale factor" in r.zero_stability.reason
    assert r.angle_deviation.value == pytest.approx(0.36, abs=1e-9)
    assert r.unused_readings["line"].tolist() == [2, 3]
    assert all("scale factor" in s for s in r.unused_readings["reason"])


def test_scale_factor_at_zero_angle_names_place(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("test,series,round,time_s,table_deg,gyro_counts\n"
                 "scale_factor,1,1,3,60,216000\nscale_factor,1,2,3,0,5\n")
    with pytest.raises(GonioError) as exc:
        compute_characteristics(read_readings(p))
    assert (exc.value.file, exc.value.line, exc.value.column) == (str(p), 3, "table_deg")


def _walk_plain(x):
    if isinstance(x, dict):
        assert all(type(k) is str for k in x)
        for v in x.values():
            _walk_plain(v)
    elif isinstance(x, list):
        for v in x:
            _walk_plain(v)
    else:
        assert x is None or type(x) in (str, int, float, bool), type(x)


def test_to_dict_json(res):
    d = res.to_dict()
    assert list(d) == ["scale_factor", "scale_factor_nonlinearity", "zero_stability",
                       "angle_deviation", "repeatability", "rate_consistency",
                       "pointing_consistency", "unused_readings"]
    units = ["counts/deg", "%", "deg/h", "arcsec", "arcsec", "ppm", "%"]
    for key, unit in zip(list(d)[:7], units):
        item = d[key]
        assert {"value", "unit", "clause", "measured", "table"} <= set(item)
        assert item["unit"] == unit and isinstance(item["table"], list)
    _walk_plain(d)
    text = json.dumps(d, indent=2, allow_nan=False)      # NaN became None
    assert json.loads(text)["scale_factor"]["value"] == pytest.approx(K)
    assert [u["line"] for u in d["unused_readings"]] == [14, 24, 28, 38, 39]
    # deterministic
    assert json.dumps(compute_characteristics(read_readings(DATA / "full.csv")).to_dict(),
                      indent=2) == json.dumps(d, indent=2)


def test_to_dict_not_measured_is_none():
    d = compute_characteristics(read_readings(DATA / "partial.csv")).to_dict()
    assert d["zero_stability"]["value"] is None and d["zero_stability"]["measured"] is False
    assert d["zero_stability"]["reason"] == "no zero_stability rows in file"


def test_summary_table(res):
    text = summary_table(res)
    lines = text.splitlines()
    assert len(lines) == 9                   # header, rule, seven items, all measured
    for line, clause in zip(lines[2:], ["7.1", "7.2", "7.3", "7.4", "7.5", "7.6", "7.7"]):
        assert clause in line
    assert f"{K:.9g}" in lines[2] and "counts/deg" in lines[2]
    assert "ppm" in lines[7]
    partial = summary_table(compute_characteristics(read_readings(DATA / "partial.csv")))
    rows = partial.splitlines()[2:9]
    assert ["not measured" in r for r in rows] == [True] * 3 + [False] + [True] * 3
    assert "no zero_stability rows in file" in partial   # reasons listed under the table
