"""Nothing in a readings file is dropped silently (docs/formats.md#columns,
#rate-gyro-columns): a column misspelt near a column gonio reads (``temprature_c``,
``temperature`` for ``temperature_c``) is refused with one line naming it (exit 2), for every
specification; any other column a specification does not read (``temp_c``) is kept and
stated, a flagged finding ``unread-column`` in results.json, summary.txt and the certificate."""

from __future__ import annotations

import json

import pytest

from tests.test_provenance import PINS, RUNS, gonio, pdf_pages, simulated


def renamed(src, dst, new: str) -> None:
    """``src`` with its ``temperature_c`` column named ``new`` (a column ``new`` of 20.0
    appended where it has none)."""
    out, head = [], True
    for line in src.read_text(encoding="utf-8").splitlines(keepends=True):
        if head and not line.startswith("#"):
            cols = line.rstrip("\n").split(",")
            head = "add" if "temperature_c" not in cols else False
            cols = [new if c == "temperature_c" else c for c in cols] + ([new] if head else [])
            line = ",".join(cols) + "\n"
        elif head == "add" and line.strip():
            line = line.rstrip("\n") + ",20.0\n"
        out.append(line)
    dst.write_text("".join(out), encoding="utf-8")


@pytest.mark.parametrize("spec, protocol, seed", RUNS, ids=[r[0] for r in RUNS])
def test_a_misspelt_or_unread_temperature_column(spec, protocol, seed, tmp_path,
                                                 shared_simulation):
    proto = [] if protocol is None else ["--protocol", PINS / protocol]
    sim = simulated(shared_simulation, spec, protocol, seed, tmp_path / "sim")
    for name in ("temprature_c", "temperature", "temp_c"):
        readings = sim / f"{name}.csv"
        renamed(sim / "readings.csv", readings, name)
        out = tmp_path / name
        near = name != "temp_c" or spec == "triad-alignment"   # the triad reads no extras
        r = gonio("calibrate", readings, "--spec", spec, *proto, "--out", out, cwd=tmp_path,
                  rc=2 if near else 0)
        if near:
            line = r.stderr.strip()
            assert "\n" not in line and "Traceback" not in line, line
            assert f"column {name}:" in line, line
            assert not out.exists()
            continue
        res = json.loads((out / "results.json").read_text(encoding="utf-8"))
        (f,) = [f for f in res["findings"] if f["code"] == "unread-column"]
        assert f["column"] == name and f["action"] == "flagged" and "temperature_c" in f["message"]
        assert f"column '{name}' is not one {spec} reads" in (out / "summary.txt").read_text(
            encoding="utf-8")
        text = " ".join(" ".join(pdf_pages(out / "certificate.pdf")).split())
        assert f"column '{name}' is not one {spec} reads" in text
