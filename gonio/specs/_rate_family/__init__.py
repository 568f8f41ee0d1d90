"""What the rate-gyro specifications (JJF 1535-2015, IEC 62047-20) share.

A package whose name starts with ``_`` is no specification: it is the common ground of a
family of them, the one place two specifications may both import (one specification never
imports another; tests/test_layers.py). :mod:`.formulas` holds the rate arithmetic both
documents use; :mod:`.rate_records` the context of their items, the metadata, segment means
and static record of a rate readings file; :mod:`.screening` the screening of a rate
readings file; :mod:`.simulate` the virtual rate bench's hooks; :mod:`.certificate_zh` the
Chinese of the budget sources both state. The item types, the GUM budget, the item loop and
the per-item renderer they use are gonio's shared ones (re-exported by ``gonio.kit``).
"""


def rate_specification(package: str, **fields):
    """The :class:`~gonio.specs.Specification` of a rate specification in ``package``
    (``gonio.specs.<name>``): the hooks both share — its ``simulate`` module's programme
    runner written out (:mod:`.simulate`) or held in memory for the coverage study, its
    ``truth`` module, the rate study bench, the per-item renderer
    (:data:`gonio.specs.ITEM_RENDERER`), its ``certificate`` module (the certificate's
    content), the room temperature the readings measured (JJF 1535's reading,
    :func:`gonio.formats.rate_readings.room_temperature_measured`, unless ``fields`` name
    ``measured_conditions``) — plus
    ``fields`` (key, titles, clauses, protocol, calibrate, budget, the coverage stream and
    programme ``stream=``/``reduced=``, and ``study_bench_options=``, keywords of the study
    bench, :func:`.simulate.study_bench`)."""
    from gonio.specs import ITEM_RENDERER, Coverage, Specification, lazy

    run = lazy(f"{package}.simulate:simulate")
    coverage = Coverage(engine="items", stream=fields.pop("stream"),
                        reduced=fields.pop("reduced"),
                        study_bench=lazy("gonio.specs._rate_family.simulate:study_bench",
                                         **fields.pop("study_bench_options", {})),
                        options=frozenset({"cases"}), cases=dict(STUDY_CASES),
                        fixed_cases=frozenset({"worst", "cold"}))
    return Specification(
        simulate=lazy("gonio.specs._rate_family.simulate:write_simulation", run),
        run_trial=lazy("gonio.specs._rate_family.simulate:run_trial", run),
        truth=lazy(f"{package}.truth:truth"), coverage=coverage,
        outputs=ITEM_RENDERER, default_bench="mems-adxrs610",
        simulated_files=("readings.csv", "truth.json"),
        certificate_content=f"{package}.certificate",
        readings_columns=lazy("gonio.formats.rate_readings:read_columns"),
        measured_conditions=fields.pop("measured_conditions", lazy(
            "gonio.formats.rate_readings:room_temperature_measured")),
        calibrate_options=frozenset({"protocol", "dcc"}),
        arguments={"validate": "gonio.specs._rate_family:add_validate_options"}, **fields)


#: The cases of the rate specifications' coverage study (``gonio validate --cases``):
#: how the study bench's equipment is set per trial (:meth:`gonio.bench.rate_gyro.RateBench.for_trial`).
STUDY_CASES = {
    "typeb": "every Type B effect of the equipment the budgets carry drawn per trial "
             "(gonio.bench.equipment.draw_equipment): the table's rate error and the "
             "voltmeter's gain normal with their certificates' u, the chamber's deviation "
             "per set point uniform within +-2 C, the fixture misalignment uniform within "
             "+-0.05 deg, the gyro's place in the volume, the phases of the chamber's "
             "fluctuation and of the table's ripple",
    "worst": "every BOUNDED Type B effect at its bound, all at once "
             "(gonio.bench.equipment.worst_equipment, WORST_RULE): the chamber's deviation "
             "+2 C at every set point above the gyro's reference temperature and -2 C at or "
             "below it (every temperature span across it stretched); the chamber's "
             "fluctuation and uniformity and the table's ripple at Table 2's 1 C, 2 C and "
             "0.05 %, the gyro's place in the volume at +-1 C with the deviation's sign at "
             "each set point; the bench states no certificate u for its rate table, so the "
             "readings carry none, the budgets take Table 2's 0.05 % as a rectangular bound "
             "and the table's rate error sits at +0.05 %; the fixture misalignment at "
             "+-0.05 deg with the sign of the gyro's cross-axis sensitivity; the voltmeter's "
             "gain (a normal certificate: its 2u is not a bound) and the two phases drawn "
             "per trial as in typeb",
    "cold": "as worst, with the gyro COLD at every set point (gonio.bench.equipment."
            "cold_equipment): the chamber's deviation -2 C and the gyro's place at -1 C "
            "(half Table 2's uniformity) at every set point, the static record's included, "
            "the chamber's fluctuation at the bench's own amplitude: the sign worst does not "
            "reach for the items read at one temperature whose reading falls with it (IEC "
            "62047-20 5.4.5's noise items, the white level read low)",
}


def add_validate_options(group) -> None:
    """The rate specifications' ``gonio validate`` option: ``--cases`` (the study's cases,
    :data:`STUDY_CASES`; the same option as the optical draft's bench cases)."""
    from gonio.analysis.cases import add_cases_option

    add_cases_option(group)
