"""Reduction: a continuous stream → readings (finding the table's rests, matching the protocol).

>>> from gonio.reduce import reduce_stream, find_rests
"""

from gonio.reduce.stream import Reduction, Rest, RestFinder, find_rests, reduce_stream

__all__ = ["Reduction", "Rest", "RestFinder", "find_rests", "reduce_stream"]
