"""File formats: readings, streams, counters, metadata, override files, TOML schemas.

Readers validate and return plain data (dataclasses, DataFrames); writers go
through :mod:`gonio.atomic`. Nothing here imports the bench, the analyses or the
report (``docs/formats.md``).
"""
