"""What the rate-gyro specifications (JJF 1535-2015, IEC 62047-20) share.

A package whose name starts with ``_`` is no specification: it is the common ground of a
family of them, the one place two specifications may both import (one specification never
imports another; tests/test_layers.py). :mod:`.formulas` holds the rate arithmetic both
documents use; :mod:`.rate_records` the context of their items, the metadata, segment means
and static record of a rate readings file; :mod:`.screening` the screening of a rate
readings file; :mod:`.simulate` the virtual rate bench's hooks; :mod:`.certificate_zh` the
Chinese of the budget sources both state. The item types, the GUM budget, the item loop and
the per-item renderer they use are gonio's shared ones (re-exported by ``gonio.kit``).
"""


def rate_specification(package: str, **fields):
    """The :class:`~gonio.specs.Specification` of a rate specification in ``package``
    (``gonio.specs.<name>``): the hooks both share — its ``simulate`` module's programme
    runner written out (:mod:`.simulate`) or held in memory for the coverage study, its
    ``truth`` module, the rate study bench, the per-item renderer
    (:data:`gonio.specs.ITEM_RENDERER`), its ``certificate`` module (the certificate's
    content) — plus
    ``fields`` (key, titles, clauses, protocol, calibrate, budget, the coverage stream and
    programme ``stream=``/``reduced=``, and ``study_bench_options=``, keywords of the study
    bench, :func:`.simulate.study_bench`)."""
    from gonio.specs import ITEM_RENDERER, Coverage, Specification, lazy

    run = lazy(f"{package}.simulate:simulate")
    coverage = Coverage(engine="items", stream=fields.pop("stream"),
                        reduced=fields.pop("reduced"),
                        study_bench=lazy("gonio.specs._rate_family.simulate:study_bench",
                                         **fields.pop("study_bench_options", {})))
    return Specification(
        simulate=lazy("gonio.specs._rate_family.simulate:write_simulation", run),
        run_trial=lazy("gonio.specs._rate_family.simulate:run_trial", run),
        truth=lazy(f"{package}.truth:truth"), coverage=coverage,
        outputs=ITEM_RENDERER, default_bench="mems-adxrs610",
        certificate_content=f"{package}.certificate",
        readings_columns=lazy("gonio.formats.rate_readings:read_columns"),
        calibrate_options=frozenset({"protocol", "dcc"}), **fields)
