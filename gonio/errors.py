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
        text = " ".join((where + self.message).split())
        return text if len(text) <= 600 else text[:600] + f"… ({len(text)} characters)"


def first_of(problems: list) -> str:
    """The first of several problems, and how many more there are, for a one-line error.

    >>> first_of(["a missing", "b late", "c void"])
    'a missing (and 2 more)'
    >>> first_of(["a missing"])
    'a missing'
    """
    more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
    return f"{problems[0]}{more}"


class NotFoundError(GonioError):
    """A named input (a protocol, a bench, a file) does not exist: callers that try several
    places catch this one and let every other error through."""


class MissingColumnError(GonioError):
    """A required column is absent from a file's header (a reader that guesses a file's
    kind from its header catches this one)."""


class TooManyAttemptsError(GonioError):
    """An action refused for a while after too many failures (the login throttle)."""


#: Default largest input file, bytes (``GONIO_MAX_INPUT_BYTES`` overrides; see gonio.limits).
MAX_INPUT_BYTES: int = 2 * 1024 ** 3


def max_input_bytes() -> float:
    """The input size limit: ``GONIO_MAX_INPUT_BYTES`` if set (a number > 0), else 2 GiB."""
    import os

    text = os.environ.get("GONIO_MAX_INPUT_BYTES", "").strip()
    try:
        v = float(text) if text else float(MAX_INPUT_BYTES)
    except ValueError:
        raise GonioError(f"environment variable GONIO_MAX_INPUT_BYTES must be a number, got "
                         f"{text[:40]!r}") from None
    if not v > 0:
        raise GonioError("environment variable GONIO_MAX_INPUT_BYTES must be > 0")
    return v


def read_input(path: str | Path, what: str = "file", limit_bytes: float | None = None) -> bytes:
    """The bytes of an input file, refusing what is not a regular file or is too large.

    A FIFO, a device (``/dev/zero``), a socket or a folder is refused before any
    byte is read (opened non-blocking, so a FIFO never hangs); so is a file over
    ``limit_bytes`` (default: :func:`gonio.limits.limit` ``GONIO_MAX_INPUT_BYTES``).
    """
    check_input_file(path, what, limit_bytes)
    path = Path(path)
    try:
        return path.read_bytes()
    except OSError as exc:
        raise GonioError(f"cannot read {what}: {exc.strerror}", file=path) from None


def check_input_file(path: str | Path, what: str = "file",
                     limit_bytes: float | None = None) -> Path:
    """GonioError unless ``path`` is a regular file of at most ``limit_bytes`` bytes."""
    import os
    import stat

    if path is None or str(path).strip() == "":
        raise GonioError(f"{what}: empty file name")
    path = Path(path)
    if limit_bytes is None:
        limit_bytes = max_input_bytes()
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as exc:
        raise GonioError(f"cannot read {what}: {exc.strerror}", file=path) from None
    try:
        st = os.fstat(fd)
    finally:
        os.close(fd)
    if not stat.S_ISREG(st.st_mode):
        kind = ("a folder" if stat.S_ISDIR(st.st_mode) else "a FIFO" if stat.S_ISFIFO(st.st_mode)
                else "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode)
                else "a special file")
        raise GonioError(f"{what} is {kind}, not a regular file", file=path)
    if st.st_size > limit_bytes:
        raise GonioError(f"{what} is {st.st_size} bytes, over the limit of {int(limit_bytes)} "
                         "(GONIO_MAX_INPUT_BYTES)", file=path)
    return path


def read_utf8(path: str | Path, what: str = "file", limit_bytes: float | None = None) -> str:
    """A text file's content (UTF-8, BOM allowed); unreadable or non-UTF-8 → GonioError.

    The error names the file and, for a bad byte, its line. Special files and files
    over the size limit are refused before reading (:func:`read_input`).
    """
    path = Path(path)
    raw = read_input(path, what, limit_bytes)
    check_not_binary(raw, path)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise GonioError(f"not UTF-8 text (byte {exc.start})", file=path,
                         line=raw[:exc.start].count(b"\n") + 1) from None


#: Leading bytes of binary formats a text file is sometimes confused with.
MAGIC: tuple[tuple[bytes, str], ...] = (
    (b"PAR1", "a Parquet file (name it .parquet)"), (b"PK\x03\x04", "a ZIP archive (or .npz, .xlsx)"),
    (b"\x1f\x8b", "a gzip-compressed file"), (b"%PDF", "a PDF document"),
    (b"\x89PNG", "a PNG image"), (b"\x93NUMPY", "a NumPy array file"),
    (b"SQLite format 3", "an SQLite database"))


def binary_kind(head: bytes) -> str | None:
    """What a binary file is, by its first bytes, or None.

    >>> binary_kind(b"PAR1\x15\x04"), binary_kind(b"# spec: x")
    ('a Parquet file (name it .parquet)', None)
    """
    for magic, kind in MAGIC:
        if head.startswith(magic):
            return kind
    return None


def check_not_binary(head: bytes, path) -> None:
    """GonioError naming what a text input really is when its first bytes say so (a Parquet
    stream renamed .csv is 'a Parquet file', not 'not UTF-8 text (byte 7)')."""
    kind = binary_kind(head)
    if kind is not None:
        raise GonioError(f"this is {kind}, not a UTF-8 text file (a file renamed?)", file=path)


#: How close (difflib ratio) an unknown name must be to a known one to be taken for a
#: misspelling of it (latitude_dge, rate_table_urel, temperature for temperature_c: 0.83–0.97).
NEAR_MISS = 0.8


def check_near_miss(given, known, *, what: str, file, line=None) -> None:
    """Refuse a name of ``given`` that gonio does not know but that is a near miss of a
    ``known`` name the file does not give (a header key or column typo would otherwise be
    kept as an extra and the value it meant replaced by a default, silently).

    >>> check_near_miss(["latitude_dge"], ["latitude_deg"], what="metadata key", file="r.csv")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: r.csv: key latitude_dge: unknown metadata key, did you mean 'latitude_deg'? (a misspelt key is never ignored)
    >>> check_near_miss(["operator", "latitude_deg"], ["latitude_deg"], what="metadata key",
    ...                 file="r.csv")

    A known name in another case is refused too, whether or not the file also gives it
    (``SERIAL`` beside ``serial`` would be kept aside, never compared):

    >>> check_near_miss(["serial", "SERIAL"], ["serial"], what="metadata key", file="r.csv")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: r.csv: key SERIAL: unknown metadata key, did you mean 'serial'? (a misspelt key is never ignored)
    """
    import difflib

    given = list(given)
    known = list(known)
    folded = {k.casefold(): k for k in known}
    absent = {k.casefold(): k for k in known if k not in given}
    for name in given:
        if name in known:
            continue
        m = ([folded[name.casefold()]] if name.casefold() in folded else
             [absent[x] for x in difflib.get_close_matches(name.casefold(), list(absent), n=1,
                                                           cutoff=NEAR_MISS)])
        if m:
            where = {"key": name} if "key" in what else {"column": name}
            raise GonioError(f"unknown {what}, did you mean {m[0]!r}? (a misspelt "
                             f"{'key' if 'key' in what else 'column'} is never ignored)",
                             file=file, line=line, **where)


def check_header(columns, required, *, file, line) -> set:
    """Column names of a CSV header: none empty, none twice, every required one present.

    >>> sorted(check_header(["a", "b"], ["a"], file="f.csv", line=1))
    ['a', 'b']
    >>> check_header(["a", "a"], ["a"], file="f.csv", line=3)
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: f.csv:3: column a: column given twice in header
    """
    seen: set[str] = set()
    for name in columns:
        if not name:
            raise GonioError("empty column name in header", file=file, line=line)
        if name in seen:
            raise GonioError("column given twice in header", file=file, line=line, column=name)
        seen.add(name)
    for name in required:
        if name not in seen:
            raise MissingColumnError("missing required column", file=file, line=line, column=name)
    return seen
