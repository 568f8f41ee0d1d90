"""What the readings measured of their conditions, in the records as in ``gonio calibrate``:
a rate file's logged room temperature (its ``temperature_c`` column in the tests run in the
room) is compared with the temperature entered at submission and attached later (the web
form, ``gonio db import --temperature``, ``calibrate --record --temperature``, ``gonio db
attach``), also where its ``# room_temperature_c`` line was deleted; IEC 62047-20's
``room_temperature_c`` (its chamber's base temperature) is not the room's."""

from __future__ import annotations

import pytest

from gonio.errors import GonioError
from gonio.records import services, submission

from .conftest import make_people


def rate_readings(room_c: str, *, head: str = "# spec: jjf1535-2015\n") -> bytes:
    """A small JJF 1535 readings file whose room tests logged ``room_c`` °C (the chamber's
    tests 60 °C), its serial MEMS-0610-001 and no ``# room_temperature_c`` line."""
    rows = ["test,run,step,role,time_s,rate_dps,output,temperature_c"]
    rows += [f"sf,1,{i},ref,{i}.0,10.0,2560.{i},{room_c}" for i in range(1, 5)]
    rows += [f"sf_temperature,1,{i},ref,{10 + i}.0,10.0,2561.{i},60" for i in range(1, 5)]
    return (head + "# model: ADXRS610-class\n# serial: MEMS-0610-001\n"
            + "\n".join(rows) + "\n").encode()


def setup(store, spec_key="jjf1535-2015"):
    people = make_people(store)
    tech = people["tech"]
    cust = services.add_customer(store, tech, "C", "1 Road")
    inst = services.register_instrument(store, tech, customer_id=cust.id,
                                        serial="MEMS-0610-001", spec_key=spec_key,
                                        model="ADXRS610-class")
    std = services.add_standard(store, tech, name="rate table", identifier="RT-07",
                                due_on="2099-01-01")
    return tech, inst, std


def submit(store, tech, inst, std, body: bytes, temperature_c):
    import io

    sha, _ = services.store_file(store, io.BytesIO(body))
    return submission.submit_calibration(store, tech, instrument_id=inst.id,
                                         readings_sha256=sha, standard_ids=[std.id],
                                         temperature_c=temperature_c, humidity_pct=45,
                                         performed_on="2025-11-20")


def test_a_logged_room_temperature_is_compared_at_submission(sqlite_store):
    tech, inst, std = setup(sqlite_store)
    with pytest.raises(GonioError, match=r"temperature: the readings say 27 °C \(the "
                                         r"temperature_c column: median of 4 rows of the tests "
                                         r"run in the room\), what was entered 20.1 °C") as got:
        submit(sqlite_store, tech, inst, std, rate_readings("27"), 20.1)
    assert got.value.key == "readings" and "\n" not in str(got.value)
    # a slow logger's blanks between its rows are no value; the logged ones are compared
    sparse = rate_readings("27").replace(b",2560.2,27", b",2560.2,")
    with pytest.raises(GonioError, match="median of 3 rows"):
        submit(sqlite_store, tech, inst, std, sparse, 20.1)
    assert submit(sqlite_store, tech, inst, std, rate_readings("27"), 26.5).status == "queued"


def test_a_temperature_attached_later_is_compared_with_the_logged_one(sqlite_store):
    tech, inst, std = setup(sqlite_store)
    cal = submit(sqlite_store, tech, inst, std, rate_readings("20.3"), 20.1)
    # the column logged 20.3: an attached 27 contradicts it, whatever entered it
    with pytest.raises(GonioError, match=r"temperature: the readings say 20.3 °C \(the "
                                         r"temperature_c column: .*\), entered 27 °C: enter "
                                         "the conditions of these readings") as got:
        services.attach_conditions(sqlite_store, tech, cal.id, temperature_c=27,
                                   humidity_pct=45)
    assert got.value.key == "environment"
    assert services.calibration(sqlite_store, cal.id).temperature_c == 20.1   # unchanged
    got = services.attach_conditions(sqlite_store, tech, cal.id, temperature_c=20.6,
                                     humidity_pct=45)
    assert got.temperature_c == 20.6


def test_the_metadata_line_does_not_hide_the_logged_column(sqlite_store):
    """A ``# room_temperature_c`` line that agrees with what was entered, beside a column that
    logged otherwise: the column is what was measured."""
    tech, inst, std = setup(sqlite_store)
    body = rate_readings("27", head="# spec: jjf1535-2015\n# room_temperature_c: 20.0\n")
    with pytest.raises(GonioError, match="the readings say 27 °C"):
        submit(sqlite_store, tech, inst, std, body, 20.1)
    # taken from the readings: the line and the column must agree as well
    cal = submit(sqlite_store, tech, inst, std, rate_readings("20.0", head=(
        "# spec: jjf1535-2015\n# room_temperature_c: 20.0\n# humidity_pct: 40\n")), 20.1)
    got = services.attach_conditions(sqlite_store, tech, cal.id,
                                     environment_from_readings=True)
    assert (got.temperature_c, got.environment_from) == (20.0, "readings")


def test_iec_base_temperature_is_not_the_room(sqlite_store):
    """IEC 62047-20's ``# room_temperature_c`` is the chamber's T_BASE: a room at 20 °C
    entered beside a T_BASE of 22.5 °C is no contradiction (as in ``gonio calibrate``)."""
    tech, inst, std = setup(sqlite_store, spec_key="iec62047-20")
    body = (b"# spec: iec62047-20\n# room_temperature_c: 22.5\n# model: ADXRS610-class\n"
            b"# serial: MEMS-0610-001\ntest,run,step,role,time_s,rate_dps,output\n"
            b"sf,1,1,ref,0.0,10.0,2560.1\n")
    assert submit(sqlite_store, tech, inst, std, body, 20).status == "queued"
