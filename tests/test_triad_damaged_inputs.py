"""Damaged triad inputs, from the outside: a simulated readings.csv + thermal.csv is
damaged as a file would be (cut short, a typed set point, a spike in the static record),
then ``gonio calibrate`` runs on it. Each is refused with a one-line error (exit 2) or set
aside and stated as a finding; none changes a certified number silently."""

from __future__ import annotations

import json
import shutil

import pytest

from gonio.cli import main


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    d = tmp_path_factory.mktemp("tri") / "sim"
    assert main(["simulate", "--spec", "triad-alignment", "--out", str(d)]) == 0
    return d


def _copy(sim, tmp_path):
    d = tmp_path / "in"
    shutil.copytree(sim, d)
    return d


def _rows(text: str, test: str) -> list[int]:
    return [i for i, ln in enumerate(text.split("\n")) if ln.startswith(test + ",")]


def _edit(text: str, i: int, column: str, value: str) -> str:
    lines = text.split("\n")
    header = next(ln for ln in lines if ln.startswith("test,")).split(",")
    cells = lines[i].split(",")
    cells[header.index(column)] = value
    lines[i] = ",".join(cells)
    return "\n".join(lines)


def _calibrate(d, tmp_path, capsys):
    rc = main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "out")])
    return rc, capsys.readouterr()


@pytest.mark.parametrize("cut", [1, 6, 17])
def test_thermal_file_cut_inside_its_last_number_is_refused(sim, tmp_path, capsys, cut):
    """Before: the last row's sd_z cut to '0' (cells all present, no final newline) was
    read as 0 and moved the certified ARW_z at the last set point by −12 %."""
    d = _copy(sim, tmp_path)
    text = (d / "thermal.csv").read_text(encoding="utf-8")
    (d / "thermal.csv").write_text(text.rstrip("\n")[:-cut], encoding="utf-8")
    n = len(text.rstrip("\n").split("\n"))
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 2
    err = cap.err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert f"thermal.csv:{n}: column sd_z: the file ends inside its last row" in err, err


def test_readings_file_cut_inside_its_last_number_is_refused(sim, tmp_path, capsys):
    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    (d / "readings.csv").write_text(text.rstrip("\n")[:-3], encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 2 and "readings.csv:" in cap.err and "ends inside its last row" in cap.err


def test_complete_files_with_a_final_newline_still_calibrate(sim, tmp_path, capsys):
    d = _copy(sim, tmp_path)
    rc, _ = _calibrate(d, tmp_path, capsys)
    assert rc == 0


def _results(tmp_path, name="out"):
    return json.loads((tmp_path / name / "results.json").read_text(encoding="utf-8"))


def _value(res, key):
    return res["items"][key]["value"]


def test_thermal_supply_typo_is_set_aside_as_a_finding(sim, tmp_path, capsys):
    """Before: one soak row with supply_v 50 for 5 was used silently (its ± pair lost, the
    ARW and K points moved, no finding). Now set aside with a ``setting-departs`` finding,
    the numbers those of the same file with that row deleted."""
    d = _copy(sim, tmp_path)
    text = (d / "thermal.csv").read_text(encoding="utf-8")
    i = _rows(text, "thermal")[100]
    (d / "thermal.csv").write_text(_edit(text, i, "supply_v", "50"), encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 0
    res = _results(tmp_path)
    f = [f for f in res["findings"] if f["code"] == "setting-departs"]
    assert len(f) == 1 and f[0]["action"] == "set_aside" and f[0]["line"] == i + 1, f
    assert f[0]["column"] == "supply_v" and "supply_v 50 V" in f[0]["message"]
    assert "supply_v 50 V" in (tmp_path / "out" / "summary.txt").read_text(encoding="utf-8")
    assert "supply_v 50 V" in (tmp_path / "out" / "certificate.html").read_text(encoding="utf-8")
    lines = text.split("\n")
    (d / "thermal.csv").write_text("\n".join(lines[:i] + lines[i + 1:]), encoding="utf-8")
    assert main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "del")]) == 0
    deleted = _results(tmp_path, "del")
    for key in ("ARW_z_t1", "K_z_t2_v1", "b_z_t2_v1"):
        assert _value(res, key) == _value(deleted, key), key


def test_static_record_spike_is_set_aside_as_a_finding(sim, tmp_path, capsys):
    """Before: one out_x of 1000 (≈ 11) in the static record set the averaging time ×4 with
    no finding. Now set aside (Hampel rule, as the rate specifications), named; the
    averaging time is that of the undamaged record."""
    d = _copy(sim, tmp_path)
    assert main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "ok")]) == 0
    text = (d / "readings.csv").read_text(encoding="utf-8")
    i = _rows(text, "static")[5000]
    (d / "readings.csv").write_text(_edit(text, i, "out_x", "1000"), encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 0
    res, ok = _results(tmp_path), _results(tmp_path, "ok")
    f = [f for f in res["findings"] if f["code"] == "output-outlier"]
    assert len(f) == 1 and f[0]["action"] == "set_aside" and f[0]["line"] == i + 1, f
    assert f[0]["column"] == "out_x"
    assert _value(res, "averaging_time") == _value(ok, "averaging_time")
    assert "out_x 1000" in (tmp_path / "out" / "summary.txt").read_text(encoding="utf-8")


def test_align_and_thermal_model_commands_screen_as_calibrate(sim, tmp_path, capsys):
    """``gonio align`` and ``gonio thermal-model`` read the same files: the spike and the
    supply typo are set aside there too and said on stderr (before: used silently)."""
    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    (d / "readings.csv").write_text(_edit(text, _rows(text, "static")[5000], "out_x", "1000"),
                                    encoding="utf-8")
    th = (d / "thermal.csv").read_text(encoding="utf-8")
    (d / "thermal.csv").write_text(_edit(th, _rows(th, "thermal")[100], "supply_v", "50"),
                                   encoding="utf-8")
    assert main(["align", str(d / "readings.csv")]) == 0
    assert "set aside:" in capsys.readouterr().err
    assert main(["thermal-model", str(d / "thermal.csv")]) == 0
    err = capsys.readouterr().err
    assert "set aside:" in err and "supply_v 50 V" in err


def test_supply_column_off_on_many_soak_rows_is_refused(sim, tmp_path, capsys):
    """Many soak rows off the shared set points are no typos: refused, the first named."""
    d = _copy(sim, tmp_path)
    text = (d / "thermal.csv").read_text(encoding="utf-8")
    rows = [i for i in _rows(text, "thermal") if ",soak," in text.split("\n")[i]]
    for k, i in enumerate(rows[::3][:12]):
        text = _edit(text, i, "supply_v", f"{6.0 + 0.5 * k:g}")
    (d / "thermal.csv").write_text(text, encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 2 and "thermal soak rows depart from the set points" in cap.err, cap.err
    assert f"thermal.csv:{rows[0] + 1}: column supply_v" in cap.err


def _delete(text: str, i: int) -> str:
    lines = text.split("\n")
    return "\n".join(lines[:i] + lines[i + 1:])


def _one_line_refusal(rc, cap, where: str):
    err = cap.err.strip()
    assert rc == 2 and "\n" not in err and "Traceback" not in err, err
    assert where in err, err
    return err


def test_n_samples_contradicting_duration_and_rate_is_refused(sim, tmp_path, capsys):
    """Before: an alignment dwell's n_samples halved (720 for 14.4 s at 100 Hz) was used as
    the dwell's weight (M_yx moved 0.06 %, no finding). Now refused naming the cell; one
    sample off (a record's ends) is accepted."""
    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    i = _rows(text, "alignment")[0]
    n = int(text.split("\n")[i].split(",")[9])
    (d / "readings.csv").write_text(_edit(text, i, "n_samples", str(n // 2)), encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    err = _one_line_refusal(rc, cap, f"readings.csv:{i + 1}: column n_samples:")
    assert "contradicts duration_s" in err and "sample_rate_hz" in err
    (d / "readings.csv").write_text(_edit(text, i, "n_samples", str(n + 1)), encoding="utf-8")
    assert main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "one")]) == 0
    # a logger that dropped 0.8 % of the samples states the count it averaged: accepted
    (d / "readings.csv").write_text(_edit(text, i, "n_samples", str(round(n * 0.992))),
                                    encoding="utf-8")
    assert main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "dropped")]) == 0


def test_empty_sd_cell_of_a_dwell_is_refused(sim, tmp_path, capsys):
    """Before: an alignment dwell's sd_x left empty was read as "no sd" and the dwell
    dropped out of the consistency check's noise scale, unsaid. Now refused naming the
    cell (a one-sample static row keeps its empty sd)."""
    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    i = _rows(text, "alignment")[0]
    (d / "readings.csv").write_text(_edit(text, i, "sd_x", ""), encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    _one_line_refusal(rc, cap, f"readings.csv:{i + 1}: column sd_x: empty sd_x")


def test_huge_sd_sets_its_dwell_aside_as_the_file_without_it(sim, tmp_path, capsys):
    """Before: sd_x 250 (the others ≈ 2.5) on an alignment dwell was used as given, no
    finding. Now the dwell is set aside (``sd-departs``), listed in unused_readings, and M
    and b are those of the same file with that row deleted."""
    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    i = _rows(text, "alignment")[0]
    (d / "readings.csv").write_text(_edit(text, i, "sd_x", "250"), encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 0, cap.err
    res = _results(tmp_path)
    f = [f for f in res["findings"] if f["code"] == "sd-departs"]
    assert len(f) == 1 and f[0]["action"] == "set_aside" and f[0]["line"] == i + 1, f
    assert f[0]["column"] == "sd_x"
    un = res["unused_readings"]
    assert [(u["line"], u["column"], u["reason"]) for u in un] == \
        [(i + 1, "sd_x", f[0]["message"])]
    (d / "readings.csv").write_text(_delete(text, i), encoding="utf-8")
    assert main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "del")]) == 0
    deleted = _results(tmp_path, "del")
    for key in ("M_xx", "M_yx", "M_xy", "b_x", "b_y", "S_yx"):
        assert _value(res, key) == _value(deleted, key), key


@pytest.mark.parametrize("column", ["out_z", "sensor_c"])
def test_ramp_row_typo_is_set_aside_as_the_file_without_it(sim, tmp_path, capsys, column):
    """Before: a ramp block's out_z with two digits transposed (4.08 → 40.8) or its sensor_c
    negated changed the ramp analysis the certificate states (the soak model's error on the
    ramps, the lag, the hysteresis) and was listed nowhere. Now set aside
    (``ramp-departs``), in unused_readings; the ramp analysis is that of the file with the
    row deleted."""
    d = _copy(sim, tmp_path)
    text = (d / "thermal.csv").read_text(encoding="utf-8")
    ramps = [i for i in _rows(text, "thermal") if ",ramp," in text.split("\n")[i]]
    i = ramps[len(ramps) // 2]
    header = next(ln for ln in text.split("\n") if ln.startswith("test,")).split(",")
    v = text.split("\n")[i].split(",")[header.index(column)]
    bad = f"{10 * float(v):.6f}" if column == "out_z" else "-" + v
    (d / "thermal.csv").write_text(_edit(text, i, column, bad), encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 0, cap.err
    res = _results(tmp_path)
    f = [f for f in res["findings"] if f["code"] == "ramp-departs"]
    assert len(f) == 1 and f[0]["action"] == "set_aside" and f[0]["line"] == i + 1, f
    assert f[0]["column"] == column and f[0]["file"].endswith("thermal.csv")
    un = res["unused_readings"]
    assert [(u["line"], u["phase"], u["reason"]) for u in un] == [(i + 1, "ramp", f[0]["message"])]
    (d / "thermal.csv").write_text(_delete(text, i), encoding="utf-8")
    assert main(["calibrate", str(d / "readings.csv"), "--out", str(tmp_path / "del")]) == 0
    deleted = _results(tmp_path, "del")
    ramp = res["extra"]["thermal_model"]["channels"]["z"]["ramp"]
    assert ramp == deleted["extra"]["thermal_model"]["channels"]["z"]["ramp"]
    for key in ("ARW_z_t1", "K_z_t2_v1", "b_z_t2_v1"):
        assert _value(res, key) == _value(deleted, key), key


def test_rows_set_aside_by_screening_are_unused_readings(sim, tmp_path, capsys):
    """Before: the supply typo and the static spike set aside were findings only;
    results.json's unused_readings was empty. Now each is listed there (file, line, test,
    step, phase, column, reason), the reason the finding's message."""
    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    s = _rows(text, "static")[5000]
    (d / "readings.csv").write_text(_edit(text, s, "out_x", "1000"), encoding="utf-8")
    th = (d / "thermal.csv").read_text(encoding="utf-8")
    t = _rows(th, "thermal")[100]
    (d / "thermal.csv").write_text(_edit(th, t, "supply_v", "50"), encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    assert rc == 0, cap.err
    res = _results(tmp_path)
    aside = {(f["file"], f["line"]): f for f in res["findings"] if f["action"] == "set_aside"}
    got = {(u["file"], u["line"]): u for u in res["unused_readings"]}
    assert got.keys() == aside.keys() and len(got) == 2
    for k, u in got.items():
        assert u["reason"] == aside[k]["message"] and u["column"] == aside[k]["column"]
    assert got[(str(d / "readings.csv"), s + 1)]["test"] == "static"
    u = got[(str(d / "thermal.csv"), t + 1)]
    assert (u["test"], u["phase"], u["column"]) == ("thermal", "soak", "supply_v")
    assert u["step"] == int(th.split("\n")[t].split(",")[1])


def test_static_record_with_many_moderate_spikes_is_refused(sim, tmp_path, capsys):
    """Before: 1 % of the static record's out_x raised by 6 σ (each below the Hampel limit
    of 8 σ that sets one sample aside) passed, the Allan floor raised with them. Now the
    record is refused as a rate specification's record is (the shared tail rule), naming a
    spiked sample."""
    import numpy as np

    d = _copy(sim, tmp_path)
    text = (d / "readings.csv").read_text(encoding="utf-8")
    rows = _rows(text, "static")
    lines = text.split("\n")
    header = next(ln for ln in lines if ln.startswith("test,")).split(",")
    k = header.index("out_x")
    y = np.array([float(lines[i].split(",")[k]) for i in rows])
    sigma = 1.4826 * float(np.median(np.abs(np.diff(y)))) / np.sqrt(2)
    hit = sorted(np.random.default_rng(1).choice(len(rows), len(rows) // 100,
                                                 replace=False).tolist())
    for j in hit:
        text = _edit(text, rows[j], "out_x", repr(float(y[j] + 6 * sigma)))
    (d / "readings.csv").write_text(text, encoding="utf-8")
    rc, cap = _calibrate(d, tmp_path, capsys)
    err = _one_line_refusal(rc, cap, "column out_x: static record: out_x:")
    assert "lie beyond 5 robust σ of the running median" in err and "damaged" in err
    line = int(err.split("readings.csv:")[1].split(":")[0])
    assert line - 1 in {rows[j] for j in hit}
