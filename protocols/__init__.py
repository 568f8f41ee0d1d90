"""The draft's procedures and example benches as data (TOML); see README."""
