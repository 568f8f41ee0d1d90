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

#: The items stated as a largest magnitude max_i |x_i| (7.2.2 K_n, 7.2.3 K_a, 7.2.5 K_t, 7.2.12
#: B_g and 7.2.14 B_t: the statement of
#: ``gonio.result.gum.max_magnitude_statement``, marked ``K_SOURCE_MAX_MAGNITUDE``): a
#: laboratory file's limit for them must be symmetric, checked before any work
#: (``Specification.magnitude_extremes``). Conformity also knows an item of that kind by its
#: statement's marker once calibrated, and a test (tests/test_conformity_stated_interval.py)
#: checks that this list names exactly the items a calibration states so.
MAGNITUDE_KEYS = ('nonlinearity', 'asymmetry', 'sf_temperature_sensitivity', 'g_sensitivity',
                  'bias_temperature_sensitivity')


#: Items that are non-negative by their definition (a maximum of absolute values, a standard
#: deviation, a noise coefficient, a time, a threshold): where U exceeds the value the
#: statement rule adds the upper bound (GUM 7.2.6 / ISO 80000; gonio.result.statement); an
#: instrument's stored or a laboratory file's upper limit below zero for one is refused
#: (``Specification.nonnegative_items``).
NONNEGATIVE = frozenset({"g_sensitivity", "nonlinearity", "asymmetry", "sf_repeatability", "sf_temperature_sensitivity", "threshold", "resolution", "bias_stability", "bias_repeatability", "warmup_time", "angle_random_walk", "bias_temperature_sensitivity", "bandwidth"})
