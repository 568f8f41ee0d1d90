"""IEC 62047-20's static-record analysis (5.4) is cached per context, and a context copied
with a provisional a_BASE (``dataclasses.replace`` while a_BASE itself is being fitted)
shares the cache dict: the record converted with the provisional scale factor must never be
handed to the final one. Checked against the conversion written out here, (output − null)/a."""
from dataclasses import replace

import numpy as np
import pandas as pd

from gonio.specs.iec62047_20 import items as iec


def _context(a_base):
    rng = np.random.default_rng(11)
    n = 2000
    null, a = 2.5, 0.01          # output units; output per °/s
    rate_dps = rng.normal(0.0, 0.05, n)
    df = pd.DataFrame({"test": "static", "run": 0, "step": 0,
                       "time_s": np.arange(n) * 0.1, "output": null + a * rate_dps})
    return iec.Context(df=df, output_unit="V", null_output=null, latitude_deg=40.0,
                       protocol={}, a_typ=a, t_base_c=25.0, v_base=5.0, a_base=a_base)


def _rate(ctx):
    r = iec._static(ctx)[1]
    return np.asarray(r[:] if not isinstance(r, np.ndarray) else r)


def test_a_provisional_scale_factor_does_not_reach_the_final_record():
    ctx = _context(0.01)
    provisional = replace(ctx, a_base=0.02)
    assert provisional.cache is ctx.cache          # what makes the key matter
    _rate(provisional)
    expected_dph = (ctx.df["output"].to_numpy() - 2.5) / 0.01 * 3600.0
    np.testing.assert_allclose(_rate(ctx), expected_dph, rtol=1e-12)
    np.testing.assert_allclose(_rate(provisional), expected_dph / 2.0, rtol=1e-12)
