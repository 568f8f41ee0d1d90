"""``gonio calibrate ... --record``: a calibration the records refuse leaves nothing that looks
issued. The run's output set is recorded from its staging folder before it is moved into
--out (docs/records.md, *A calibration the records refuse leaves no certificate*), and what
can be refused without the work is refused before it; either way exit 2, one line, no
certificate, DCC or results.json in --out (a folder that was there keeps what it held),
nothing recorded.

Each refusal kind reached from the command line, on SQLite and PostgreSQL: readings another
calibration holds (before the work), a laboratory file naming a standard the records do not
register (after the work, when the set is recorded), an identity the laboratory file
contradicts, standards to attach without a records user. The table calibration the register
does not hold is the same path, tested in test_records_table_calibration_import.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from gonio.cli import main
from gonio.records import services

from .conftest import SMALL_PROTOCOL, make_people
from .test_web_lab_file import n_calibrations

REPO = Path(__file__).resolve().parents[2]
LAB = (REPO / "protocols" / "lab-example.toml").read_text(encoding="utf-8")
assert 'identifier = "RT-07"' in LAB and 'serial = "RLG-0001"' in LAB


def _where(store) -> list[str]:
    """The command line's options naming the records ``store`` is: its data folder (the
    stored files; the SQLite database), and on PostgreSQL its URL too."""
    url = store.engine.url
    data = ["--data", str(store.data)]
    if url.get_backend_name() == "sqlite":
        return data
    return ["--database", url.render_as_string(hide_password=False), *data]


def _record(store, readings, out: Path, *extra: str) -> int:
    return main(["calibrate", str(readings), "--protocol", str(SMALL_PROTOCOL),
                 "--out", str(out), "--record", *_where(store), *extra])


def _refused(capsys, out: Path, *, kept: dict | None = None) -> str:
    """The one line of a refusal; ``out`` holds no file gonio would write (none at all,
    or exactly the files ``kept`` {name: bytes} it held before)."""
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    held = {p.relative_to(out).as_posix(): p.read_bytes() for p in out.rglob("*")
            if p.is_file()} if out.exists() else {}
    assert held == (kept or {}), sorted(held)
    return err


def test_readings_another_calibration_holds_refused_before_the_work(store, bench_readings,
                                                                     tmp_path, capsys):
    """Readings of a calibration that stands: refused naming it, before anything is computed;
    a folder the user had there keeps its own file and gains nothing."""
    tech = make_people(store)["tech"]
    cust = services.add_customer(store, tech, "C")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="RLG-0001",
                                        spec_key="ogam-draft")
    std = services.add_standard(store, tech, name="rotary table", identifier="RT-07",
                                due_on="2099-01-01")
    with open(bench_readings[0], "rb") as fh:
        sha, _ = services.store_file(store, fh)
    services.create_calibration(store, tech, instrument_id=inst.id, readings_sha256=sha,
                                standard_ids=[std.id], temperature_c=20.0, humidity_pct=45.0)
    out = tmp_path / "cal"
    out.mkdir()
    (out / "notes.txt").write_bytes(b"the operator's notes\n")
    capsys.readouterr()
    assert _record(store, bench_readings[0], out) == 2
    err = _refused(capsys, out, kept={"notes.txt": b"the operator's notes\n"})
    assert "already those of calibration 1" in err, err
    assert n_calibrations(store) == 1


def test_refused_when_recorded_writes_nothing(store, bench_readings, tmp_path, capsys):
    """The laboratory file names the standard RT-07, which these records do not register:
    the calibration is computed, the records refuse its set (naming the standard), and --out
    is never created: no certificate, DCC or results.json; nothing recorded."""
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB, encoding="utf-8")
    out = tmp_path / "cal"
    capsys.readouterr()
    assert _record(store, bench_readings[1], out, "--lab", str(lab), "--dcc") == 2
    err = _refused(capsys, out)
    assert "'RT-07' is not a registered standard" in err, err
    assert n_calibrations(store) == 0


def test_refused_before_the_work(store, bench_readings, tmp_path, capsys):
    """A laboratory file whose serial contradicts the readings, and standards to attach
    with no records user: each one line before the work, no --out."""
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB.replace('serial = "RLG-0001"', 'serial = "RLG-0002"'), encoding="utf-8")
    out = tmp_path / "cal"
    for extra, expect in ((["--lab", str(lab)], "serial: the readings say 'RLG-0001'"),
                          (["--standard", "RT-07"], "give the records user attaching")):
        capsys.readouterr()
        assert _record(store, bench_readings[1], out, *extra) == 2
        err = _refused(capsys, out)
        assert expect in err, err
    assert n_calibrations(store) == 0


@pytest.fixture(autouse=True)
def _no_user(monkeypatch):
    monkeypatch.delenv("GONIO_USER", raising=False)
