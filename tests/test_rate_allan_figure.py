"""The Allan figure of a rate certificate says which number is certified (leftover 5 of the
last stop): IEC 62047-20 certifies the ARW of a slope −½ line read at 1 h (5.4.5.2) and the
bias instability from the floor (5.4.5.3), not the five-term fit's N and B drawn beside them
(the legend showed "N → 1.791 °/√h" beside a stated 1.786). JJF 1535's ARW is the fit's N.

The figures are drawn from synthetic results whose numbers are known here: the certified line
must be N/√τ with N = 60 × the certified ARW (IEEE 952 C.1, closed form)."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from gonio.report.rate_figures import draw_allan
from gonio.result.model import Item, Result, Uncertainty

U_ARW = Uncertainty([], 0.015, 0.030, 1.99, 77)     # as the IEC demo: 1.786 ± 0.030
U_BI = Uncertainty([], 5.5, 11.0, 1.99, 73)

TAU = np.logspace(-1, 3, 25)


def _fit(arw_deg_sqrt_h: float, b_dph: float) -> dict:
    return {"Q": 0.0, "N": 60.0 * arw_deg_sqrt_h, "B": b_dph, "K": 0.0, "R": 0.0,
            "arw_deg_sqrt_h": arw_deg_sqrt_h, "bias_instability_dph": b_dph}


def _allan(fit: dict) -> dict:
    adev = fit["N"] / np.sqrt(TAU) + 0.664 * fit["B"]
    return {"tau_s": TAU.tolist(), "adev_dph": adev.tolist(), "ci_low": (0.9 * adev).tolist(),
            "ci_high": (1.1 * adev).tolist()}


def _legend(result) -> tuple[list[str], Figure]:
    fig = Figure()
    draw_allan(fig, fig.add_gridspec(1, 1)[0], result, {})
    ax = fig.axes[0]
    return [t.get_text() for t in ax.get_legend().get_texts()], fig


def _iec(arw_value: float, bi_value: float) -> Result:
    fit = _fit(1.791431, 25.96)
    items = {"arw": Item("arw", "angular random walk", "5.4.5.2", "°/√h", arw_value,
                         uncertainty=U_ARW),
             "bias_instability": Item("bias_instability", "bias instability", "5.4.5.3", "°/h",
                                      bi_value, uncertainty=U_BI,
                                      details={"allan": _allan(fit), "fit": fit})}
    return Result("iec62047-20", "IEC", items, {}, {})


def test_iec_legend_marks_the_fit_as_drawn_and_draws_the_certified_arw():
    texts, fig = _legend(_iec(1.7856603, 30.23))
    fit_label = next(t for t in texts if "five-term" in t)
    assert "not certified" in fit_label and "1.791" in fit_label, texts
    cert = [t for t in texts if "certified ARW 1.786" in t and "5.4.5.2" in t]
    assert len(cert) == 1, texts
    assert any("certified bias instability 30" in t and "5.4.5.3" in t for t in texts), texts
    line = next(ln for ln in fig.axes[0].lines if ln.get_label() == cert[0])
    x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
    assert y * np.sqrt(x) / 60.0 == pytest.approx(1.7856603, rel=1e-12)


def test_legend_names_the_fit_certified_where_it_is():
    """The same estimator (JJF 1535: the ARW is the fit's N): one plain fit line, said to be
    the certified ARW, no second line."""
    fit = _fit(1.794293, 18.5)
    items = {"angle_random_walk": Item("angle_random_walk", "angle random walk ARW", "7.2.13",
                                       "°/√h", 1.794293, uncertainty=U_ARW,
                                       details={"allan": _allan(fit), "fit": fit})}
    texts, _ = _legend(Result("jjf1535-2015", "JJF", items, {}, {}))
    fit_label = next(t for t in texts if "five-term" in t)
    assert "not certified" not in fit_label and "certified ARW, 7.2.13" in fit_label, texts
    assert "N/√τ" in texts and not any("certified ARW 1" in t for t in texts), texts


def test_iec_with_the_fit_equal_to_the_certified_values_has_no_warning():
    texts, _ = _legend(_iec(1.791431, 25.96))
    assert not any("not certified" in t or "bias instability" in t for t in texts), texts
