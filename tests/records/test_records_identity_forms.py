"""The person the readings name as their operator (``# operator:``) is the calibration's
creator for the duties (ISO/IEC 17025 7.8.1.1: a second person reviews and approves), whatever
form their name is typed in: case, Unicode compatibility forms (full-width letters, an
ideographic space) and spacing folded on both sides by one normaliser
(``gonio.formats.metadata.identity_text``); a different name still reviews. The same
normaliser matches readings to a registered instrument's serial."""

from __future__ import annotations

import pytest

from gonio.errors import GonioError
from gonio.records import services

from .conftest import PASSWORD
from .test_records_services import new_calibration, run_worker, setup_instrument


def _with_operator(src, dst, operator: str):
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    at = [i for i, ln in enumerate(lines) if ln.lower().startswith("# operator:")]
    assert len(at) == 1                    # the bench names its operator: replaced here
    lines[at[0]] = f"# operator: {operator}\n"
    dst.write_text("".join(lines), encoding="utf-8")
    return dst


@pytest.mark.parametrize("operator", ["ALICE SMITH", "ＡＬＩＣＥ\u3000ＳＭＩＴＨ",
                                      "alice  smith", "Ａｌｉｃｅ Ｓｍｉｔｈ"],
                         ids=["upper", "full-width-ideographic-space", "spacing",
                              "full-width-mixed"])
def test_the_operator_in_another_form_does_not_review(store, people, computed_folder,
                                                      bench_readings, monkeypatch, tmp_path,
                                                      operator):
    """Readings naming ``operator`` (Alice Smith in another form): user Alice Smith may not
    review them, in the one-line duty refusal; another reviewer may."""
    alice = services.create_user(store, None, "asmith", PASSWORD, "reviewer",
                                 full_name="Alice Smith")
    readings = _with_operator(bench_readings[0], tmp_path / "readings.csv", operator)
    inst, std = setup_instrument(store, people)
    new_calibration(store, people, inst, std, readings)
    cal = run_worker(store, monkeypatch, computed_folder)
    with pytest.raises(GonioError, match=r"as their operator: the person who measured "
                                         r"may not review") as got:
        services.review(store, alice, cal.id, accept=True)
    assert got.value.key == "role" and "\n" not in str(got.value)
    assert services.review(store, people["rev"], cal.id, accept=True).status == "reviewed"


def test_a_full_width_serial_is_the_registered_instrument(store, people):
    """Readings naming the registered RLG-0001 in full-width forms are of that instrument
    (never a second registration of it); another serial is not."""
    from gonio.records.importer import registered_instrument

    inst, _ = setup_instrument(store, people)
    with store.session() as s:
        meta = {"serial": "ＲＬＧ－０００１", "manufacturer": "Ｅｘａｍｐｌｅ Ｇｙｒｏ Ｗｏｒｋｓ",
                "model": "RLG-GM-1"}
        assert registered_instrument(s, meta).id == inst.id
        assert registered_instrument(s, {**meta, "serial": "ＲＬＧ－０００２"}) is None


@pytest.mark.parametrize("serial", ["rlg-0001", "ＲＬＧ－０００１", " RLG-0001\u200b"])
def test_one_instrument_is_not_registered_twice_in_another_form(store, people, serial):
    """The registered RLG-0001 (Example Gyro Works RLG-GM-1) in another form of its serial
    is refused at registration and at an edit of another instrument, in one line naming the
    registered one; RLG-0002 is another instrument."""
    from sqlalchemy import func, select

    from gonio.records.models import Instrument

    inst, _ = setup_instrument(store, people)
    tech = people["tech"]
    with pytest.raises(GonioError, match=r"^key serial: this instrument \(manufacturer, "
                                         r"model, serial\) is registered as Example Gyro "
                                         r"Works RLG-GM-1 RLG-0001") as got:
        services.register_instrument(store, tech, customer_id=inst.customer_id, serial=serial,
                                     spec_key="ogam-draft", manufacturer="EXAMPLE GYRO WORKS",
                                     model="RLG-GM-1")
    assert "\n" not in str(got.value)
    with store.session() as s:
        assert s.scalar(select(func.count()).select_from(Instrument)) == 1
    other = services.register_instrument(store, tech, customer_id=inst.customer_id,
                                         serial="RLG-0002", spec_key="ogam-draft",
                                         manufacturer="Example Gyro Works", model="RLG-GM-1")
    with pytest.raises(GonioError, match="is registered as Example Gyro Works RLG-GM-1 "
                                         "RLG-0001"):
        services.update_instrument(store, tech, other.id, serial=serial)
    assert services.update_instrument(store, tech, inst.id, serial=serial).id == inst.id
