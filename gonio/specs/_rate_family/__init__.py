"""What the rate-gyro specifications (JJF 1535-2015, IEC 62047-20) share.

A package whose name starts with ``_`` is no specification: it is the common ground of a
family of them, the one place two specifications may both import (one specification never
imports another; tests/test_layers.py). :mod:`.formulas` holds the rate arithmetic both
documents use; :mod:`.rate_records` the records, the per-item GUM wrapper and segment means
of a rate readings file.
"""


def rate_specification(package: str, **fields):
    """The :class:`~gonio.specs.Specification` of a rate specification in ``package``
    (``gonio.specs.<name>``): the hooks both share — its ``simulate`` module's programme
    runner written out (:mod:`.simulate`) or held in memory for the coverage study, its
    ``truth`` module, the rate study bench, the per-item renderer (:mod:`.outputs`), its
``certificate`` module (the certificate's content) — plus
    ``fields`` (key, titles, clauses, protocol, calibrate, budget, the coverage stream and
    programme ``stream=``/``reduced=``)."""
    from gonio.specs import Coverage, Specification, lazy

    run = lazy(f"{package}.simulate:simulate")
    coverage = Coverage(engine="items", stream=fields.pop("stream"),
                        reduced=fields.pop("reduced"),
                        study_bench=lazy("gonio.specs._rate_family.simulate:study_bench"))
    return Specification(
        simulate=lazy("gonio.specs._rate_family.simulate:write_simulation", run),
        run_trial=lazy("gonio.specs._rate_family.simulate:run_trial", run),
        truth=lazy(f"{package}.truth:truth"), coverage=coverage,
        outputs="gonio.specs._rate_family.outputs", default_bench="mems-adxrs610",
        certificate_content=f"{package}.certificate",
        calibrate_options=frozenset({"protocol", "dcc"}), **fields)
