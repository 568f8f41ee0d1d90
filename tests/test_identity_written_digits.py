"""A temperature or humidity contradiction names both numbers as they were written: the
laboratory file's ``temperature_c = 25.0`` is "25.0 °C" (as the certificate prints it), a
form's "25.0" likewise, the readings' ``# temperature_c: 20.0`` "20.0 °C" — never the float's
"25 °C", which would print a resolution nobody wrote."""
from types import SimpleNamespace

import pytest

from gonio.errors import GonioError
from gonio.formats.lab import load_lab
from gonio.pipeline.identity import contradictions
from gonio.records import services
from gonio.records.submission import check_readings
from gonio.report.header import condition_text


LAB = """[laboratory]
name = "Lab W"
address = "1 Row"
[certificate]
number = "W-1"
[customer]
name = "C"
address = "2 Row"
[signatory]
approved_by = "A. B."
approved_title = "Manager"
[environment]
"""


def test_lab_file_digits(tmp_path):
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB + "temperature_c = 25.0\nhumidity_pct = 70.50\n",
                   encoding="utf-8")
    d = load_lab(lab)
    found = {c["what"]: c for c in contradictions(
        {"temperature_c": " 20.0 ", "humidity_pct": "45"}, d)}
    env = d["environment"]
    assert found["temperature"]["lab"] == f"{env['temperature_c'].text} °C" == "25.0 °C"
    assert found["temperature"]["readings"] == "20.0 °C"
    assert found["humidity"]["lab"] == "70.50 %" and found["humidity"]["readings"] == "45 %"


def test_certificate_and_message_print_one_text(tmp_path):
    """The contradiction's laboratory number is the certificate's condition text."""
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB + "temperature_c = 25.0\n", encoding="utf-8")
    t = load_lab(lab)["environment"]["temperature_c"]
    (c,) = contradictions({"temperature_c": "20.0"}, load_lab(lab))
    assert c["lab"].split(" ")[0] in condition_text(t)


@pytest.mark.parametrize("typed", ["25.0", "25.00", "25"])
def test_records_form_digits(typed):
    temp = services.condition_value(typed, "temperature_c", -50, 100)
    inst = SimpleNamespace(serial="", model="", manufacturer="", gyro_type="")
    facts = {"spec": None, "spec_from": "", "metadata": {"temperature_c": "20.0"}}
    with pytest.raises(GonioError) as e:
        check_readings(facts, inst, "ogam-draft", temp, None)
    assert f"the readings say 20.0 °C (# temperature_c), what was entered {typed} °C " \
           "(more than 1 °C apart)" in str(e.value)


@pytest.mark.parametrize("written", ["30,0", "30 °C", "303.15 K", "３０"])
@pytest.mark.parametrize("with_lab", [True, False])
def test_a_room_temperature_no_number_is_refused(tmp_path, shared_simulation, capsys,
                                                 written, with_lab):
    """The optical readings' ``# room_temperature_c`` written so that it is no number: refused
    in one line (exit 2) whether a laboratory file's temperature would be compared with it
    or the certificate would state it — never passed unread, never printed as written."""
    from gonio.cli import main

    sim = shared_simulation("ogam-draft")
    text = (sim / "readings.csv").read_text(encoding="utf-8")
    body = "".join(ln for ln in text.splitlines(keepends=True)
                   if not ln.startswith("# temperature_c"))
    readings = tmp_path / "r.csv"
    readings.write_text(f"# room_temperature_c: {written}\n" + body, encoding="utf-8")
    lab = tmp_path / "lab.toml"
    lab.write_text(LAB.replace("[environment]\n", "[instrument]\nserial = \"RLG-0001\"\n"
                               "[environment]\n") + "temperature_c = 20.1\n", encoding="utf-8")
    argv = ["calibrate", str(readings), "--out", str(tmp_path / "out")]
    rc = main(argv + (["--lab", str(lab)] if with_lab else []))
    err = capsys.readouterr().err
    assert rc == 2 and "key room_temperature_c: expected a number" in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out" / "certificate.html").exists()
