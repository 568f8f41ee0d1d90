"""Gyro-triad electrical alignment and the extended MEMS-gyro model.

Not a standard: a calibration built on the alignment application article ([Looney-alignment]:
misalignment budget, electrical alignment with M⁻¹) and the MEMS-gyro thesis ([Vagner2015]:
K(ϑ, U), b(ϑ, U), ARW(ϑ)), with the cross-axis sensitivity of IEC 62047-20 5.2.
:mod:`~gonio.specs.triad_alignment.calibration` computes the results;
:mod:`~gonio.specs.triad_alignment.simulate` simulates them on the virtual bench;
:mod:`~gonio.specs.triad_alignment.study` is the coverage study of ``gonio validate``;
:mod:`~gonio.specs.triad_alignment.commands` adds ``gonio align`` and ``gonio thermal-model``. The
reading taken of the sources is ``docs/alignment.md`` and ``docs/thermal-model.md``.
"""

from gonio.specs import Coverage, Specification, lazy
from gonio.specs.triad_alignment.keys import ALIGNMENT_KEYS, NONNEGATIVE_KEYS, THERMAL_POINT_KEYS

#: ``gonio.specs.triad_alignment.readings.FORMAT``, written here so that loading ``SPEC`` imports no reader
#: (tests/test_cli_startup.py checks that the two agree).
FORMAT = "gonio-triad-readings/1"


def _simulate(out, *, protocol="triad-alignment", bench="mems-triad", seed: int = 0):
    """``SPEC.simulate``: readings.csv (alignment session), thermal.csv (chamber programme)
    and truth.json into ``out``, by their roles."""
    from gonio.specs.triad_alignment.simulate import simulate

    paths = simulate(protocol, bench, seed, out)
    roles = {"readings.csv": "readings", "thermal.csv": "thermal", "truth.json": "truth"}
    return {roles.get(name, name): p for name, p in paths.items()}


SPEC = Specification(
    key="triad-alignment",
    title_en="Gyro triad: mechanical misalignment budget, electrical alignment and extended "
             "temperature / supply model",
    title_zh="三轴陀螺组件:安装失准预算、电气对准与温度/电压扩展模型",
    clause_doc="docs/alignment.md",
    default_protocol="triad-alignment",
    default_bench="mems-triad",
    calibrate=lazy("gonio.specs.triad_alignment.calibration:calibrate"),
    screen=lazy("gonio.specs.triad_alignment.calibration:screen_files"),
    simulate=_simulate,
    simulated_files=("readings.csv", "truth.json"),
    truth=lazy("gonio.specs.triad_alignment.truth:truth"),
    budget=lazy("gonio.specs.triad_alignment.calibration:article_budget"),
    outputs="gonio.specs.triad_alignment.outputs",
    calibrate_options=frozenset({"thermal", "robust", "dcc", "protocol"}),
    coverage=Coverage(engine="cases", stream=2,
                      study=lazy("gonio.specs.triad_alignment.study:plan_study"),
                      options=frozenset({"cases", "resume"})),
    arguments={"calibrate": "gonio.specs.triad_alignment.commands:add_calibrate_options",
               "validate": "gonio.specs.triad_alignment.commands:add_validate_options"},
    readings_format=FORMAT,
    named_inputs=lazy("gonio.specs.triad_alignment.readings:named_inputs"),
    certificate_content="gonio.specs.triad_alignment.certificate",
    item_keys=tuple(ALIGNMENT_KEYS) + THERMAL_POINT_KEYS,
    nonnegative_items=NONNEGATIVE_KEYS,
    commands=(("align", "gonio.specs.triad_alignment.commands:add_align"),
              ("thermal-model", "gonio.specs.triad_alignment.commands:add_thermal_model")),
)
