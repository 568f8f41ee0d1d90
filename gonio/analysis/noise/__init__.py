"""Allan-family noise analysis of gyro records (IEEE 952-1997 Annex C; NIST SP 1065).

=========================  =====================================================
:mod:`.allan`              estimators: overlapping/modified Allan, Hadamard, total
                           (gap-aware; every τ in O(N log² N))
:mod:`.edf`                Greenhall edf, noise identification, χ² intervals
:mod:`.fit`                five-term model per variance, bootstrap, sinusoid
:mod:`.covariance`         covariance of the estimates across τ (the fit's u)
:mod:`.markov`             five terms, flicker band-limited below a fitted T_lo (the ARW's)
:mod:`.record`             whole-record analysis and static-window selection
=========================  =====================================================

Plots are drawn in :mod:`gonio.report.noise_figures`; unit conversions are in
:mod:`gonio.units`. The public names of the submodules are re-exported here.
"""

from gonio.analysis.noise.allan import (  # noqa: F401
    INPUT_TYPES, KIND_METHODS, AllanResult, allan_deviation, angle_series,
    averaging_factors, hadamard_deviation, modified_allan_deviation, total_deviation,
)
from gonio.analysis.noise.edf import (  # noqa: F401
    chi2_interval, edf_for, edf_greenhall, edf_simple, edf_totdev, noise_id_b1,
    noise_id_lag1,
)
from gonio.analysis.noise.fit import (  # noqa: F401
    FLICKER_COEFF, FLICKER_FLOOR, HVAR_FLICKER_COEFF, HVAR_RRW_COEFF, MVAR_FLICKER_COEFF,
    MVAR_RRW_COEFF, SINE_PEAK_PER_AMPLITUDE, SINE_TAU_PER_PERIOD, TERMS, NoiseFit,
    SinusoidDetection, bootstrap_uncertainty, design_matrix, detect_sinusoid,
    fit_noise_model, model_adev, model_deviation, simulate_noise, sinusoid_adev,
)
from gonio.analysis.noise.markov import (  # noqa: F401
    MarkovFit, band_flicker_avar, fit_markov_model, markov_avar,
)
from gonio.analysis.noise.record import (  # noqa: F401
    StaticNoiseResult, StaticWindow, analyse_record, analyse_static, select_window,
    static_windows,
)

__all__ = [
    "INPUT_TYPES", "KIND_METHODS", "AllanResult", "allan_deviation", "angle_series",
    "averaging_factors", "hadamard_deviation", "modified_allan_deviation",
    "total_deviation", "chi2_interval", "edf_for", "edf_greenhall", "edf_simple",
    "edf_totdev", "noise_id_b1", "noise_id_lag1", "FLICKER_COEFF", "FLICKER_FLOOR",
    "HVAR_FLICKER_COEFF", "HVAR_RRW_COEFF", "MVAR_FLICKER_COEFF", "MVAR_RRW_COEFF",
    "SINE_PEAK_PER_AMPLITUDE", "SINE_TAU_PER_PERIOD", "TERMS", "NoiseFit",
    "SinusoidDetection", "bootstrap_uncertainty", "design_matrix", "detect_sinusoid",
    "fit_noise_model", "model_adev", "model_deviation", "simulate_noise", "sinusoid_adev",
    "StaticNoiseResult", "StaticWindow", "analyse_record", "analyse_static",
    "select_window", "static_windows", "MarkovFit", "fit_markov_model", "markov_avar",
    "band_flicker_avar",
]
