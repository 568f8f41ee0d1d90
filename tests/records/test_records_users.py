"""User management (deactivate, reset a password, change roles, with the audit trail) on the
server, the command line and the web; technicians do not read the users nor the whole audit
trail; laboratory settings checked by the laboratory file's schema; multi-line addresses."""

from __future__ import annotations

import pytest
from sqlalchemy import select

from gonio.cli import main
from gonio.errors import GonioError
from gonio.records import auth, services
from gonio.records.db import open_store
from gonio.records.models import AuditEvent

from .conftest import PASSWORD, conditions, make_people
from .test_web_security import app, csrf_of, login  # noqa: F401  (the app fixture)


def test_deactivate_reset_and_roles_with_audit(sqlite_store):
    people = make_people(sqlite_store)
    admin = people["admin"]
    with pytest.raises(GonioError, match="admin role"):
        services.update_user(sqlite_store, people["rev"], "tech", active=False)
    with pytest.raises(GonioError, match="deactivate yourself"):
        services.update_user(sqlite_store, admin, "admin", active=False)
    with pytest.raises(GonioError, match="last active admin"):
        services.update_user(sqlite_store, None, "admin", roles="technician")
    services.update_user(sqlite_store, admin, "tech", active=False)
    with pytest.raises(GonioError):
        auth.authenticate(sqlite_store, "tech", PASSWORD)
    services.update_user(sqlite_store, admin, "rev", password="a new long password",
                         roles="reviewer technician")
    assert auth.authenticate(sqlite_store, "rev", "a new long password").roles == \
        "technician reviewer"
    with pytest.raises(GonioError):
        auth.authenticate(sqlite_store, "rev", PASSWORD)
    with sqlite_store.session() as s:
        ev = s.scalars(select(AuditEvent).where(AuditEvent.entity == "user",
                                                AuditEvent.action == "update")).all()
    assert len(ev) == 2 and '"(reset)"' in ev[1].after_json and "argon2" not in ev[1].after_json


def test_set_user_from_the_command_line(tmp_path, monkeypatch, capsys):
    data = str(tmp_path / "data")
    monkeypatch.delenv("GONIO_USER", raising=False)
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    assert main(["db", "create-user", "admin", "--roles", "admin", "--data", data]) == 0
    monkeypatch.setenv("GONIO_NEW_PASSWORD", "alice's own password")
    assert main(["db", "create-user", "alice", "--user", "admin", "--data", data]) == 0
    monkeypatch.setenv("GONIO_NEW_PASSWORD", "another long password")
    assert main(["db", "set-user", "alice", "--deactivate", "--roles", "reviewer",
                 "--reset-password", "--user", "admin", "--data", data]) == 0
    assert "alice (reviewer; deactivated); password reset" in capsys.readouterr().out
    assert main(["db", "set-user", "admin", "--deactivate", "--user", "admin",
                 "--data", data]) == 2
    assert "deactivate yourself" in capsys.readouterr().err
    st = open_store(None, data)
    try:
        services.update_user(st, None, "alice", active=True)
        assert auth.authenticate(st, "alice", "another long password").username == "alice"
        with st.session() as s:
            who = [(e.action, e.username) for e in s.scalars(select(AuditEvent).where(
                AuditEvent.entity == "user").order_by(AuditEvent.id))]
    finally:
        st.close()
    # the first admin set up without a login; alice created and changed by the admin's login
    assert who[0][0] == "create" and who[1:] == [("command-line login", "admin"),
                                                  ("create", "admin"),
                                                  ("command-line login", "admin"),
                                                  ("update", "admin"),
                                                  ("command-line login", "admin"),
                                                  ("update", "(system)")], who


def test_users_cannot_be_managed_without_an_admin_login(tmp_path, monkeypatch, capsys):
    """Once the records have an active administrator, an account on the machine cannot create
    a user, promote one, reset a password or reactivate one without an admin's login."""
    data = str(tmp_path / "data")
    monkeypatch.delenv("GONIO_USER", raising=False)
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    # a new database: its first user, created without a login, is its administrator
    assert main(["db", "create-user", "tech", "--roles", "technician", "--data", data]) == 2
    assert "the first is their administrator" in capsys.readouterr().err
    assert main(["db", "create-user", "boss", "--roles", "admin", "--data", data]) == 0
    monkeypatch.setenv("GONIO_NEW_PASSWORD", "long enough password")
    assert main(["db", "create-user", "tech", "--roles", "technician", "--user", "boss",
                 "--data", data]) == 0
    monkeypatch.delenv("GONIO_NEW_PASSWORD")
    capsys.readouterr()
    attempts = (["db", "create-user", "mallory", "--roles", "admin"],
                ["db", "set-user", "tech", "--roles", "admin technician"],
                ["db", "set-user", "boss", "--reset-password"],
                ["db", "set-user", "tech", "--deactivate"])
    for argv in attempts:
        assert main(argv + ["--data", data]) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Traceback" not in err, err
        assert "active administrator" in err and "--user ADMIN" in err, err
        # a technician's login is not an admin's; a wrong password is no login
        assert main(argv + ["--user", "tech", "--data", data]) == 2, argv
        assert "admin role" in capsys.readouterr().err
        monkeypatch.setenv("GONIO_PASSWORD", "not the password")
        assert main(argv + ["--user", "boss", "--data", data]) == 2, argv
        assert "'boss'" in capsys.readouterr().err
        monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    monkeypatch.setenv("GONIO_USER", "tech")
    assert main(["db", "create-user", "mallory", "--data", data]) == 2
    assert "admin role" in capsys.readouterr().err
    # the laboratory's settings too: its name and accreditation are an admin's
    monkeypatch.delenv("GONIO_USER")
    assert main(["db", "init", "--lab-accreditation", "CNAS L0000", "--data", data]) == 2
    assert "active administrator" in capsys.readouterr().err
    assert main(["db", "init", "--data", data]) == 0          # creating or upgrading: no login
    assert main(["db", "init", "--lab-accreditation", "CNAS L1234", "--user", "boss",
                 "--data", data]) == 0
    st = open_store(None, data)
    try:
        assert services.user(st, "mallory") is None
        assert services.user(st, "tech").roles == "technician" and services.user(
            st, "tech").active
        assert auth.authenticate(st, "boss", "long enough password").username == "boss"
        assert services.settings(st)["lab_accreditation"] == "CNAS L1234"
    finally:
        st.close()


def test_web_user_management_and_what_technicians_read(app, sqlite_store):  # noqa: F811
    tech = login(app, "tech")
    for page in ("/users", "/audit"):
        assert tech.get(page).status_code == 403, page
    assert 'href="/audit"' not in tech.get("/").text
    admin = login(app, "admin")
    assert admin.get("/audit").status_code == 200
    r = admin.post("/users/tech", data={"csrf": csrf_of(admin), "roles": "technician"})
    assert r.status_code == 303                       # no 'active': deactivated
    assert not services.user(sqlite_store, "tech").active
    assert tech.get("/").status_code == 303           # the session ended with it
    r = admin.post("/users/tech", data={"csrf": csrf_of(admin), "roles": ["technician",
                   "reviewer"], "active": "yes", "password": "brand new password"})
    assert r.status_code == 303 and services.user(sqlite_store, "tech").roles == \
        "technician reviewer"
    assert auth.authenticate(sqlite_store, "tech", "brand new password").active
    rev = login(app, "rev")
    r = rev.post("/users/tech", data={"csrf": csrf_of(rev), "roles": "admin",
                                      "active": "yes"})
    assert r.status_code == 400 and "admin role" in r.text
    assert services.user(sqlite_store, "tech").roles == "technician reviewer"


def test_settings_checked_by_the_laboratory_schema(sqlite_store):
    with pytest.raises(GonioError, match="key guard_band_factor: not a number"):
        services.set_settings(sqlite_store, None, guard_band_factor="abc")
    with pytest.raises(GonioError, match="decision_rule.rule"):
        services.set_settings(sqlite_store, None, decision_rule="lenient")
    with pytest.raises(GonioError, match="key lab_name: longer than 200"):
        services.set_settings(sqlite_store, None, lab_name="L" * 4000)
    assert services.settings(sqlite_store)["guard_band_factor"] == "1.0"
    got = services.set_settings(sqlite_store, None, lab_address="1 Road\r\nTown\rCountry",
                                guard_band_factor="1.5")
    assert got["lab_address"] == "1 Road\nTown\nCountry" and got["guard_band_factor"] == "1.5"


def test_two_line_customer_address_reaches_the_laboratory_file(sqlite_store, tmp_path):
    """A customer's two-line address typed with CR LF (a browser's textarea) is kept as lines
    and the laboratory file written for the worker reads back (before: 'control character
    U+000D' on every calibration of that customer)."""
    import datetime as dt

    from gonio.records.compute import write_lab_toml
    from gonio.records.models import Calibration
    from gonio.formats.lab import load_lab

    people = make_people(sqlite_store)
    tech = people["tech"]
    cust = services.add_customer(sqlite_store, tech, "Two Lines Ltd", "1 Road\r\nTown")
    inst = services.register_instrument(sqlite_store, tech, customer_id=cust.id, serial="S",
                                        spec_key="ogam-draft")
    sha, _ = services.store_file(sqlite_store, __import__("io").BytesIO(b"x"))
    cal = services.create_calibration(sqlite_store, tech, instrument_id=inst.id,
                                      readings_sha256=sha, performed_on=dt.date.today(),
                                      **conditions(sqlite_store, tech))
    with sqlite_store.writing() as s:                # stored before the normalisation
        s.get(Calibration, cal.id).instrument.customer.address = "1 Road\r\nOld Town"
        s.commit()
    lab = load_lab(write_lab_toml(services.lab_details(sqlite_store, cal.id, final=False),
                                  tmp_path / "lab.toml"))
    assert lab["customer"]["address"] == "1 Road\nOld Town"


def test_two_admins_deactivating_each_other_at_once_leave_one(store, monkeypatch):
    """Two admins deactivate each other in transactions that overlap: the second waits for the
    first and is refused as the last active admin (before, on PostgreSQL, both committed and
    the records had no active administrator, so anyone could then make one)."""
    import threading

    from gonio.records import queries

    from .conftest import PASSWORD

    a = services.create_user(store, None, "a", PASSWORD, "admin")
    b = services.create_user(store, None, "b", PASSWORD, "admin")
    real = services.audit
    t1_in_audit, t2_done = threading.Event(), threading.Event()

    def slow_audit(s, actor, action, entity, *rest, **kw):
        if action == "update" and entity == "user" and threading.current_thread().name == "t1":
            t1_in_audit.set()
            t2_done.wait(3)             # the first transaction held open while t2 runs
        return real(s, actor, action, entity, *rest, **kw)

    monkeypatch.setattr(services, "audit", slow_audit)
    errs = {}

    def run(name, actor, target):
        try:
            services.update_user(store, actor, target, active=False)
        except GonioError as exc:
            errs[name] = exc.message

    t1 = threading.Thread(target=run, args=("t1", a, "b"), name="t1")
    t1.start()
    assert t1_in_audit.wait(10)
    t2 = threading.Thread(target=run, args=("t2", b, "a"), name="t2")
    t2.start()
    t2.join(1.5)
    t2_done.set()
    t1.join(30)
    t2.join(30)
    monkeypatch.setattr(services, "audit", real)
    assert queries.active_admins(store) == ["a"], (errs, queries.active_admins(store))
    assert "t1" not in errs and "last active admin" in errs.get("t2", ""), errs


def test_a_new_database_is_set_up_whatever_gonio_user_says(tmp_path, monkeypatch, capsys):
    """A machine whose profile sets $GONIO_USER still sets up a new database: with no user
    yet there is no one to log in as, so the name is not asked for."""
    data = str(tmp_path / "data")
    monkeypatch.setenv("GONIO_USER", "alice")
    monkeypatch.setenv("GONIO_PASSWORD", "long enough password")
    assert main(["db", "init", "--lab-name", "Angle Lab", "--data", data]) == 0
    assert main(["db", "create-user", "alice", "--roles", "admin technician",
                 "--data", data]) == 0
    # from now on the name is the login, the password proves it
    monkeypatch.setenv("GONIO_NEW_PASSWORD", "bob's long password")
    assert main(["db", "create-user", "bob", "--data", data]) == 0
    st = open_store(None, data)
    try:
        assert services.settings(st)["lab_name"] == "Angle Lab"
        assert services.user(st, "bob").roles == "technician"
    finally:
        st.close()


def test_records_with_users_and_no_admin_get_none_from_the_command_line(tmp_path,
                                                                         monkeypatch, capsys):
    """Records in use whose users include no active administrator (made before the first user
    had to be one, or restored so): no account on the machine makes itself their
    administrator nor resets a password without a login."""
    data = tmp_path / "data"
    st = open_store(None, data)
    try:
        services.create_user(st, None, "alice", PASSWORD, "technician")
    finally:
        st.close()
    monkeypatch.delenv("GONIO_USER", raising=False)
    monkeypatch.setenv("GONIO_PASSWORD", "mallory's password!")
    for argv in (["db", "create-user", "mallory", "--roles", "admin"],
                 ["db", "set-user", "alice", "--reset-password"],
                 ["db", "init", "--lab-name", "Mallory's Lab"]):
        assert main(argv + ["--data", str(data)]) == 2, argv
        err = capsys.readouterr().err
        assert "users but no active administrator" in err and err.count("\n") == 1, err
    st = open_store(None, data)
    try:
        assert services.user(st, "mallory") is None
        assert auth.authenticate(st, "alice", PASSWORD).username == "alice"
    finally:
        st.close()
