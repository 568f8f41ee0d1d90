"""Protocols: the specifications' procedures as validated data (TOML → dataclasses).

:mod:`gonio.protocol.model` holds the draft's sections and the loader;
:mod:`gonio.protocol.sections` the optional sections (equal division, tilt
estimate), registered on import. This layer sits below the bench and the
reduction, which both read a protocol; it imports only physics and formats.
"""

from gonio.protocol.model import (ORIENTATIONS, AnnexA, Conditions, Protocol, RotationItem, Round,
                                  Session, ZeroStability, load_protocol, parse_protocol,
                                  register_section)
from gonio.protocol import sections  # noqa: F401  (registers the optional sections)

__all__ = ["ORIENTATIONS", "AnnexA", "Conditions", "Protocol", "RotationItem", "Round", "Session", "ZeroStability",
           "load_protocol", "parse_protocol", "register_section", "sections"]
