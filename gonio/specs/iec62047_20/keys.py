"""The IEC 62047-20 characteristics (clauses 5.1–5.6) without their computation, so that
loading ``SPEC`` stays light; :data:`.items.ITEMS` pairs each row with its function."""

#: The key of the specification (``--spec``, the readings' ``# spec:`` line).
KEY = "iec62047-20"

#: (key, title, clause) of every item, in the specification's order (the one copy of this list).
ITEM_ROWS = (
    ("scale_factor", "scale factor a_BASE", "5.1.3.1"),
    ("initial_sf_variation", "initial scale-factor variation", "5.1.3.2"),
    ("sf_temperature_coefficient", "scale-factor temperature coefficient", "5.1.3.4"),
    ("ratiometric_error", "scale-factor ratiometric error", "5.1.3.5"),
    ("linearity", "linearity", "5.1.3.6"),
    ("sf_stability", "scale-factor stability", "5.1.3.7"),
    ("symmetry", "scale-factor symmetry", "5.1.3.8"),
    ("cross_axis", "cross-axis sensitivity", "5.2"),
    ("bias", "bias N_bias", "5.3.3.1"),
    ("initial_bias_variation", "initial bias variation", "5.3.3.2"),
    ("bias_repeatability", "bias repeatability", "5.3.3.4"),
    ("bias_drift_after_power_on", "bias drift after power on", "5.3.3.5"),
    ("bias_temperature_coefficient", "bias temperature coefficient", "5.3.3.6"),
    ("bias_ratiometric_error", "bias ratiometric error", "5.3.3.3"),
    ("bias_hysteresis", "bias hysteresis", "5.3.3.7"),
    ("g_sensitivity", "linear g sensitivity", "5.3.3.8"),
    ("startup_time", "start-up time", "5.3.3.9"),
    ("inband_noise", "in-band noise", "5.4.5.1 b)"),
    ("broadband_noise", "broadband noise", "5.4.5.1 c)"),
    ("arw", "angular random walk", "5.4.5.2"),
    ("bias_instability", "bias instability", "5.4.5.3"),
    ("frequency_band", "frequency band", "5.5"),
    ("resolution", "resolution", "5.6"),
)

#: The items stated as a largest magnitude max_i |x_i| (5.1.3.5, 5.1.3.6, 5.2, 5.3.3.3 and 5.3.3.8:
#: the statement of
#: ``gonio.result.gum.max_magnitude_statement``, marked ``K_SOURCE_MAX_MAGNITUDE``): a
#: laboratory file's limit for them must be symmetric, checked before any work
#: (``Specification.magnitude_extremes``). Conformity also knows an item of that kind by its
#: statement's marker once calibrated, and a test (tests/test_conformity_stated_interval.py)
#: checks that this list names exactly the items a calibration states so.
MAGNITUDE_KEYS = ('ratiometric_error', 'linearity', 'cross_axis', 'bias_ratiometric_error',
                  'g_sensitivity')


#: Items that are non-negative by their definition (a maximum of absolute values, a standard
#: deviation, a noise coefficient, a time, a threshold): where U exceeds the value the
#: statement rule adds the upper bound (GUM 7.2.6 / ISO 80000; gonio.result.statement); an
#: instrument's stored or a laboratory file's upper limit below zero for one is refused
#: (``Specification.nonnegative_items``).
NONNEGATIVE = frozenset({"ratiometric_error", "bias_ratiometric_error", "cross_axis", "g_sensitivity", "linearity", "sf_stability", "bias_repeatability", "bias_drift_after_power_on", "bias_hysteresis", "arw", "bias_instability", "inband_noise", "frequency_band", "startup_time", "broadband_noise", "resolution"})
