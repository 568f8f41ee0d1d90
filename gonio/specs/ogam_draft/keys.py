"""The draft's item keys, in a module that imports nothing: loading ``SPEC`` (``gonio --help``
lists every specification's commands) reads them without importing the analysis."""

#: The seven characteristics of clause 7, in Annex B order (the one copy of this list).
ITEM_KEYS: tuple[str, ...] = ("scale_factor", "scale_factor_nonlinearity", "zero_stability",
                              "angle_deviation", "repeatability", "rate_consistency",
                              "pointing_consistency")

#: The items that cannot be negative by their definition: a range of scale factors (7.2), a
#: dispersion of zero readings (7.3), a range of deviations (7.5, 7.6, 7.7). An instrument's
#: stored or a laboratory file's upper limit below zero for one is refused
#: (``Specification.nonnegative_items``); with the physical budget each is also stated with
#: its upper bound where U exceeds the value (``gonio.specs.ogam_draft.item_uncertainty``).
NONNEGATIVE_KEYS: tuple[str, ...] = ("scale_factor_nonlinearity", "zero_stability",
                                     "repeatability", "rate_consistency",
                                     "pointing_consistency")
