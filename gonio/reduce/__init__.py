"""Rests of a continuous stream: where the table (or, without its encoder, the gyro) dwells;
shared by a specification's reduction of a stream to readings and the noise analysis of a
stream's static record.

>>> from gonio.reduce import find_rests
"""

from gonio.reduce.rests import MemorySamples, Rest, RestFinder, find_rests, rests_of

__all__ = ["MemorySamples", "Rest", "RestFinder", "find_rests", "rests_of"]
