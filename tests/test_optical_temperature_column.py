"""The optical readings' ``temperature_c`` column (the chamber the draft's Table 2 sets at
(20 ± 1) °C) is what was measured: compared with the laboratory file's environment as the
metadata line is (the specification's ``measured_conditions``), on readings and on a CSV or
Parquet stream. Before, readings that logged 35 °C on every row were certified as "during
calibration 20.1 °C" with no finding."""
from __future__ import annotations

import contextlib
import io

import pytest

from gonio.cli import main
from gonio.resources import protocols_dir
from gonio.specs.ogam_draft.readings import temperature_measured

LAB = protocols_dir() / "lab-example.toml"          # environment 20.1 °C, serial RLG-0001


def _with_column(src, dst, value: str, every: int = 1):
    out, header = [], False
    for n, ln in enumerate(src.read_text(encoding="utf-8").splitlines()):
        if ln.startswith("#"):
            out.append(ln)
        elif not header:
            out.append(ln + ",temperature_c")
            header = True
        else:
            out.append(ln + "," + (value if n % every == 0 else ""))
    dst.write_text("\n".join(out) + "\n", encoding="utf-8")
    return dst


def _run(argv):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(argv)
    return rc, err.getvalue()


@pytest.mark.parametrize("every", [1, 10])
def test_a_logged_temperature_that_contradicts_the_lab_file_is_refused(tmp_path,
                                                                        shared_simulation,
                                                                        every):
    src = shared_simulation("ogam-draft") / "readings.csv"
    bad = _with_column(src, tmp_path / "t35.csv", "35.0", every)
    assert temperature_measured(bad)["temperature_c"][0] == "35"
    rc, err = _run(["calibrate", str(bad), "--lab", str(LAB), "--out", str(tmp_path / "o")])
    assert rc == 2 and "the readings say 35 °C (the temperature_c column" in err, err
    assert "20.1 °C" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()
    # the same column at the room the laboratory states is no contradiction
    good = _with_column(src, tmp_path / "t20.csv", "20.3", every)
    rc, err = _run(["calibrate", str(good), "--lab", str(LAB), "--out", str(tmp_path / "g")])
    assert rc == 0, err


def test_a_parquet_streams_temperature_column_is_read(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    p = tmp_path / "s.parquet"
    pq.write_table(pa.table({"time_s": [0.0, 1.0, 2.0], "temperature_c": [34.8, None, 35.2]}), p)
    assert temperature_measured(p)["temperature_c"][0] == "35"
    pq.write_table(pa.table({"time_s": [0.0]}), p)
    assert temperature_measured(p) == {}
