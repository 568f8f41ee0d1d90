"""A table-calibration file's numbers screened against the table's MPE as the readings state
it (``table_mpe_arcsec``; gonio/specs/ogam_draft/table_calibration.py ``screen_against_mpe``,
docs/formats.md "Table calibration"): an error beyond MPE + 3u, a u above the MPE or below
MPE/100 is refused by ``gonio calibrate`` in one line naming file, line and column (exit 2,
nothing written); the rule's edges are checked against the rule's arithmetic written here, and
the dof refusal states the t's real variance ν/(ν − 2)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.formats.toml import read_toml
from gonio.resources import resolve
from gonio.specs.ogam_draft.bench import load_bench, run_session
from gonio.specs.ogam_draft.protocol import parse_protocol
from gonio.specs.ogam_draft.readings import write_readings
from gonio.specs.ogam_draft.study import table_positions_deg
from gonio.specs.ogam_draft.table_calibration import (draw_dof_refusal, read_table_calibration,
                                                      screen_against_mpe)


def write_tc(path, rows):
    path.write_text("# table certificate\ntable_deg,error_arcsec,u_arcsec\n" + "".join(
        f"{a:g},{e!r},{u!r}\n" for a, e, u in rows), encoding="utf-8")
    return path


@pytest.mark.parametrize("e, u, column", [
    (0.1 + 3 * 0.02 + 1e-6, 0.02, "error_arcsec"),      # just beyond MPE + 3u
    (-(0.1 + 3 * 0.02 + 1e-6), 0.02, "error_arcsec"),   # either sign
    (1e6, 0.02, "error_arcsec"),
    (0.0, 0.1 + 1e-9, "u_arcsec"),                      # u above the MPE
    (0.0, 0.001 - 1e-9, "u_arcsec"),                    # below MPE/100
    (0.0, 1e-300, "u_arcsec"),
])
def test_implausible_row_refused_naming_line_and_column(tmp_path, e, u, column):
    f = write_tc(tmp_path / "tc.csv", [(0, 0.01, 0.02), (60, 0.0, 0.02), (120, e, u)])
    with pytest.raises(GonioError) as exc:
        screen_against_mpe(read_table_calibration(f), 0.1)
    msg = str(exc.value)
    assert msg.startswith(f"tc.csv:5: column {column}:") and "\n" not in msg, msg


@pytest.mark.parametrize("e, u", [
    (0.1 + 3 * 0.02 - 1e-6, 0.02), (-0.1, 0.1), (0.0, 0.001), (0.05, 0.0011)])
def test_plausible_rows_pass(tmp_path, e, u):
    f = write_tc(tmp_path / "tc.csv", [(0, 0.01, 0.02), (120, e, u)])
    assert screen_against_mpe(read_table_calibration(f), 0.1) is None


def test_the_mpe_scales_the_rule(tmp_path):
    """The readings' MPE, not a constant: 0.3″ at 120° is refused at MPE 0.1″ and passes at
    0.5″ (0.3 < 0.5 + 3·0.02); u 0.004″ passes at 0.1″ and is refused at 0.5″ (< 0.005)."""
    f = write_tc(tmp_path / "tc.csv", [(0, 0.0, 0.02), (120, 0.3, 0.02)])
    with pytest.raises(GonioError, match="column error_arcsec"):
        screen_against_mpe(read_table_calibration(f), 0.1)
    screen_against_mpe(read_table_calibration(f), 0.5)
    g = write_tc(tmp_path / "tg.csv", [(0, 0.0, 0.004)])
    screen_against_mpe(read_table_calibration(g), 0.1)
    with pytest.raises(GonioError, match="column u_arcsec"):
        screen_against_mpe(read_table_calibration(g), 0.5)


@pytest.fixture(scope="module")
def readings(tmp_path_factory):
    d = tmp_path_factory.mktemp("tcscreen")
    p = parse_protocol(read_toml(resolve("ogam-draft", "protocol")),
                       resolve("ogam-draft", "protocol"))
    res = run_session(p, replace(load_bench("rlg"), sample_rate_hz=5.0), seed=4)
    rd = d / "readings.csv"
    write_readings(res.readings, rd, dict(res.metadata))
    return rd, table_positions_deg(p)


@pytest.mark.parametrize("bad, column", [((1e6, 0.02), "error_arcsec"),
                                          ((0.01, 1e-300), "u_arcsec")])
def test_calibrate_refuses_in_one_line(readings, tmp_path, capsys, bad, column):
    """The reviewer's files: an error of 1e6″ at 120° (was exit 0, "K = 54000 ± 58000") and
    u = 1e-300″ (was a halved U(K)) are refused before any work, exit 2, nothing written."""
    rd, x = readings
    rows = [(a, bad[0], bad[1]) if np.isclose(a, 120.0) else (a, 0.01, 0.02) for a in x]
    f = write_tc(tmp_path / "tc.csv", rows)
    line = 3 + [i for i, a in enumerate(x) if np.isclose(a, 120.0)][0]
    out = tmp_path / "out"
    rc = main(["calibrate", str(rd), "--table-calibration", str(f), "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1, err
    assert f"tc.csv:{line}: column {column}" in err, err
    assert not out.exists()


def test_dof_message_states_the_real_variance():
    """A t with ν = 2.5 has variance ν/(ν − 2) = 5 (in u²): the refusal says so, and says
    'no variance' only for ν ≤ 2."""
    nu = 2.5
    msg = draw_dof_refusal(nu)
    assert f"variance {nu / (nu - 2):.3g}·u²" in msg and "no variance" not in msg, msg
    assert "dof must be >= 3" in msg
    assert "has no variance" in draw_dof_refusal(2.0)
    assert draw_dof_refusal(3.0) is None
