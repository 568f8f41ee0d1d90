"""What the rate-gyro specifications (JJF 1535-2015, IEC 62047-20) share.

A package whose name starts with ``_`` is no specification: it is the common ground of a
family of them, the one place two specifications may both import (one specification never
imports another; tests/test_layers.py). :mod:`.formulas` holds the rate arithmetic both
documents use; :mod:`.rate_records` the records, the per-item GUM wrapper and segment means
of a rate readings file.
"""
