"""Unit constants (placeholder on the rate-gyro branch until the layout's gonio.units lands).

Only the one literal the rate-gyro code needs is written here; at the merge the
lead's ``gonio.units`` (which names the same constant ``S_PER_H``) replaces this file.
"""

#: Seconds per hour.
S_PER_H = 3600.0
