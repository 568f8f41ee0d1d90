"""The one exception type a user can cause, and helpers to say *where*.

Every error a user can provoke with an input (a file, a protocol, a bench, a
command-line value) is a :class:`GonioError` whose message names the place:
file, line, column or key, and what was expected. The CLI prints it on one line
and exits with code 2.
"""

from __future__ import annotations

from pathlib import Path


class GonioError(ValueError):
    """A user-caused error; the message names what was wrong and where.

    >>> str(GonioError("expected a number", file="r.csv", line=4, column="time_s"))
    'r.csv:4: column time_s: expected a number'
    >>> str(GonioError("unknown key", file="p.toml", key="scale_factor.rate"))
    'p.toml: key scale_factor.rate: unknown key'
    """

    def __init__(self, message: str, *, file: str | Path | None = None,
                 line: int | None = None, column: str | None = None,
                 key: str | None = None):
        self.message = message
        self.file = None if file is None else str(file)
        self.line = line
        self.column = column
        self.key = key
        super().__init__(self._format())

    def _format(self) -> str:
        where = ""
        if self.file is not None:
            where = self.file
            if self.line is not None:
                where += f":{self.line}"
            where += ": "
        elif self.line is not None:
            where = f"line {self.line}: "
        if self.column is not None:
            where += f"column {self.column}: "
        if self.key is not None:
            where += f"key {self.key}: "
        return (where + self.message).replace("\n", " ")
