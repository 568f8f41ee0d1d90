"""The draft's item keys, in a module that imports nothing: loading ``SPEC`` (``gonio --help``
lists every specification's commands) reads them without importing the analysis."""

#: The seven characteristics of clause 7, in Annex B order (the one copy of this list).
ITEM_KEYS: tuple[str, ...] = ("scale_factor", "scale_factor_nonlinearity", "zero_stability",
                              "angle_deviation", "repeatability", "rate_consistency",
                              "pointing_consistency")
