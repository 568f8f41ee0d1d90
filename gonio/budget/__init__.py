"""Budget assembly shared by every specification: components beyond a standard's own lines.

The generic GUM/Monte Carlo engine is the top-level :mod:`uncertainty` package;
each specification's own budget (the draft's Annex A, JJF 1535 Annex A) lives in
its package under :mod:`gonio.specs`. This layer holds what several budgets and
the validation share (:mod:`gonio.budget.extra`).
"""
