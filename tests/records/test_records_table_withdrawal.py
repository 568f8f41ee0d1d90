"""The register of table calibrations fit for accredited work
(docs/records.md#the-register-of-table-calibrations), on SQLite and on the throwaway PostgreSQL:
due dates bounded by the laboratory's longest interval; no entry valid from the future or
registered late behind a calibration already made; a wrong entry withdrawn — its own frozen row
(migration 0010), asked by one person and approved by another — in force on no day from then
on, the calibrations made with it kept as sealed and listed as affected; the web page, the CSV
export, the calibration page and ``gonio db withdraw-table-calibration``.

Truths from outside the code under test: month ends written out by hand (2024-02-29 + 24
months is 2026-02-28), which entry is in force on a day by the second rule of
test_records_table_register (the newest valid from on or before the day among the entries not
withdrawn, in force when not past its due date) over every day of two years, digests by
hashlib."""

from __future__ import annotations

import csv
import datetime as dt
import hashlib
import io
import json

import pytest
from sqlalchemy import select, text, update
from sqlalchemy.exc import DBAPIError, IntegrityError

from gonio.errors import GonioError
from gonio.records import services
from gonio.records.models import (AuditEvent, Calibration, Certificate, TableCalibration,
                                  TableCalibrationWithdrawal)

from .conftest import PASSWORD
from .test_records_services import store_run_as_computed
from .test_records_table_register import (FILES, SHA, VALID, create, in_force_here, register,
                                          setup_lab)


#: the corrected file registered in a withdrawn TC-2's place: its own bytes (another SHA-256)
#: and a corrected number (a file with the withdrawn numbers, dates and certificate corrects
#: nothing: test_withdrawn_numbers_under_other_bytes_are_refused)
CORRECTED = FILES["TC-2"].replace(b"TC-2\n", b"TC-2 (corrected issue)\n").replace(
    b"120,0.020,", b"120,0.021,")
assert CORRECTED.count(b"0.021") == 1


def reg(store, actor, table_id, key, start, due, name=None, content=None):
    sha, _ = services.store_file(store, io.BytesIO(FILES[key] if content is None else content))
    return services.register_table_calibration(store, actor, standard_id=table_id, sha256=sha,
                                               name=name or f"{key}.csv", valid_from=start,
                                               due_on=due, certificate=key)


def one_line(exc_info) -> str:
    msg = str(exc_info.value)
    assert "\n" not in msg, msg
    return msg


def test_due_date_bounded_and_start_not_in_the_future(store):
    """The due date after valid from and at most the laboratory's longest interval after it
    (default 24 months, calendar months with the month's end kept: 2024-02-29 → 2026-02-28);
    a due date 50 years ahead, one on the start day and a start tomorrow (UTC) are refused in
    one line, nothing registered; the setting takes 1 … 120 whole months and binds from
    then on."""
    people, _, table_id, _ = setup_lab(store)
    tech = people["tech"]
    today = services.records_today(store)
    for start, due, expect in (
            ("2024-02-29", "2074-02-28", "is more than 24 months after valid_from 2024-02-29 "
                                         "(the laboratory's longest table calibration "
                                         "interval, setting table_calibration_max_months: due "
                                         "on 2026-02-28 at the latest)"),
            ("2024-02-29", "2026-03-01", "due on 2026-02-28 at the latest"),
            ("2024-02-29", "2024-02-29", "due_on 2024-02-29 is not after valid_from 2024-02-29"),
            (str(today + dt.timedelta(days=1)), str(today + dt.timedelta(days=300)),
             f"is in the future (today is {today}, the laboratory's date)")):
        with pytest.raises(GonioError) as e:
            reg(store, tech, table_id, "TC-1", start, due)
        assert expect in one_line(e), (start, due, str(e.value))
    assert services.table_calibrations(store) == []
    assert reg(store, tech, table_id, "TC-1", "2024-02-29", "2026-02-28").due_on == \
        dt.date(2026, 2, 28)
    assert reg(store, tech, table_id, "TC-2", str(today), str(today + dt.timedelta(days=30)))
    for bad in ("0", "121", "1.5", "twelve", ""):
        with pytest.raises(GonioError, match="a whole number of months, 1 … 120"):
            services.set_settings(store, people["admin"], table_calibration_max_months=bad)
    services.set_settings(store, people["admin"], table_calibration_max_months="12")
    with pytest.raises(GonioError, match="more than 12 months after valid_from 2025-01-31 .* "
                                         "due on 2026-01-31 at the latest"):
        reg(store, tech, table_id, "TC-3", "2025-01-31", "2026-02-01")
    assert reg(store, tech, table_id, "TC-3", "2025-01-31", "2026-01-31")


def test_due_date_refused_on_the_command_line(store, tmp_path, capsys, monkeypatch):
    """``gonio db register-table-calibration`` with a due date 50 years ahead: exit 2, one
    line, nothing registered."""
    from gonio.cli import main

    monkeypatch.setenv("GONIO_PASSWORD", PASSWORD)
    setup_lab(store)
    where = ["--database", store.url] if not store.url.startswith("sqlite") else \
        ["--data", str(store.blob_root.parent)]
    (tmp_path / "tc.csv").write_bytes(FILES["TC-1"])
    assert main(["db", "register-table-calibration", str(tmp_path / "tc.csv"), "--table",
                 "RT-07", "--valid-from", "2025-01-01", "--due-on", "2075-01-01", "--user",
                 "tech", *where]) == 2
    err = capsys.readouterr().err
    assert "due_on 2075-01-01 is more than 24 months after valid_from 2025-01-01" in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert services.table_calibrations(store) == []


def test_late_registration_refused_and_never_changes_a_sealed_entry(store, computed_folder):
    """A calibration made with TC-1 on 2025-07-01 (result stored, seal signed): TC-2 valid from
    2025-06-01 registered after it would be in force on its day — refused in one line naming
    the calibration; valid from 2025-07-02 it is registered, and the calibration still names
    TC-1, its seal unchanged, and the review signs that seal. A voided calibration and one
    made with these very bytes (an upload) do not block a registration."""
    people, inst_id, table_id, _ = setup_lab(store)
    tech = people["tech"]
    tc1 = register(store, tech, table_id, "TC-1")
    cal = create(store, tech, inst_id, "2025-07-01", [table_id])
    assert cal.table_calibration_id == tc1.id
    store_run_as_computed(store, cal.id, computed_folder)
    signed = services.seal(store, cal.id)
    with pytest.raises(GonioError) as e:
        reg(store, tech, table_id, "TC-2", "2025-06-01", "2026-03-01")
    msg = one_line(e)
    assert (f"calibration {cal.id} of 2025-07-01 was made with table calibration {tc1.id} of "
            "RT-07: an entry valid from 2025-06-01 would be in force on its day") in msg, msg
    assert "valid from 2025-07-02 or later" in msg
    tc2 = reg(store, tech, table_id, "TC-2", "2025-07-02", "2026-03-01")
    assert services.calibration(store, cal.id).table_calibration_id == tc1.id
    assert services.seal(store, cal.id) == signed
    reviewed = services.review(store, people["rev"], cal.id, accept=True, shown_seal=signed)
    assert reviewed.reviewed_seal == signed and reviewed.table_calibration_id == tc1.id
    # a later calibration takes TC-2 from its own date; the first one stays with TC-1
    assert create(store, tech, inst_id, "2025-07-02", [table_id]).table_calibration_id == tc2.id
    # only calibrations made otherwise block: void ones and the same bytes do not
    people2, inst2, table2, _ = setup_lab_more(store)
    up = services.store_file(store, io.BytesIO(FILES["TC-3"]))[0]
    with pytest.raises(GonioError, match="not in the register"):   # no bare upload
        create(store, tech, inst2, "2025-08-01", [table2], table_calibration_sha256=up,
               table_calibration_name="TC-3.csv")
    other = create(store, tech, inst2, "2025-09-01", [table2])
    with store.writing() as s:
        s.get(Calibration, other.id).status = "void"
        s.commit()
    assert reg(store, tech, table2, "TC-3", "2025-08-01", "2026-08-01").id


def setup_lab_more(store):
    """A second table RT-08 and instrument in the same records."""
    tech = services.user(store, "tech")
    cust = services.add_customer(store, tech, "C2")
    inst = services.register_instrument(store, tech, customer_id=cust.id, serial="RLG-2",
                                        spec_key="ogam-draft")
    table = services.add_standard(store, tech, name="rotary table 2", identifier="RT-08",
                                  due_on="2099-01-01")
    return None, inst.id, table.id, None


def test_withdrawal_two_people_frozen_and_in_force_again(store, computed_folder):
    """TC-2 (superseding TC-1 from 2025-06-01) used by a calibration, then withdrawn: asked by
    a reviewer with the reason, approved by another reviewer (the asker and a technician are
    refused); its row is frozen by the database; from then on TC-2 is in force on no day and
    TC-1 is in force where the second rule without TC-2 says, every day of two years; a
    calibration made with TC-2 keeps it, its seal unchanged, and is listed as affected (the
    register, the audit trail); TC-2's bytes are refused (for any table) and a corrected file is registered on its day; a
    request declined leaves the entry in force."""
    people, inst_id, table_id, _ = setup_lab(store)
    tech, rev, rev2 = people["tech"], people["rev"], people["rev2"]
    ids = {k: register(store, tech, table_id, k).id for k in VALID}
    made = []
    for _ in range(3):       # computed; reviewed; approved (issuing) — all with TC-2
        made.append(create(store, tech, inst_id, "2025-07-01", [table_id]))
        assert made[-1].table_calibration_id == ids["TC-2"]
        store_run_as_computed(store, made[-1].id, computed_folder)
    used, in_review, issuing = made
    signed = services.seal(store, used.id)
    for cal in (in_review, issuing):
        services.review(store, rev, cal.id, accept=True)
    assert services.approve(store, rev2, issuing.id).status == "issuing"
    with pytest.raises(GonioError, match="no withdrawal of table calibration 2 is asked for"):
        services.approve_withdrawal(store, rev2, ids["TC-2"])
    only_admin = services.create_user(store, people["admin"], "boss", PASSWORD, "admin")
    with pytest.raises(GonioError, match="technician or reviewer role"):
        services.ask_withdrawal(store, only_admin, ids["TC-2"], "r")
    services.ask_withdrawal(store, rev, ids["TC-2"], "due date mistyped\n(2026-03-01, not "
                                                     "2026-01-03)")
    with pytest.raises(GonioError, match="is asked for already"):
        services.ask_withdrawal(store, tech, ids["TC-2"], "again")
    with pytest.raises(GonioError, match="the person who asked for the withdrawal may not "
                                         "approve it"):
        services.approve_withdrawal(store, rev, ids["TC-2"])
    with pytest.raises(GonioError, match="reviewer role"):
        services.approve_withdrawal(store, tech, ids["TC-2"])
    assert not services.table_calibration_state(
        next(r["entry"] for r in services.table_calibrations(store)
             if r["entry"].id == ids["TC-2"]), [], dt.date(2025, 7, 1))   # still in force
    w = services.approve_withdrawal(store, rev2, ids["TC-2"])
    assert (w.asked_by_id, w.withdrawn_by_id, w.reason) == \
        (rev.id, rev2.id, "due date mistyped\n(2026-03-01, not 2026-01-03)")
    with pytest.raises(GonioError, match="was withdrawn on .* already"):
        services.ask_withdrawal(store, tech, ids["TC-2"], "twice")
    for stmt in (update(TableCalibrationWithdrawal).values(reason="nothing"),
                 TableCalibrationWithdrawal.__table__.delete()):
        with store.writing() as s:
            with pytest.raises((DBAPIError, IntegrityError), match="never changed or removed"):
                s.execute(stmt)
            s.rollback()
    # in force: the second rule over the entries not withdrawn, every day of two years
    rows = services.table_calibrations(store)
    with store.session() as s:
        withdrawn = services.withdrawals(s)
    entries = [r["entry"] for r in rows]
    day = dt.date(2024, 12, 1)
    while day < dt.date(2026, 12, 1):
        got = [e.certificate for e in entries
               if not services.table_calibration_state(e, entries, day, withdrawn)]
        want = in_force_here([("TC-1", *VALID["TC-1"])], day)
        assert got == ([want] if want else []), day
        day += dt.timedelta(days=1)
    by_cert = {r["entry"].certificate: r for r in rows}
    assert by_cert["TC-2"]["state"].startswith("withdrawn on ")
    all_three = [c.id for c in made]
    assert by_cert["TC-2"]["affected"] == all_three and by_cert["TC-1"]["affected"] == []
    # the calibrations made with it keep it, sealed as signed, nothing chosen again — and
    # none is reviewed, approved or issued with a withdrawn correction: each refusal one
    # line naming the entry, the state unchanged
    assert services.calibration(store, used.id).table_calibration_id == ids["TC-2"]
    assert services.seal(store, used.id) == signed
    refused = (f"it was made with table calibration {ids['TC-2']} (TC-2), withdrawn on ")
    for act, cal, who, was in (
            (lambda c, who: services.review(store, who, c, accept=True, shown_seal=signed),
             used, rev, "computed"),
            (lambda c, who: services.approve(store, who, c), in_review, rev2, "reviewed"),
            (lambda c, who: services.sealed_result(store, c), issuing, None, "issuing"),
            (lambda c, who: services.store_issue(store, c, computed_folder), issuing, None,
             "issuing")):
        with pytest.raises(GonioError) as e:
            act(cal.id, who)
        msg = one_line(e)
        assert refused in msg and "with a table calibration in force" in msg, msg
        now = services.calibration(store, cal.id)
        assert (now.status, now.table_calibration_id) == (was, ids["TC-2"])
    with store.session() as s:
        assert s.scalars(select(Certificate)).all() == []
        ev = s.scalar(select(AuditEvent).where(AuditEvent.action == "withdraw"))
        assert (ev.username, ev.entity, ev.entity_id) == ("rev2", "table-calibration",
                                                          str(ids["TC-2"]))
        assert json.loads(ev.after_json)["affected"] == all_three
        flags = s.scalars(select(AuditEvent).where(
            AuditEvent.action == "table-calibration-withdrawn")).all()
        assert [(f.entity, f.entity_id) for f in flags] == \
            [("calibration", str(i)) for i in all_three]
    # from then on: chosen or uploaded, TC-2 is refused; without a choice TC-1 is taken
    for kw in ({"table_calibration_id": ids["TC-2"]},
               {"table_calibration_sha256": SHA["TC-2"]}):
        with pytest.raises(GonioError, match=r"table calibration 2 \(TC-2\) of RT-07 cannot "
                                             r"be used on 2025-07-01: withdrawn on "):
            create(store, tech, inst_id, "2025-07-01", [table_id], **kw)
    # the withdrawn entry's bytes are refused, whoever registers them, for this table or
    # another (one person would undo a withdrawal two people made), naming the entry
    people2, _, table2, _ = setup_lab_more(store)
    for table in (table_id, table2):
        with pytest.raises(GonioError) as e:
            reg(store, tech, table, "TC-2", "2025-06-01", "2026-03-01")
        msg = one_line(e)
        assert (f"is table calibration {ids['TC-2']} (TC-2), withdrawn on " in msg
                and "a withdrawn entry's bytes are not registered again" in msg), msg
    assert len(services.table_calibrations(store)) == 2
    # the right one registered in its place: a new file, same day, the due date corrected
    # (the calibration made with TC-2 is affected, so it does not block)
    again = reg(store, tech, table_id, "TC-2", "2025-06-01", "2026-03-01", content=CORRECTED)
    assert again.id not in (ids["TC-1"], ids["TC-2"])
    assert again.sha256 == hashlib.sha256(CORRECTED).hexdigest() != SHA["TC-2"]
    cal = create(store, tech, inst_id, "2025-07-01", [table_id],
                 table_calibration_sha256=again.sha256)
    assert cal.table_calibration_id == again.id
    # declined: the entry stays in force
    services.ask_withdrawal(store, tech, ids["TC-1"], "checking")
    with pytest.raises(GonioError, match="reviewer role \\(or the person who asked\\)"):
        services.decline_withdrawal(store, services.create_user(
            store, people["admin"], "tech2", PASSWORD, "technician"), ids["TC-1"])
    services.decline_withdrawal(store, rev, ids["TC-1"], "it was right")
    assert next(r for r in services.table_calibrations(store, dt.date(2025, 3, 1))
                if r["entry"].id == ids["TC-1"])["state"] == ""
    with store.session() as s:
        assert services.pending_withdrawal(s, ids["TC-1"]) is None


def test_withdrawal_on_the_web_and_in_the_export(store, tmp_path, computed_folder):
    """The register's page: a technician asks (the reason escaped), the asker sees no approve
    button and is refused on the server, another reviewer approves; the page, the CSV
    export and the calibration page show the entry withdrawn, who asked and approved, and
    the affected calibration."""
    from gonio.web.app import create_app

    from .test_web_lab_file import alert
    from .test_web_security import csrf_of, login

    people, inst_id, table_id, _ = setup_lab(store)
    ids = {k: register(store, people["tech"], table_id, k).id for k in VALID}
    used = create(store, people["tech"], inst_id, "2025-07-01", [table_id])
    store_run_as_computed(store, used.id, computed_folder)
    app = create_app(store)
    tech, rev, rev2 = (login(app, n) for n in ("tech", "rev", "rev2"))
    reason = "<script>alert(1)</script> wrong file"

    def post(c, **data):
        return c.post(f"/table-calibrations/{ids['TC-2']}/withdraw",
                      data={"csrf": csrf_of(c), **data})

    assert post(tech, decision="ask", reason="").status_code == 400
    assert post(tech, decision="ask", reason=reason).status_code == 303
    page = tech.get("/table-calibrations").text
    assert "<script>alert(1)" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert 'value="approve"' not in page.split('id="entry-2"')[1].split("</tr>")[0]
    assert 'value="approve"' in rev.get("/table-calibrations").text.split(
        'id="entry-2"')[1].split("</tr>")[0]
    r = post(tech, decision="approve")
    assert r.status_code == 400 and "reviewer role" in alert(r.text)
    assert post(rev, decision="approve").status_code == 303
    page = rev2.get("/table-calibrations").text
    row = page.split('id="entry-2"')[1].split("</tr>")[0]
    assert "withdrawn on " in row and "asked by tech" in row and "approved by rev" in row
    assert f'href="/calibrations/{used.id}"' in row
    rows = list(csv.DictReader(io.StringIO(tech.get("/export/table_calibrations.csv").text)))
    two = next(r for r in rows if r["id"] == str(ids["TC-2"]))
    assert two["state_today"].startswith("withdrawn on ") and two["withdrawn_at"].endswith("Z")
    assert (two["withdrawn_by"], two["withdrawal_asked_by"], two["withdrawal_reason"],
            two["affected"]) == ("rev", "tech", reason, str(used.id))
    one = next(r for r in rows if r["id"] == str(ids["TC-1"]))
    assert (one["withdrawn_at"], one["affected"]) == ("", "")
    cal_page = tech.get(f"/calibrations/{used.id}").text
    assert 'id="table-calibration-withdrawn"' in cal_page and "<script>alert(1)" not in cal_page
    other = create(store, people["tech"], inst_id, "2025-07-01", [table_id])
    assert 'id="table-calibration-withdrawn"' not in tech.get(f"/calibrations/{other.id}").text


def test_withdrawal_on_the_command_line(store, tmp_path, capsys, monkeypatch):
    """``gonio db withdraw-table-calibration N --reason R`` asks, ``--approve`` by the asker is
    refused (exit 2, one line), by another reviewer withdraws; ``gonio db table-calibrations``
    then says withdrawn, by whom and the affected calibrations; ``gonio db
    register-table-calibration`` of the withdrawn entry's bytes is refused (exit 2), a new
    file is registered."""
    from gonio.cli import main

    monkeypatch.setenv("GONIO_PASSWORD", PASSWORD)
    people, inst_id, table_id, _ = setup_lab(store)
    tc = register(store, people["tech"], table_id, "TC-1")
    used = create(store, people["tech"], inst_id, "2025-03-01", [table_id])
    where = ["--database", store.url] if not store.url.startswith("sqlite") else \
        ["--data", str(store.blob_root.parent)]
    base = ["db", "withdraw-table-calibration", str(tc.id), *where]
    assert main(base + ["--reason", "wrong table", "--user", "rev"]) == 0
    capsys.readouterr()
    assert main(base + ["--approve", "--user", "rev"]) == 2
    err = capsys.readouterr().err
    assert "may not approve it" in err and err.count("\n") == 1
    assert main(base + ["--approve", "--user", "rev2"]) == 0
    capsys.readouterr()
    assert main(["db", "table-calibrations", *where]) == 0
    line = capsys.readouterr().out.strip().split("\t")
    assert line[7].startswith("withdrawn on ")
    assert line[10] == (f"withdrawn by rev2 (asked by rev): wrong table; affected: "
                        f"calibration {used.id}")
    # the technician alone registers the same bytes again, same certificate and dates:
    # refused (exit 2, one line naming the withdrawn entry), nothing registered
    (tmp_path / "tc.csv").write_bytes(FILES["TC-1"])
    again = ["db", "register-table-calibration", str(tmp_path / "tc.csv"), "--table", "RT-07",
             "--valid-from", VALID["TC-1"][0], "--due-on", VALID["TC-1"][1], "--certificate",
             "TC-1", "--user", "tech", *where]
    assert main(again) == 2
    err = capsys.readouterr().err
    assert (f"is table calibration {tc.id} (TC-1), withdrawn on " in err
            and err.count("\n") == 1 and "Traceback" not in err), err
    assert len(services.table_calibrations(store)) == 1
    (tmp_path / "tc.csv").write_bytes(CORRECTED)      # a new file is registered
    assert main(again) == 0
    assert len(services.table_calibrations(store)) == 2


def test_migration_0010_over_0009(tmp_path, pg_server):
    """Records at 0009 with a register entry a calibration used, upgraded to 0010: the rows
    kept, the register still frozen, its reference from calibrations still enforced, a
    withdrawn entry's day registrable again with a corrected file; back down to 0009 the database's rules
    return, and a register holding such a pair is refused by the down-migration in words —
    on SQLite and PostgreSQL."""
    from gonio.records.db import open_store

    from .conftest import both_back_ends, records_at
    from .test_result_statement import _downgrade

    for url, data in both_back_ends(tmp_path, pg_server):
        st = records_at(url, data, "0009")
        # today's services read and write a later column of a table 0009 and 0010 leave
        # alone (0011's standards.out_of_service): added by hand, as 0011 adds it, so that
        # the set-up can run through them at 0009
        with st.engine.begin() as c:
            c.execute(text("ALTER TABLE standards ADD COLUMN out_of_service TEXT NOT NULL "
                           "DEFAULT ''"))
        people, inst_id, table_id, _ = setup_lab(st)
        shas = {k: services.store_file(st, io.BytesIO(FILES[k]))[0] for k in VALID}
        with st.engine.begin() as c:        # the 0009 services' rows, written as 0009 has them
            for key, (start, due) in VALID.items():
                sha = shas[key]
                c.execute(text("INSERT INTO table_calibrations (standard_id, sha256, name, "
                               "certificate, valid_from, due_on, registered_by_id, "
                               "registered_at) VALUES (:t, :s, :n, :n, :a, :b, NULL, "
                               "'2025-01-01 00:00:00')"),
                          {"t": table_id, "s": sha, "n": key, "a": start, "b": due})
            c.execute(text("ALTER TABLE standards DROP COLUMN out_of_service"))   # 0011 adds it
        st.close()
        st = open_store(url, data)
        try:
            got = [(r["entry"].certificate, str(r["entry"].valid_from))
                   for r in services.table_calibrations(st)]
            assert sorted(got) == [("TC-1", "2025-01-01"), ("TC-2", "2025-06-01")]
            cal = create(st, people["tech"], inst_id, "2025-07-01", [table_id])
            assert cal.table_calibration_id == 2
            with st.writing() as s:
                with pytest.raises((DBAPIError, IntegrityError), match="never changed"):
                    s.execute(update(TableCalibration).values(due_on=dt.date(2099, 1, 1)))
                s.rollback()
            with st.writing() as s:
                with pytest.raises(IntegrityError):
                    s.execute(update(Calibration).where(Calibration.id == cal.id)
                              .values(table_calibration_id=99))
                s.rollback()
            _downgrade(st.engine, "0009")     # no pair yet: the rules come back
            with st.engine.connect() as c:
                with pytest.raises(IntegrityError):
                    c.execute(text(
                        "INSERT INTO table_calibrations (standard_id, sha256, name, "
                        "certificate, valid_from, due_on, registered_at) VALUES (:t, :s, "
                        "'x', 'x', '2025-01-01', '2025-02-01', '2025-01-01 00:00:00')"),
                        {"t": table_id, "s": SHA["TC-1"]})
                c.rollback()
        finally:
            st.close()
        st = open_store(url, data)          # up again, and a withdrawn entry registered anew
        try:
            assert services.calibration(st, cal.id).table_calibration_id == 2
            services.ask_withdrawal(st, people["rev"], 2, "wrong")
            services.approve_withdrawal(st, people["rev2"], 2)
            reg(st, people["tech"], table_id, "TC-2", "2025-06-01", "2026-03-01",
                content=CORRECTED)
            with pytest.raises(RuntimeError, match="cannot downgrade below 0010: the register "
                                                   "holds 1 pair"):
                _downgrade(st.engine, "0009")
            assert len(services.table_calibrations(st)) == 3
        finally:
            st.close()


def test_backup_restore_keeps_the_withdrawal(store, tmp_path):
    """A backup restored into empty records holds the withdrawal row (who, why, when) and
    the entry's state: withdrawn, in force on no day; the affected calibration listed."""
    from gonio.records.backup import backup, restore
    from gonio.records.db import open_store

    people, inst_id, table_id, _ = setup_lab(store)
    ids = {k: register(store, people["tech"], table_id, k).id for k in VALID}
    used = create(store, people["tech"], inst_id, "2025-07-01", [table_id])
    services.ask_withdrawal(store, people["tech"], ids["TC-2"], "wrong file")
    w = services.approve_withdrawal(store, people["rev"], ids["TC-2"])
    backup(store, tmp_path / "b.zip")
    target = open_store(None, tmp_path / "target")
    try:
        restore(target, tmp_path / "b.zip")
        with target.session() as s:
            got = services.withdrawals(s)[ids["TC-2"]]
            assert (got.reason, got.asked_by.username, got.withdrawn_by.username,
                    got.withdrawn_at) == ("wrong file", "tech", "rev", w.withdrawn_at)
        rows = {r["entry"].id: r for r in services.table_calibrations(target,
                                                                      dt.date(2025, 7, 1))}
        assert rows[ids["TC-2"]]["state"].startswith("withdrawn on ")
        assert rows[ids["TC-2"]]["affected"] == [used.id] and rows[ids["TC-1"]]["state"] == ""
    finally:
        target.close()


def test_withdrawn_numbers_under_other_bytes_are_refused(store):
    """One person cannot undo a two-person withdrawal by registering the withdrawn file again
    with a byte added, CRLF line endings, a comment changed or a number written with another
    zero: the numbers as read, the table, the dates and the certificate are those of the
    withdrawn entry, so it is refused in one line naming it; the same numbers under a
    corrected due date are a correction and are registered."""
    people, _, table_id, _ = setup_lab(store)
    tech, rev, rev2 = people["tech"], people["rev"], people["rev2"]
    tc = register(store, tech, table_id, "TC-1")
    services.ask_withdrawal(store, rev, tc.id, "wrong file")
    services.approve_withdrawal(store, rev2, tc.id)
    raw = FILES["TC-1"]
    for variant in (raw + b"\n", raw.replace(b"\n", b"\r\n"),
                    raw.replace(b"# table certificate TC-1", b"# table certificate TC-1 again"),
                    raw.replace(b"0,0.0,0.02", b"0,0.00,0.020"),
                    # the same rows in another order; a zero written "-0.0"
                    _rows_swapped(raw), raw.replace(b"0,0.0,0.02", b"0,-0.0,0.02")):
        assert variant != raw
        with pytest.raises(GonioError) as e:
            reg(store, tech, table_id, "TC-1", *VALID["TC-1"], content=variant)
        msg = one_line(e)
        assert (f"is table calibration {tc.id} (TC-1), withdrawn on " in msg
                and "numbers (as read), table, dates and certificate" in msg), msg
    # the same numbers under the same certificate written in lower case
    with pytest.raises(GonioError) as e:
        reg(store, tech, table_id, "tc-1", *VALID["TC-1"], content=raw + b"\n")
    assert "withdrawn on " in one_line(e)
    assert len(services.table_calibrations(store)) == 1
    # the same numbers, the due date corrected: registered (a correction of the entry)
    again = reg(store, tech, table_id, "TC-1", VALID["TC-1"][0], "2025-12-31",
                content=raw + b"\n")
    assert again.id != tc.id and len(services.table_calibrations(store)) == 2


def _rows_swapped(raw: bytes) -> bytes:
    """``raw`` with its data rows (after the column header) in reverse order."""
    lines = raw.splitlines(keepends=True)
    head = next(i for i, ln in enumerate(lines) if ln.startswith(b"table_deg"))
    rows = lines[head + 1:]
    assert len(rows) >= 2
    return b"".join(lines[:head + 1] + rows[::-1])
