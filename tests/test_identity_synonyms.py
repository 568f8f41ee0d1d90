"""An identity or condition written under another name (``# serial_number:``, ``# S/N:``,
``# maker:``, ``# temperature:``, ``# RH:``) is refused in one line naming the key gonio
compares, for every readings format: before, ``# serial_number: RLG-0999`` was kept in
results.json and compared with nothing, and the certificate stated the laboratory file's
RLG-0001 alone."""
from __future__ import annotations

import contextlib
import io

import pytest

from gonio.cli import main


@pytest.mark.parametrize("spec", ["ogam-draft", "jjf1535-2015", "iec62047-20",
                                  "triad-alignment"])
@pytest.mark.parametrize("line, want", [("# serial_number: X-999", "serial"),
                                        ("# S/N: X-999", "serial"),
                                        ("# Model-No: M-9", "model"),
                                        ("# maker: ACME", "manufacturer"),
                                        ("# temperature: 35", "temperature_c"),
                                        ("# RH: 80", "humidity_pct")])
def test_another_name_for_an_identity_key_is_refused(tmp_path, shared_simulation, spec, line,
                                                     want):
    src = shared_simulation(spec) / "readings.csv"
    text = src.read_text(encoding="utf-8")
    bad = tmp_path / "readings.csv"
    bad.write_text(line + "\n" + text, encoding="utf-8")
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(["calibrate", str(bad), "--out", str(tmp_path / "o")])
    key = line[2:].partition(":")[0]
    msg = err.getvalue()
    assert rc == 2 and f"key {key}: another name for '{want}'" in msg, msg
    assert len(msg.strip().splitlines()) == 1 and "Traceback" not in msg
    assert not (tmp_path / "o").exists()
