"""Analyses on reduced readings (noise, tilt estimate, equal division, conformity)."""
