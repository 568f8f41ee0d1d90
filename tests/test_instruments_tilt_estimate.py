"""The in-situ tilt estimate (``[tilt_estimate]``, beyond the draft) taken through the
instruments: ``gonio acquire`` on the served virtual bench writes the rests as ``gonio
simulate`` does (same rows, same columns), the tilt it gives agrees with the simulation's of
the same bench and seed and with the bench file's own tilt within the estimate's
uncertainty, the calibration then states K corrected by the measured tilt (line K_te), and an
acquisition interrupted in the middle of the rests continues at the next position.

The served bench and ``gonio simulate`` share the bench's physics and seeding but not the
timing (a served session's instants are the host's), so the two files agree within the
noise, not bit for bit, and a served file differs from run to run: the comparisons are
Student-t intervals of 99.99 % (the rests taken in opposite pairs: ν = N/2 − 2 = 4, k =
15.5), so that a correct acquisition fails them about once in ten thousand comparisons —
the two served acquisitions below make ten random ones a run, so about one CI run in a
thousand (at 99.9 % it was one in a hundred, and a CI run failed so, before the pairs
made the intervals honest) — while a wrong sign of the table angle mirrors α about the
direction β of the Earth rate across the axis, moving it by 2|α − β| (the bound
k·√(u_a² + u_s²) is ≈ 44° at u(α) ≈ 2°). The bench is the ``rlg`` bench
with its tilt at the draft's Annex A.1 bound, 0.1°, at azimuth 120°."""

from __future__ import annotations

import contextlib
import io
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import t as student_t

from gonio.cli import main
from gonio.physics.kinematics import trapezoid_duration_s
from gonio.specs.ogam_draft.acquisition import acquire, plan_programme, programme_duration_s
from gonio.specs.ogam_draft.acquisition_module import AcquisitionModule
from gonio.specs.ogam_draft.bench import load_bench
from gonio.specs.ogam_draft.protocol import load_protocol
from gonio.specs.ogam_draft.readings import read_readings
from gonio.specs.ogam_draft.served import serve_bench
from gonio.specs.ogam_draft.tilt_estimate import tilt_estimate_from_readings

ROOT = Path(__file__).resolve().parents[1]
PROTOCOL = ROOT / "tests" / "data" / "small-tilt-protocol.toml"
SEED = 3
SPEED = 200.0          # simulated seconds per real second: the programme in ~10 s
LATITUDE_DEG = 40.2
META = {"latitude_deg": str(LATITUDE_DEG)}
N_TOTAL = 3 + 12 + 3   # 7.3's readings, the 12 rests, 7.1's rounds
TILT_DEG, AZIMUTH_DEG = 0.1, 120.0
#: Student-t factor of the tests' 99.99 % intervals, ν = 12/2 − 2 (six opposite pairs).
K9999 = float(student_t.ppf(1.0 - 0.5e-4, 4))
#: The Earth's rotation rate, ″/s (WGS 84: 7.292115×10⁻⁵ rad/s).
EARTH_ARCSEC_S = 7.292115e-5 * 180.0 / math.pi * 3600.0


@pytest.fixture(scope="module")
def bench_file(tmp_path_factory):
    """The ``rlg`` bench file with its tilt at the A.1 bound and azimuth 120°."""
    text = (ROOT / "protocols" / "benches" / "rlg.toml").read_text(encoding="utf-8")
    lines = [f"tilt_deg = {TILT_DEG}" if ln.startswith("tilt_deg =") else
             f"tilt_azimuth_deg = {AZIMUTH_DEG}" if ln.startswith("tilt_azimuth_deg =") else ln
             for ln in text.splitlines()]
    assert lines != text.splitlines()
    path = tmp_path_factory.mktemp("bench") / "rlg-tilted.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def rlg(bench_file):
    b = load_bench(bench_file)
    assert (b.instrument.tilt_deg, b.instrument.tilt_azimuth_deg) == (TILT_DEG, AZIMUTH_DEG)
    return b


@pytest.fixture(scope="module")
def simulated(tmp_path_factory, bench_file, simulate_calibrate):
    """``gonio simulate`` + ``gonio calibrate`` of the protocol on the same bench and seed
    (tests/conftest.py)."""
    return simulate_calibrate(tmp_path_factory.mktemp("sim"), PROTOCOL, bench_file, SEED)


@pytest.fixture()
def calibrate(calibrate_readings):
    """``gonio calibrate`` of a readings file with :data:`PROTOCOL` (tests/conftest.py)."""
    return lambda readings, out: calibrate_readings(readings, PROTOCOL, out)


def _rows(path: Path):
    df = read_readings(path).data
    return df[["test", "series", "round", "rate_dps", "orientation", "table_deg"]] \
        .fillna(-1.0).to_records(index=False).tolist()


def _assert_tilt_agrees(acq: Path, sim: Path, bench) -> None:
    """ψ and α of the two files agree within K9999·√(u_a² + u_s²), and each holds the bench
    file's ψ and α within its own K9999·u (the bench's truth, independent of the estimator);
    the fit's offset is the Earth rate along the vertical, Ω sin φ (closed form: the rests'
    counts are not compensated), within the bench's bias and K9999·u."""
    a, s = (tilt_estimate_from_readings(read_readings(p)) for p in (acq, sim))
    k = K9999
    assert abs(a.tilt_deg - s.tilt_deg) <= k * math.hypot(a.u_tilt_deg, s.u_tilt_deg), (a, s)
    d_az = (a.tilt_azimuth_table_deg - s.tilt_azimuth_table_deg + 180.0) % 360.0 - 180.0
    assert abs(d_az) <= k * math.hypot(a.u_phase_deg, s.u_phase_deg), (a, s)
    inst = bench.instrument
    vertical = EARTH_ARCSEC_S * math.sin(math.radians(LATITUDE_DEG))
    bias = inst.bias_dph + inst.warmup_drift_dph          # °/h, = ″/s ÷ 1 (3600″/3600 s)
    for e in (a, s):
        assert abs(e.tilt_deg - inst.tilt_deg) <= k * e.u_tilt_deg, e
        d = (e.tilt_azimuth_table_deg - inst.tilt_azimuth_deg + 180.0) % 360.0 - 180.0
        assert abs(d) <= k * e.u_phase_deg, e
        assert e.n_positions == 12 and e.dof == 4 and e.basis == "opposite pairs"
        assert abs(e.offset_arcsec_s - vertical) <= bias + k * e.residual_sd_arcsec_s, e


def _assert_k_corrected(acq_items: dict, sim_items: dict) -> None:
    """Both calibrations state K corrected by the measured tilt (budget line K_te, not
    K_tilt) and the two K agree within their U (root sum of squares)."""
    for it in (acq_items, sim_items):
        sf = it["scale_factor"]
        assert sf["details"]["stated"] == "tilt_corrected"
        syms = [c["symbol"] for c in sf["uncertainty"]["components"]]
        assert "K_te" in syms and "K_tilt" not in syms
    a, s = acq_items["scale_factor"], sim_items["scale_factor"]
    assert abs(a["value"] - s["value"]) <= math.hypot(a["uncertainty"]["U"],
                                                      s["uncertainty"]["U"])


# ------------------------------------------------------------------ the plan
def test_plan_takes_the_rests_after_zero_stability_uncompensated():
    proto = load_protocol(PROTOCOL)
    blocks = plan_programme(proto)
    assert [b.label for b in blocks][:3] == ["zero_stability", "tilt_estimate up",
                                            "scale_factor up 60 dps series 1"]
    te = blocks[1]
    assert te.positions and not te.at_rest and te.rezero
    # opposite pairs: 0°, 180°, 30°, 210°, …, 150°, 330°
    order = [30.0 * (i // 2) + 180.0 * (i % 2) for i in range(12)]
    assert [st.stop_deg for st in te.steps] == order
    assert {(st.test, st.series, st.rate_dps, st.read_delay_s, st.rest_s) for st in te.steps} \
        == {("tilt_estimate", 1, 60.0, 120.0, 5.0)}
    # each rest: the move at 60 °/s from the one before (180° into a pair, 150° back to the
    # next pair; none for the first), the settling, the dwell; no static phase (the Earth
    # rate is the signal)
    accel = 200.0
    per = programme_duration_s(blocks, proto, accel)[3:15]
    move = [trapezoid_duration_s(d, 60.0, accel) for d in (180.0, -150.0)]
    assert move == pytest.approx([d / 60.0 + 60.0 / accel for d in (180.0, 150.0)])  # d/v + v/a
    assert per == pytest.approx([125.0] + [move[i % 2 == 0] + 125.0 for i in range(1, 12)])


# ------------------------------------------------------------------ against the simulation
def test_acquired_rests_give_the_simulations_tilt_and_correct_k(rlg, simulated, calibrate,
                                                                 tmp_path):
    s = serve_bench(rlg, speed=SPEED, seed=SEED)
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = main(["acquire", "--protocol", str(PROTOCOL), "--table", s.table_resource,
                       "--gyro", s.gyro_resource, "--out", str(tmp_path / "acq"),
                       "--meta", f"latitude_deg={LATITUDE_DEG}"])
    finally:
        s.close()
    assert rc == 0, err.getvalue()
    assert "tilt_estimate" not in err.getvalue()           # no note: the rests are taken
    acq = tmp_path / "acq" / "readings.csv"
    assert _rows(acq) == _rows(simulated[0])                # same rows, same positions
    df = read_readings(acq).data
    te = df[df["test"] == "tilt_estimate"]
    # each dwell is the protocol's 120 s plus the host's latency on the module's clock; at
    # SPEED the latency is multiplied (40 ms of a busy host is 8 s of bench time), so the
    # upper bound only catches a dwell taken twice, not the host's load
    assert np.all((te["time_s"] >= 120.0) & (te["time_s"] < 180.0))
    _assert_tilt_agrees(acq, simulated[0], rlg)
    _assert_k_corrected(calibrate(acq, tmp_path / "cal"), simulated[1])


class Terminal(io.StringIO):
    """stderr as an interactive terminal (the status lines are written only to one)."""

    def isatty(self) -> bool:
        return True


class InterruptedModule(AcquisitionModule):
    """A module whose ``stop_at``-th ``READ?`` is interrupted (the operator's Ctrl-C)."""

    stop_at = 0
    reads = 0

    def read(self, expected_counts: float = 0.0):
        type(self).reads += 1
        if type(self).reads == self.stop_at:
            raise KeyboardInterrupt
        return super().read(expected_counts)


def test_resume_in_the_middle_of_the_rests(rlg, simulated, calibrate, tmp_path):
    """Stopped at the 5th rest's reading: 7.3's readings and 4 rests stand (each rest has
    its own zeroing); the resume takes the 4 other rests and 7.1 only, every reading once."""
    out = tmp_path / "acq"
    # READ? calls: 7.3's static phase (measured compensation) and its 3 readings, then one
    # per rest: the 9th is the 5th rest's
    InterruptedModule.stop_at, InterruptedModule.reads = 1 + 3 + 5, 0
    s = serve_bench(rlg, speed=SPEED, seed=SEED)
    try:
        with pytest.raises(KeyboardInterrupt), contextlib.redirect_stderr(io.StringIO()):
            acquire(load_protocol(PROTOCOL), s.table_resource, s.gyro_resource, out,
                    metadata=META, gyro_cls=InterruptedModule)
        kept = read_readings(out / "readings.csv")
        assert kept.metadata["acquisition"] == "incomplete"
        assert (kept.data["test"] == "tilt_estimate").sum() == 4 and len(kept.data) == 7
        before = (out / "readings.csv").read_text(encoding="utf-8")
        term = Terminal()
        with contextlib.redirect_stderr(term):
            res = acquire(load_protocol(PROTOCOL), s.table_resource, s.gyro_resource, out,
                          resume=True, metadata=META)
    finally:
        s.close()
    assert res.complete and res.taken == N_TOTAL - 7 and res.total == N_TOTAL
    # on a terminal: the rest under way, then the point count (7.3 and 4 rests kept: the
    # resume's first reading is point 8 of 18)
    shown = term.getvalue()
    assert "acquire: tilt estimate rest 5/12 at 60°, 2 min 00 s dwell" in shown, shown
    assert "rest 4/12" not in shown
    assert f"acquire: point 8/{N_TOTAL}  tilt_estimate series 1 round 5  about" in shown, shown
    after = (out / "readings.csv").read_text(encoding="utf-8")
    body = [ln for ln in before.splitlines() if ln and not ln.startswith("#")]
    assert after.splitlines()[-N_TOTAL - 1:][:len(body)] == body    # the kept rows stand
    assert _rows(out / "readings.csv") == _rows(simulated[0])       # every reading once
    _assert_tilt_agrees(out / "readings.csv", simulated[0], rlg)
    _assert_k_corrected(calibrate(out / "readings.csv", tmp_path / "cal"), simulated[1])
