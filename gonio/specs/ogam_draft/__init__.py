"""The optical-gyro angle-measuring instrument draft (JJF xxxx 光学陀螺测角仪校准规范, draft for comment).

:mod:`~gonio.specs.ogam_draft.items` the seven characteristics of clause 7;
:mod:`~gonio.specs.ogam_draft.calibration` the whole calibration path (``SPEC.calibrate``:
readings or stream → items, Annex A budget, item uncertainties);
:mod:`~gonio.specs.ogam_draft.budget` the Annex A budget; :mod:`.simulate` the virtual bench;
:mod:`.truth` the true values from the bench (``SPEC.truth``); :mod:`.study` the coverage
study of ``gonio validate`` (its trial, truths and bench cases) and :mod:`.item_coverage`
what each item's coverage is checked against; :mod:`.outputs` the rendering (results,
tables, certificate, DCC, demo); :mod:`.commands` its own ``gonio`` sub-commands (``reduce``,
``tilt``, ``tilt-estimate``, ``eda``); :mod:`.acquisition` its programme on a laboratory's
table and acquisition module (``SPEC.acquire``, ``gonio acquire``) and :mod:`.served` its
virtual bench served as those instruments (``SPEC.serve``, ``gonio bench serve``).
What only this draft uses lives here too: :mod:`.protocol` (its protocol model and loader,
``SPEC.load_protocol``), :mod:`.readings` (its readings file), :mod:`.bench` (the goniometer
on a precision rotary table), :mod:`.reduce` and :mod:`.override` (stream → readings),
:mod:`.tilt`, :mod:`.coupling` and :mod:`.compensation` (its physics), :mod:`.table_periodic`
(one periodic table error's worst order, for the budgets' table lines), :mod:`.budget_extra`,
:mod:`.equal_division`, :mod:`.tilt_estimate` and :mod:`.zero_stability_noise`. The
clause-by-clause reading is ``docs/draft-readings.md``.
"""

from gonio.specs import Coverage, Specification, lazy
from gonio.specs.ogam_draft.keys import ITEM_KEYS, NONNEGATIVE_KEYS

SPEC = Specification(
    key="ogam-draft",
    title_en="Calibration Specification for Optical Gyroscope Angle Measuring Instruments "
             "(draft for comment)",
    title_zh="光学陀螺测角仪校准规范(征求意见稿)",
    clause_doc="docs/draft-readings.md",
    clauses=("7.1", "7.2", "7.3", "7.4", "7.5", "7.6", "7.7"),
    item_keys=tuple(ITEM_KEYS),
    # E (7.4) = ± max|E_i|: an extreme of magnitudes, compared with a symmetric limit only
    magnitude_extremes=("angle_deviation",),
    nonnegative_items=NONNEGATIVE_KEYS,
    default_protocol="ogam-draft",
    default_bench="rlg",
    load_protocol=lazy("gonio.specs.ogam_draft.protocol:load_protocol"),
    calibrate=lazy("gonio.specs.ogam_draft.calibration:calibrate"),
    screen=lazy("gonio.specs.ogam_draft.calibration:screen"),
    readings_columns=lazy("gonio.specs.ogam_draft.readings:read_columns"),
    # the chamber temperature the readings logged, compared with the laboratory's statement
    measured_conditions=lazy("gonio.specs.ogam_draft.readings:temperature_measured"),
    named_inputs=lazy("gonio.specs.ogam_draft.static_record:named_inputs"),
    simulate=lazy("gonio.specs.ogam_draft.simulate:simulate"),
    simulated_files=("readings.csv", "truth.json"),
    truth=lazy("gonio.specs.ogam_draft.truth:truth"),
    budget=lazy("gonio.specs.ogam_draft.budget:annex_a_budget"),
    acquire=lazy("gonio.specs.ogam_draft.acquisition:acquire_programme"),
    serve=lazy("gonio.specs.ogam_draft.served:serve"),
    coverage=Coverage(engine="cases", stream=0,
                      study=lazy("gonio.specs.ogam_draft.study:plan_study"),
                      options=frozenset({"cases", "truth", "extra_components", "u_scale",
                                         "sample_rate_hz", "all_items", "resume",
                                         "monte_carlo"})),
    read_table_calibration=lazy("gonio.specs.ogam_draft.table_calibration:"
                                "read_table_calibration"),
    outputs="gonio.specs.ogam_draft.outputs",
    simulate_options=frozenset({"table", "stream", "stream_format"}),
    calibrate_options=frozenset({"protocol", "dcc", "budget", "tilt", "gyro_type",
                                 "table_calibration"}),
    budget_options=frozenset({"table_mpe_arcsec", "tilt_deg", "zero_stability_dph",
                              "duration_min", "repeatability_arcsec", "k",
                              "monte_carlo_trials", "seed"}),
    serve_options=frozenset({"range_deg", "warm_up_s"}),
    arguments={"calibrate": "gonio.specs.ogam_draft.commands:add_calibrate_options",
               "simulate": "gonio.specs.ogam_draft.commands:add_simulate_options",
               "budget": "gonio.specs.ogam_draft.commands:add_budget_options",
               "validate": "gonio.specs.ogam_draft.commands:add_validate_options",
               "bench serve": "gonio.specs.ogam_draft.commands:add_serve_options"},
    commands=(("eda", "gonio.specs.ogam_draft.commands:add_eda"),
              ("reduce", "gonio.specs.ogam_draft.commands:add_reduce"),
              ("tilt", "gonio.specs.ogam_draft.commands:add_tilt"),
              ("tilt-estimate", "gonio.specs.ogam_draft.commands:add_tilt_estimate")),
)
