"""Noise analysis: Allan-family deviations, their confidence intervals, the gyro noise-model fit.

The estimators and the fit are in :mod:`gonio.analysis.noise.allan`; unit
conversions of the noise coefficients are in :mod:`gonio.units`; figures in
:mod:`gonio.report`.
"""

from gonio.analysis.noise.allan import *  # noqa: F401,F403
from gonio.analysis.noise.allan import __all__  # noqa: F401
