"""``gonio db`` (init, create-user, import, backup, restore) and ``gonio calibrate --record``
through the command line's entry point; bad input is one line and exit code 2."""

from __future__ import annotations

import shutil
from pathlib import Path

from gonio.cli import main
from gonio.records import services
from gonio.records.db import open_store


def test_db_commands_round_trip(tmp_path, computed_folder, bench_readings, monkeypatch,
                                capsys):
    data, other = tmp_path / "data", tmp_path / "other"
    assert main(["db", "init", "--data", str(data), "--lab-name", "Angle Lab"]) == 0
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    assert main(["db", "create-user", "alice", "--roles", "admin,technician,reviewer",
                 "--data", str(data)]) == 0
    folder = tmp_path / "run"
    shutil.copytree(computed_folder, folder)
    shutil.copy(bench_readings[0], folder / "readings.csv")
    small = Path(__file__).resolve().parents[1] / "data" / "small-protocol.toml"
    assert main(["db", "import", str(folder), "--data", str(data), "--protocol",
                 str(small)]) == 0
    assert main(["db", "backup", str(tmp_path / "b.zip"), "--data", str(data)]) == 0
    assert main(["db", "restore", str(tmp_path / "b.zip"), "--data", str(other)]) == 0
    st = open_store(None, other)
    try:
        assert services.settings(st)["lab_name"] == "Angle Lab"
        assert services.user(st, "alice").roles == "technician reviewer admin"
        assert services.calibration(st, 1).status == "computed"
    finally:
        st.close()
    capsys.readouterr()
    # a second restore into the same records, a short password, an unknown role: one line, 2
    for argv in (["db", "restore", str(tmp_path / "b.zip"), "--data", str(other)],
                 ["db", "create-user", "bob", "--roles", "root", "--data", str(data)],
                 ["db", "import", str(tmp_path), "--data", str(data)]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("gonio: error: ") and err.count("\n") == 1, err
    monkeypatch.setenv("GONIO_PASSWORD", "short")
    assert main(["db", "create-user", "carol", "--data", str(data)]) == 2


def test_calibrate_record_puts_the_run_into_the_records(tmp_path, bench_readings, capsys):
    data = tmp_path / "data"
    out = tmp_path / "cal"
    protocol = str(Path(__file__).resolve().parents[1] / "data" / "small-protocol.toml")
    assert main(["calibrate", str(bench_readings[1]), "--protocol", protocol, "--out", str(out),
                 "--record", "--data", str(data)]) == 0
    assert "recorded as calibration 1" in capsys.readouterr().err
    st = open_store(None, data)
    try:
        cal = services.calibration(st, 1)
        assert cal.status == "computed" and cal.instrument.serial == "RLG-0001"
        assert services.file_bytes(st, cal.readings_sha256) == bench_readings[1].read_bytes()
    finally:
        st.close()


def test_calibrate_record_keeps_the_lab_file_for_the_issue(tmp_path, bench_readings,
                                                           monkeypatch):
    """``gonio calibrate --lab FILE --record``: the laboratory file is stored with the
    calibration, so that the records' details (written as the lab file, the same pipeline)
    decide with the file's limits and rule and carry the recorded result item for item
    (before: the instrument's limits, none). Its standard RT-07 is a registered one."""
    import json

    from gonio.records.compute import calibrate_folder, write_lab_toml
    from gonio.records.results import result_items

    from .test_records_attach import records_of_alice

    repo = Path(__file__).resolve().parents[2]
    lab = repo / "protocols" / "lab-example.toml"
    data, out = records_of_alice(tmp_path, monkeypatch), tmp_path / "cal"
    protocol = str(repo / "tests" / "data" / "small-protocol.toml")
    assert main(["calibrate", str(bench_readings[1]), "--protocol", protocol, "--out", str(out),
                 "--lab", str(lab), "--record", "--data", str(data)]) == 0
    st = open_store(None, data)
    try:
        cal = services.calibration(st, 1)
        assert cal.lab_name == "lab-example.toml"
        assert services.file_bytes(st, cal.lab_sha256) == lab.read_bytes()
        details = services.lab_details(st, 1, final=True)
        # the issue's [record] (seal, people) is the records' to render a sealed result with,
        # refused by a calibration computed now: the details without it
        details = {k: v for k, v in details.items() if k != "record"}
        again = tmp_path / "again"
        calibrate_folder(bench_readings[1], again, spec_key=cal.spec_key, protocol=protocol,
                         lab=write_lab_toml(details, tmp_path / "lab.toml"))
        reviewed = result_items(json.loads(services.file_bytes(st, cal.results_sha256)))
        recomputed = result_items(json.loads((again / "results.json").read_text("utf-8")))
        assert recomputed == reviewed
        decided = {it.key: it.limits for it in reviewed if it.outcome is not None}
        assert decided == {"angle_deviation": (-0.5, 0.5), "repeatability": (None, 0.3)}
    finally:
        st.close()


def test_verify_certificate_closes_the_file_it_reads(tmp_path):
    """``gonio db verify --certificate FILE`` reads the file and closes it (before: left to
    the garbage collector, a ResourceWarning). Its action is called directly: the command
    line's entry point records the warnings of a refused command and drops them."""
    import argparse
    import gc
    import warnings

    import pytest

    from gonio.cli.cmd_db import run_verify
    from gonio.errors import GonioError

    data = tmp_path / "data"
    assert main(["db", "init", "--data", str(data)]) == 0
    cert = tmp_path / "c.pdf"
    cert.write_bytes(b"%PDF-1.4 not one of ours")
    args = argparse.Namespace(database=None, data=str(data), certificate=str(cert))
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(GonioError, match="no certificate issued in these records"):
            run_verify(args)
        gc.collect()
    assert not [w for w in seen if issubclass(w.category, ResourceWarning)], \
        [str(w.message) for w in seen]


def test_a_named_user_proves_it_with_their_password(tmp_path, capsys, monkeypatch):
    """``--user NAME`` on the command line is the login's: the named user's password from
    $GONIO_PASSWORD (no terminal here to ask on), checked against its stored hash; without it,
    or wrong, one line and exit 2 before anything is done; with it the login is an audit
    event naming the operating-system account (before: the name was taken on trust, so anyone
    with a shell acted as "alice")."""
    import getpass
    import json

    from gonio.records.models import AuditEvent

    data = tmp_path / "data"
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    assert main(["db", "create-user", "alice", "--roles", "admin technician", "--data",
                 str(data)]) == 0
    capsys.readouterr()
    attach = ["db", "attach", "1", "--user", "alice", "--temperature", "20", "--humidity",
              "40", "--data", str(data)]
    for password, said in ((None, "give the password of records user 'alice' in "
                                  "$GONIO_PASSWORD"),
                           ("not alice's password", "wrong user name or password")):
        if password is None:
            monkeypatch.delenv("GONIO_PASSWORD")
        else:
            monkeypatch.setenv("GONIO_PASSWORD", password)
        assert main(attach) == 2
        err = capsys.readouterr().err
        assert said in err and err.count("\n") == 1, err
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    assert main(attach) == 2                 # logged in: refused for what it names, not who
    err = capsys.readouterr().err
    assert "password" not in err and err.count("\n") == 1, err
    st = open_store(None, data)
    try:
        with st.session() as s:
            logins = [json.loads(e.after_json) for e in s.query(AuditEvent).filter_by(
                action="command-line login", username="alice")]
    finally:
        st.close()
    assert logins == [{"command": "db attach", "os_user": getpass.getuser()}]
