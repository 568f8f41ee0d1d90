"""Callers tell errors apart by their type, never by parsing their message: the
:class:`gonio.errors.GonioError` subclasses are raised where a caller needs to know the kind,
and no module of gonio looks inside a GonioError's text to decide what to do."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gonio.errors import (GonioError, MissingColumnError, NotFoundError, TooManyAttemptsError,
                          check_header)
from gonio.specs.ogam_draft.protocol import load_protocol

ROOT = Path(__file__).resolve().parents[1]
#: ``"…" in exc.message``, ``"…" in str(exc)``, ``exc.message.startswith(…)``: a decision
#: taken on the words of an error.
PARSES_MESSAGE = re.compile(
    r"""["'][^"']*["']\s+(?:not\s+)?in\s+(?:str\()?\w*(?:exc|err)\w*(?:\.message)?\)?"""
    r"""|(?:exc|err)\w*\.message\.(?:startswith|endswith|find|split)\(""")


def test_kinds_are_types():
    with pytest.raises(NotFoundError, match="protocol file not found: no-such-protocol"):
        load_protocol("no-such-protocol")
    with pytest.raises(MissingColumnError, match="column time_s: missing required column"):
        check_header(["test"], ["test", "time_s"], file="r.csv", line=3)
    for kind in (NotFoundError, MissingColumnError, TooManyAttemptsError):
        assert issubclass(kind, GonioError)       # the CLI still prints one line, exit 2


#: The one place that reads an exception's text: tomllib's (a third-party exception that gives
#: no line number for a document cut short, on Python 3.11).
THIRD_PARTY_TEXT = {"gonio/formats/toml.py"}


def test_no_module_decides_on_an_error_message():
    found = [f"{p.relative_to(ROOT)}:{n}: {line.strip()}"
             for p in sorted((ROOT / "gonio").rglob("*.py"))
             if p.relative_to(ROOT).as_posix() not in THIRD_PARTY_TEXT
             for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
             if PARSES_MESSAGE.search(line)]
    assert found == []
    # the pattern finds what it is for
    assert PARSES_MESSAGE.search('if "not found" not in exc.message:')
    assert PARSES_MESSAGE.search('code = 429 if "too many" in str(exc) else 401')
    assert PARSES_MESSAGE.search('if opt is None or exc.message.startswith("--"):')
    assert not PARSES_MESSAGE.search('raise GonioError(f"{opt}: {exc.message}") from None')
