"""The triad's item keys, in a module that imports nothing: loading ``SPEC`` (``gonio --help``
lists every specification's commands) reads them without importing the analysis."""

AXES = "xyz"
#: The off-diagonal pairs (gyro, axis about which it is sensitive).
OFFDIAG = ("xy", "xz", "yx", "yz", "zx", "zy")

ALIGNMENT_KEYS = ([f"M_{a}{b}" for a in AXES for b in AXES] + [f"b_{a}" for a in AXES]
                  + [f"S_{n}" for n in OFFDIAG] + [f"L_{n}" for n in OFFDIAG]
                  + ["averaging_time"])


#: The thermal model's certified items (:func:`thermal_items`): the value of each model at
#: the programme's chamber set points t1, t2 … (ascending) and supply levels v1, v2 …
#: (ascending) — ``K_<gyro>_t<i>_v<j>``, ``b_<gyro>_t<i>_v<j>``, ``ARW_<gyro>_t<i>``.
#: (1–99 set points, 1–99 supply levels; fnmatch has no "digits only" repetition).
_INDEX = ("[1-9]", "[1-9][0-9]")
THERMAL_POINT_KEYS = tuple(f"{m}_[xyz]_t{i}_v{j}" for m in ("K", "b") for i in _INDEX
                           for j in _INDEX) + tuple(f"ARW_[xyz]_t{i}" for i in _INDEX)

#: The items that cannot be negative: each gyro's angle random walk at a set point (a noise
#: coefficient), marked so by the thermal model (:func:`thermal_items`) and stated with its
#: upper bound where U exceeds it; an instrument's stored or a laboratory file's upper limit
#: below zero for one is refused (``Specification.nonnegative_items``).
NONNEGATIVE_KEYS = tuple(f"ARW_[xyz]_t{i}" for i in _INDEX)
