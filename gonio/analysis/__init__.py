"""Analysis of reduced data: noise (Allan family), equal division, tilt estimation."""
