"""The environment the readings state (``# temperature_c``, ``# humidity_pct``) is a number in
a plausible range for every specification: text in its place ("45 %RH") is refused in one
line naming the key (exit 2, no traceback); a number in exponent form ("2e1") is stated
plainly on the certificate ("20 °C"), as a laboratory file's number is."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gonio.cli import main

SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")
PINS = Path(__file__).parent / "data" / "pins"


def protocol(spec: str) -> list[str]:
    """The small programme of the pin test (tests/data/pins/SPEC-small.toml; the built-in one
    where it has none): the environment is read and stated alike whatever the programme's
    size, and the built-in programmes cost more CPU to simulate and to calibrate."""
    small = PINS / f"{spec}-small.toml"
    return ["--spec", spec, "--protocol", str(small)] if small.exists() else ["--spec", spec]


def with_line(src, dst, line: str) -> None:
    """The readings with one metadata line added at the top (other files beside)."""
    dst.write_text(line + "\n" + src.read_text())


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    base = tmp_path_factory.mktemp("env")
    for spec in SPECS:
        assert main(["simulate", *protocol(spec), "--seed", "3", "--out", str(base / spec)]) == 0
    return base


@pytest.mark.parametrize("spec", SPECS)
@pytest.mark.parametrize("line,key", [("# humidity_pct: 45 %RH", "humidity_pct"),
                                      ("# temperature_c: twenty", "temperature_c"),
                                      ("# humidity_pct: 140", "humidity_pct"),
                                      # digits of other scripts, an underscore: float() takes
                                      # them, a certificate and a DCC cannot state them
                                      ("# humidity_pct: \uff14\uff15", "humidity_pct"),
                                      ("# humidity_pct: \u0664\u0665", "humidity_pct"),
                                      ("# temperature_c: 2_0", "temperature_c")])
def test_environment_text_refused(simulated, spec, line, key, capsys):
    folder = simulated / spec
    bad = folder / "bad.csv"
    with_line(folder / "readings.csv", bad, line)
    capsys.readouterr()
    assert main(["calibrate", str(bad), *protocol(spec), "--out", str(folder / "out_bad")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and "internal error" not in err, err
    assert key in err and "bad.csv" in err, err
    assert not (folder / "out_bad").exists()


@pytest.mark.parametrize("spec", SPECS)
def test_exponent_form_stated_plainly(simulated, spec, capsys):
    folder = simulated / spec
    src = folder / "readings.csv"
    if re.search(r"(?m)^# (temperature_c|room_temperature_c):", src.read_text()):
        text = re.sub(r"(?m)^# (temperature_c|room_temperature_c):[^\n]*\n", "",
                      src.read_text())
        src = folder / "plain.csv"
        src.write_text(text)
    exp = folder / "exp.csv"
    with_line(src, exp, "# temperature_c: 2.05e1")
    capsys.readouterr()
    assert main(["calibrate", str(exp), *protocol(spec), "--out", str(folder / "out_exp")]) == 0
    html = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ",
                                      (folder / "out_exp" / "certificate.html").read_text()))
    assert "20.5 °C" in html and "2.05e1" not in html
