"""The one result model every specification returns.

This package is being built up: :mod:`gonio.result.findings` holds the screening
findings that every specification's ``screen(readings)`` returns; :mod:`gonio.result.statement`
the one rule by which every output states a value with its uncertainty (GUM 7.2.6); the item and result
classes (``Item``, ``Result``, budget rows, conformity) join it in ``gonio.result.model``;
:mod:`gonio.result.gum` an item's GUM budget and :mod:`gonio.result.items` the one item loop.
It sits low in the layers (beside ``gonio.protocol``): specifications, analyses, the
report and the pipeline import it; it imports only the ground floor, ``gonio.formats`` and
the domain-free ``uncertainty`` engine.
"""

from gonio.result.findings import ACTIONS, Finding, findings_to_json

__all__ = ["ACTIONS", "Finding", "findings_to_json"]
