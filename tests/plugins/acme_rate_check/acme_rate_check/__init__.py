"""ACME RC-1, "Rate-table check of a rate gyro": a laboratory's in-house procedure written as
a gonio specification plug-in (docs/writing-a-specification.md is its walk-through).

The procedure: the gyro, input axis vertical, is turned at a few table rates Ω_j in both
directions (clause 4.1); the mean output at each rate is recorded. Items: the scale factor K
(4.2, the least-squares slope of output on rate), the bias B (4.3, the intercept divided
by K, in °/s, the Earth rate not removed) and the scale-factor asymmetry A (4.4, in ppm).
Uncertainties by the GUM from the calibration's own data (clause 5), checked by Monte Carlo
on request. Tolerance (clause 6): |B| ≤ 1 °/s.
"""

from gonio.kit import ITEM_RENDERER, Coverage, Specification, lazy

from acme_rate_check.items import ITEMS, calibrate, load_protocol, screen

KEY = "acme-rate-check"

SPEC = Specification(
    key=KEY,
    title_en="ACME RC-1 Rate-table check of a rate gyro (in-house procedure)",
    title_zh="ACME RC-1 速率陀螺速率转台检查（内部规程）",
    clause_doc="tests/plugins/acme_rate_check/README.md",
    clauses=tuple(item.clause for item in ITEMS),
    default_protocol=KEY,
    default_bench="acme-bench",
    load_protocol=load_protocol,
    calibrate=calibrate,
    screen=screen,
    # the simulation side is loaded on first use: calibrating a file never imports it
    simulate=lazy("acme_rate_check.simulate:simulate"),
    truth=lazy("acme_rate_check.simulate:truth"),
    run_trial=lazy("acme_rate_check.simulate:run_trial"),
    coverage=Coverage(engine="items", stream=101),
    # gonio's renderer of a per-item result: results.json, summary, certificate, DCC
    outputs=ITEM_RENDERER,
    certificate_content="acme_rate_check.certificate",   # its headings and groups, as data
    calibrate_options=frozenset({"protocol", "dcc"}),
    item_keys=tuple(item.key for item in ITEMS),
    # the D-SI form of the units its items state that gonio's DCC does not know
    dcc_units={"ppm": r"\ppm"},
    # the tolerance its document gives (clause 6): decided where the lab file sets none
    default_limits=({"item": "bias", "mpe": 1.0, "source": "ACME RC-1 clause 6"},),
    # its own sub-command, added to gonio's command line through the registry
    commands=(("acme-programme", "acme_rate_check.commands:add_programme"),),
    # its own option of gonio simulate: the keyword its simulate takes, and the hook adding it
    simulate_options=frozenset({"samples"}),
    arguments={"simulate": "acme_rate_check.commands:add_simulate_options"},
)
