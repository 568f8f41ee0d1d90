"""Screening findings: what a specification's ``screen(readings)`` says of each reading.

A finding names the reading (file, line, column, test), the rule that fired with its
threshold, and what was done: the reading was **refused** (the whole calibration stops with a
GonioError), **set aside** (the calibration goes on without it and the certificate says so)
or **flagged** (kept and used, with a warning on the certificate and in ``results.json``).

>>> f = Finding("count-outlier", "counts depart from K·angle by 3600 counts (> 5 MAD)",
...             "set_aside", file="readings.csv", line=42, column="gyro_counts",
...             test="scale_factor", clause="7.1", rule="|r − median| > 5·1.4826·MAD")
>>> f.to_json()["action"], f.location()
('set_aside', 'readings.csv line 42, column gyro_counts')
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from gonio.errors import GonioError

#: The code of the flagged finding that states a readings column the specification does not
#: read (:func:`gonio.pipeline.dispatch.unread_columns`).
UNREAD_CODE = "unread-column"
#: The code of the flagged finding that states a contradiction between the readings and the
#: laboratory file the laboratory proceeded with (:mod:`gonio.pipeline.identity`).
IDENTITY_CODE = "identity-mismatch"
#: Findings about the whole file, stated before the findings of single readings wherever a
#: certificate lists only the first few.
WHOLE_FILE_CODES: tuple[str, ...] = (IDENTITY_CODE, UNREAD_CODE)

#: What was done with a reading a rule fired on.
ACTIONS: tuple[str, ...] = ("refused", "set_aside", "flagged")


@dataclass(frozen=True)
class Finding:
    """One screening finding (see the module docstring)."""

    code: str
    message: str
    action: str
    file: str | None = None
    line: int | None = None
    column: str | None = None
    test: str | None = None
    clause: str | None = None
    rule: str | None = None
    #: what of the instrument's identity or conditions the finding contradicts ("serial",
    #: "model", "manufacturer", "gyro type", "temperature", "humidity"; an identity finding
    #: only): the certificate flags that line of its first page (:func:`identity_subjects`)
    subject: str | None = None

    def __post_init__(self):
        if self.action not in ACTIONS:
            raise GonioError(f"finding action must be one of {', '.join(ACTIONS)}, "
                             f"got {self.action!r}")

    def location(self) -> str:
        """``file line N, column C`` (the parts that are known)."""
        parts = [p for p in (self.file, None if self.line is None else f"line {self.line}")
                 if p]
        where = " ".join(parts)
        if self.column:
            where = f"{where}, column {self.column}" if where else f"column {self.column}"
        return where

    def to_json(self) -> dict:
        d = asdict(self)
        if d["subject"] is None:        # results.json of every other finding as before
            del d["subject"]
        return d


#: The identity and conditions an identity finding can contradict, as its message begins
#: ("serial: the readings say …"; :mod:`gonio.pipeline.identity`).
IDENTITY_SUBJECTS: tuple[str, ...] = ("serial", "model", "manufacturer", "gyro type",
                                      "temperature", "humidity")


def identity_subjects(findings) -> dict[str, list[int]]:
    """What of the instrument's identity and conditions a stated identity finding contradicts
    (the laboratory chose to proceed): {subject: the finding's numbers}, numbered 1, 2, … as
    the certificate and the DCC state the findings (all but the refused ones, those about the
    whole file first: ``dcc:statement id="finding-N"``). ``findings``: Finding objects or
    results.json dicts; a stored finding without ``subject`` (a result stored before it was
    recorded) is read from its message's first word, which :mod:`gonio.pipeline.identity`
    writes as the subject. The certificate flags those lines of its first page, summary.txt
    and the DCC's identification point to the finding.

    >>> found = [{"code": "spike", "action": "set_aside", "message": "x", "line": 5},
    ...          {"code": IDENTITY_CODE, "action": "flagged", "subject": "serial",
    ...           "message": "serial: the readings say 'A'"},
    ...          {"code": IDENTITY_CODE, "action": "flagged",
    ...           "message": "temperature: the readings say 25 (# temperature_c)"}]
    >>> identity_subjects(found)
    {'serial': [1], 'temperature': [2]}
    """
    out: dict[str, list[int]] = {}
    for i, f in enumerate(stated_findings(findings), 1):
        g = f if isinstance(f, dict) else f.to_json()
        if g.get("code") != IDENTITY_CODE:
            continue
        subject = g.get("subject") or next(
            (s for s in IDENTITY_SUBJECTS if (g.get("message") or "").startswith(s + ":")), None)
        if subject:
            out.setdefault(subject, []).append(i)
    return out


def stated_findings(findings) -> list:
    """The findings a certificate states, in its order: all but the refused ones, those about
    the whole file (:data:`WHOLE_FILE_CODES`) first, the rest in their order."""
    def get(f, k):
        return f.get(k) if isinstance(f, dict) else getattr(f, k, None)
    return sorted((f for f in findings or () if get(f, "action") != "refused"),
                  key=lambda f: get(f, "code") not in WHOLE_FILE_CODES)


def findings_to_json(findings) -> list[dict]:
    """``results.json``'s ``findings``: in file order (line, then code)."""
    return [f.to_json() for f in sorted(findings, key=lambda f: (f.line is None, f.line or 0,
                                                                   f.code))]


def set_aside(data, findings):
    """``data`` (a DataFrame with a ``line`` column: each row's line in its file) without the
    rows a ``set_aside`` finding names by its line; a ``refused`` finding stops here with the
    one-line error naming the reading (:class:`GonioError`); ``flagged`` findings change
    nothing. The input is not modified.

    >>> import pandas as pd
    >>> df = pd.DataFrame({"line": [5, 6, 7], "output": [1.0, 99.0, 1.1]})
    >>> f = Finding("spike", "output 99 is 50 σ from its neighbours", "set_aside", line=6)
    >>> set_aside(df, [f])["output"].tolist()
    [1.0, 1.1]
    """
    for f in findings:
        if f.action == "refused":
            raise GonioError(f"refused by the screening: {f.message}", file=f.file,
                             line=f.line, column=f.column)
    lines = {f.line for f in findings if f.action == "set_aside" and f.line is not None}
    if not lines:
        return data
    if "line" not in data:
        raise GonioError("the readings have no 'line' column: findings that set rows aside "
                         "name them by their line in the file", key="line")
    return data[~data["line"].isin(lines)].reset_index(drop=True)
