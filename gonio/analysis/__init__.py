"""Analyses shared by the specifications: noise (Allan family), equal-division averaging,
in-situ tilt estimate, decision rules and conformity (:mod:`gonio.analysis.conformity`).

Each takes readings or records (plain data) and returns result dataclasses; no
plotting here (figures are drawn in :mod:`gonio.report`).
"""
