"""JJF 1535-2015 Table 3 as plain data, importing nothing: ``SPEC`` (loaded by
``gonio --help``) takes its keys and clauses from here; :data:`.items.ITEMS` adds the
function of each row."""

KEY = "jjf1535-2015"

#: (key, title, clause) of every item, in the specification's order (the one copy of this list).
ITEM_ROWS = (
    ("scale_factor", "scale factor K", "7.2.1"),
    ("nonlinearity", "scale-factor nonlinearity K_n", "7.2.2"),
    ("asymmetry", "scale-factor asymmetry K_a", "7.2.3"),
    ("sf_repeatability", "scale-factor repeatability K_r", "7.2.4"),
    ("sf_temperature_sensitivity", "scale-factor temperature sensitivity K_t", "7.2.5"),
    ("threshold", "threshold", "7.2.6"),
    ("resolution", "resolution", "7.2.7"),
    ("bias", "bias B_0", "7.2.8"),
    ("warmup_time", "warm-up time", "7.2.9"),
    ("bias_stability", "bias stability B_s", "7.2.10"),
    ("bias_repeatability", "bias repeatability B_r", "7.2.11"),
    ("g_sensitivity", "bias acceleration sensitivity B_g", "7.2.12"),
    ("angle_random_walk", "angle random walk ARW", "7.2.13"),
    ("bias_temperature_sensitivity", "bias temperature sensitivity B_t", "7.2.14"),
    ("bandwidth", "bandwidth B_w", "7.2.15"),
)
