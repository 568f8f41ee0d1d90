"""Example virtual instruments and tables (TOML)."""
