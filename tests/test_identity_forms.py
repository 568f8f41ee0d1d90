"""The readings' identity texts against the laboratory file's (gonio.pipeline.identity) are
compared by the one identity normaliser (gonio.formats.metadata.identity_text) the records
use for names and serials: a serial typed in full-width characters, another case or with a
zero-width space is the same serial; a different serial is still a contradiction."""

from __future__ import annotations

import pytest

from gonio.pipeline.identity import contradictions, record_contradictions

LAB = {"instrument": {"serial": "RLG-0001", "manufacturer": "Example Gyro Works"}}


@pytest.mark.parametrize("serial", ["ＲＬＧ－０００１", "rlg-0001", "RLG\u200b-0001 ",
                                    "RLG-0001"])
def test_the_same_serial_in_another_form_is_no_contradiction(serial):
    assert contradictions({"serial": serial}, LAB) == []
    assert record_contradictions({"serial": serial}, None, {"serial": "RLG-0001"}) == []


@pytest.mark.parametrize("serial", ["ＲＬＧ－０００２", "RLG-0002", "RLG-00O1"])
def test_another_serial_is_a_contradiction(serial):
    found = contradictions({"serial": serial}, LAB)
    assert [(c["what"], c["readings"], c["lab"]) for c in found] == [
        ("serial", f"'{serial}'", "'RLG-0001'")]
