"""A coverage study's workers stay light (issue 26): a trial of the default study and of
the item study runs without importing SymPy (its import was most of the ~12 s start-up),
and the additive budgets' SymPy-free models give the same GUM numbers, bit for bit, as
the sympy expressions they replace (the study's validation.json is byte-identical)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from uncertainty import from_u, propagate, type_b
from uncertainty.propagation import LinearModel

ROOT = Path(__file__).resolve().parents[1]


def test_a_study_trial_does_not_import_sympy(tmp_path):
    code = textwrap.dedent("""
        import sys
        from dataclasses import replace
        from gonio.specs.ogam_draft.bench import load_bench
        from gonio.specs.ogam_draft.study import run_trial, validation_protocol
        import gonio.pipeline.validate
        assert "sympy" not in sys.modules, "importing the study code imported sympy"
        run_trial(validation_protocol(), replace(load_bench("rlg"), sample_rate_hz=100.0), 3)
        assert "sympy" not in sys.modules, "a trial imported sympy"
        print("ok")
    """)
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]


@pytest.mark.parametrize("value,coeffs", [(0.0, (-1.0, 1.0, 1.0, 1.0)),
                                          (3600.2, (1.0, 1.0, 1.0, 1.0)),
                                          (-0.0123, (2.5, -1e-3, 1.0, 0.5))])
def test_linear_model_equals_its_sympy_expression(value, coeffs):
    names = ("P", "phi_e", "B_E", "r")
    qs = [type_b("P", 0.0, 0.5, "rectangular"), type_b("phi_e", 0.0, 0.13, "rectangular"),
          type_b("B_E", 0.0, 0.07, "triangular"), from_u("r", 0.0, 0.09, dof=5)]
    m = LinearModel(value, coeffs, names)
    a = propagate(m, qs, k=None, p=0.95)
    b = propagate(m.to_sympy(), qs, k=None, p=0.95)
    assert a == b
    # inputs in another order than the model's names: compiled through the expression
    c = propagate(m, qs[::-1], k=None, p=0.95)
    assert c.u_c == pytest.approx(a.u_c, rel=1e-15) and c.value == a.value
