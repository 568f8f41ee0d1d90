"""The one result model every specification returns: a :class:`Result` of
:class:`Item` s, written as one ``results.json`` shape (``docs/formats.md#results-file``,
JSON Schema ``docs/results.schema.json``).

An :class:`Item` is one calibrated characteristic: key, clause, title, value and unit, whether
it was measured (or the reason not), its :class:`Uncertainty` (combined standard uncertainty
u_c, coverage factor k, ν_eff, U, coverage probability, the budget rows) and the statement of
conformity the pipeline decided for it (:class:`Conformity`; ``None`` without limits), plus
the specification's own details (tables, intermediate values) under ``details``.

A :class:`Result` holds the items in the specification's order, the screening findings
(:class:`~gonio.result.findings.Finding`), the readings not used, the source file's name and
SHA-256, the metadata and settings, the specification's key and title, gonio's version,
covariances between items (a triad's matrix elements), and ``extra``: sections a
specification adds beside its items (an annex budget, a thermal model).

Decisions and roundings are made here or in the pipeline; renderers only render.

>>> it = Item("K", "scale factor K", "7.1", "counts/deg", 2.0, uncertainty=Uncertainty(
...     [budget_row("s_K", "scatter", 0.01, 1.0, dof=4)], 0.01, 0.0278, 2.78, 4.0))
>>> r = Result("demo", "a demo", {"K": it}, {}, {"file": "r.csv", "sha256": "0" * 64})
>>> d = r.to_json()
>>> d["version"], d["items"]["K"]["uncertainty"]["U"], Result.from_json(d).items["K"].U
(1, 0.0278, 0.0278)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

from gonio import __version__
from gonio.errors import GonioError
from gonio.formats.jsonsafe import json_safe
from gonio.formats.provenance import result_provenance
from gonio.result.findings import Finding, findings_to_json

#: The version of the results.json shape (docs/formats.md#results-file). Raise it when a
#: key is renamed or removed; adding an optional key keeps it.
RESULTS_VERSION = 1
#: The coverage probability gonio's expanded uncertainties are stated for (GUM 6.2.2).
COVERAGE_PROBABILITY = 0.95
#: The keys every budget row carries in results.json (others, e.g. ``distribution``, may
#: follow): u = u(x_i), c = c_i, contribution = |c_i|·u(x_i), dof = ν_i (None: infinite).
ROW_KEYS = ("symbol", "source", "type", "u", "c", "contribution", "dof", "clause",
            "beyond_standard")


def _f(x):
    """A finite float or None (JSON has no NaN or infinity)."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def budget_row(symbol: str, source: str, u, c=1.0, contribution=None, dof=None, *,
               type: str = "", clause: str = "", beyond_standard: bool = False,
               **more) -> dict:
    """One row of an item's budget as results.json writes it (:data:`ROW_KEYS` first).

    ``contribution`` defaults to |c|·u. ``beyond_standard``: the term is not in the
    specification's own budget (gonio adds it; the certificate marks it).
    """
    if contribution is None and u is not None and c is not None:
        contribution = abs(float(c)) * float(u)
    row = {"symbol": str(symbol), "source": str(source), "type": type, "u": _f(u), "c": _f(c),
           "contribution": _f(contribution), "dof": _f(dof), "clause": clause,
           "beyond_standard": bool(beyond_standard)}
    row.update(json_safe(more))
    return row


def normalise_row(row: dict) -> dict:
    """A budget row from the earlier shapes (``beyond_draft``; no ``c``: a row that gives
    u_i(y), the item's standard uncertainty due to this input, has c_i = 1) with
    :data:`ROW_KEYS` present."""
    r = dict(row)
    beyond = r.pop("beyond_standard", r.pop("beyond_draft", False))
    u = r.pop("u", None)
    c = r.pop("c", None)
    contribution = r.pop("contribution", None)
    if c is None and contribution is None and u is not None:
        c = 1.0          # a row given as u_i(y): its input already in the item's unit
    return budget_row(r.pop("symbol", ""), r.pop("source", ""), u, c, contribution,
                      r.pop("dof", None), type=r.pop("type", "") or "",
                      clause=r.pop("clause", "") or "", beyond_standard=bool(beyond), **r)


#: results.json ``uncertainty.u_c_of`` of an item stated by its interval alone whose u_c is
#: its value's own budget: U there is the interval's upper end − the value (the decision
#: rule's guard band), so U/u_c is no coverage factor. ``{p}`` is the interval's coverage
#: probability as stated (:func:`p_stated`), filled by :func:`u_c_of_interval`.
U_C_OF_INTERVAL = ("the stated value, from its own budget; the {p} interval is the statement "
                   "and U is its upper end minus the value, not k·u_c")


def p_stated(p: float | None) -> str | None:
    """A coverage probability as every output states it, "p = 95 %", "p ≈ 98 %":
    :func:`gonio.result.statement.p_text` (a computed p rounded down) with its relation
    (:func:`gonio.result.statement.p_relation`); results.json ``uncertainty.p_stated`` beside
    the unrounded ``coverage_probability``. None without a p.

    >>> p_stated(0.95), p_stated(0.9823487503232564), p_stated(0.99998), p_stated(None)
    ('p = 95 %', 'p ≈ 98 %', 'p ≈ 99.998 %', None)
    """
    from gonio.result.statement import p_relation, p_text
    t = p_text(p)
    return None if t is None else f"p {p_relation(t)} {t} %"


def u_c_of_interval(p: float | None) -> str:
    """:data:`U_C_OF_INTERVAL` for an interval of coverage probability ``p`` (its
    :func:`p_stated`; "p = 95 %" where none is given)."""
    return U_C_OF_INTERVAL.format(p=p_stated(p) or p_stated(0.95))


@dataclass
class Uncertainty:
    """An item's uncertainty (JCGM 100): the budget rows (``components``, see
    :func:`budget_row`), u_c, U, k, ν_eff (None or inf: infinite), the coverage probability
    of U (None: a fixed k was asked for), optional JCGM 101 Monte Carlo figures, how k was
    chosen and an interval (e.g. χ²). With ``k`` None the interval *is* the statement (a
    dispersion, range or extreme: :func:`gonio.result.statement.state_interval`), U is then
    the distance from the value to the interval's upper end, used by the decision rule's
    guard band; otherwise no interval is stated beside U."""

    components: list[dict]
    u_c: float
    U: float
    k: float | None             # None: stated by ``interval`` alone (no coverage factor)
    nu_eff: float | None
    monte_carlo: dict | None = None
    coverage_probability: float | None = None
    k_source: str = ""
    interval: tuple[float, float] | None = None
    #: what ``u_c`` is the standard uncertainty of, for an item stated by its interval alone
    #: (``k`` None): there U is the interval's reach above the value and u_c is not U/k
    #: (None: :data:`U_C_OF_INTERVAL`, the stated value's own budget)
    u_c_of: str | None = None
    #: for an interval taken from a Monte Carlo's draws: the standard uncertainty of its ends
    #: from the finite number of draws (JCGM 101 7.9), which decides the decimal place the
    #: ends are stated at (:func:`gonio.result.statement.state_interval`); None: exact
    interval_numerical_u: float | None = None
    #: for an interval taken from a Monte Carlo's draws: how many draws its ends come from
    #: (JCGM 101 7.2's M; an adaptive procedure's total, 7.9.4); None: not a Monte Carlo's
    interval_draws: int | None = None

    @property
    def p(self) -> float | None:
        """The coverage probability (the name the rate items were written with)."""
        return self.coverage_probability

    @property
    def u(self) -> float:
        """The combined standard uncertainty u_c."""
        return self.u_c

    def to_json(self) -> dict:
        out = {"u_c": _f(self.u_c), "U": _f(self.U), "k": _f(self.k),
               "nu_eff": _f(self.nu_eff), "coverage_probability": _f(self.coverage_probability),
               "p_stated": p_stated(self.coverage_probability), "k_source": self.k_source,
               "components": [normalise_row(c) for c in self.components]}
        if self.interval is not None:
            out["interval"] = [_f(self.interval[0]), _f(self.interval[1])]
            if self.k is None:      # stated by the interval: say what U and u_c are
                out["u_c_of"] = self.u_c_of or u_c_of_interval(self.coverage_probability)
            if self.interval_numerical_u is not None:
                out["interval_numerical_u"] = _f(self.interval_numerical_u)
            if self.interval_draws is not None:
                out["interval_draws"] = int(self.interval_draws)
        if self.monte_carlo is not None:
            out["monte_carlo"] = json_safe(self.monte_carlo)
        return out

    @classmethod
    def from_json(cls, d: dict | None) -> "Uncertainty | None":
        if d is None:
            return None
        iv = d.get("interval")
        return cls(list(d.get("components") or []), d.get("u_c"), d.get("U"), d.get("k"),
                   d.get("nu_eff"), d.get("monte_carlo"), d.get("coverage_probability"),
                   d.get("k_source") or "", None if iv is None else (iv[0], iv[1]),
                   d.get("u_c_of") if d.get("u_c_of") != u_c_of_interval(
                       d.get("coverage_probability")) else None,
                   d.get("interval_numerical_u"), d.get("interval_draws"))


@dataclass(frozen=True)
class Conformity:
    """The statement of conformity of one item (ILAC-G8:09/2019, JCGM 106), in the item's
    unit, as decided by :func:`gonio.analysis.conformity.decide`.

    ``outcome`` is None when a limit was given but no decision is possible (the item was not
    measured, or has no U); ``reason`` then says why. ``limits_from`` says where the limits
    came from (``lab file``, ``protocol``, the specification's tolerance).
    """

    item: str
    value: float | None
    U: float | None
    k: float | None
    lower: float | None
    upper: float | None
    rule: str
    guard_band: float | None
    acceptance_lower: float | None
    acceptance_upper: float | None
    outcome: str | None
    accepted: bool | None
    conformance_probability: float | None
    false_accept_probability: float | None
    false_reject_probability: float | None
    source: str = ""
    guard_factor: float | None = None
    limits_from: str = ""
    reason: str = ""
    probability_model: str = "normal"
    #: what the acceptance interval bounds: "value" (the measured value, JCGM 106 8.3.2) or
    #: "interval" (the ends of the item's stated 95 % interval: an item stated by its
    #: interval alone, decided under a guard band; its upper end must not exceed
    #: ``acceptance_upper``, its lower end not fall below ``acceptance_lower``)
    acceptance_of: str = "value"
    #: no value can pass: the guard bands close the tolerance, or leave only values below
    #: zero for a non-negative quantity (stated "none", never as a negative limit)
    acceptance_empty: bool = False
    #: the guard band at the lower limit where it differs from ``guard_band`` (the upper one):
    #: an item stated by an interval that is not symmetric about its value is guarded by its
    #: own reach below the value there (r·U_L); None where the two bands are one
    guard_band_lower: float | None = None
    #: the acceptance limits as printed, decided once (a limit as given, else rounded inward
    #: at the decimal place of what is compared with it), or None (open, or an older result)
    acceptance_lower_text: str | None = None
    acceptance_upper_text: str | None = None
    #: an item stated by its 95 % interval alone: the interval and the value as its
    #: statement prints them (what the decision is taken on), else None
    stated_interval: tuple[str, str] | None = None
    stated_value: str | None = None
    #: where no probability is computed (an interval item accepted under a guard band,
    #: r ≥ 1): the bound on the specific false-accept probability the rule implies, 1 − p of
    #: its stated interval (the measurand lies above the interval's upper end with at most
    #: that probability), else None
    false_accept_bound: float | None = None
    #: the measured value (before rounding, as text) where it decided a stricter outcome than
    #: the printed value would (:func:`gonio.analysis.conformity.stricter_of`), else None
    decided_on_measured: str | None = None
    #: with ``decided_on_measured``: the acceptance interval the measured decision used (from
    #: the value and U before rounding), as text ("≤ 783.9447", "[−0.08, 0.4991]"), so that
    #: the statement names the limit the measured value lies beyond; None otherwise (or an
    #: older result)
    decided_on_measured_acceptance: str | None = None

    def to_dict(self) -> dict:
        return {f.name: (_f(getattr(self, f.name))
                         if isinstance(getattr(self, f.name), float) else getattr(self, f.name))
                for f in fields(self)}

    to_json = to_dict

    @classmethod
    def from_json(cls, d: dict | None) -> "Conformity | None":
        if d is None:
            return None
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in names})


@dataclass
class Item:
    """One calibration item (see the module docstring)."""

    key: str
    title: str
    clause: str
    unit: str
    value: float | None = None
    measured: bool = True
    reason: str = ""
    uncertainty: Uncertainty | None = None
    details: dict = field(default_factory=dict)
    conformity: Conformity | None = None
    #: A quantity that cannot be negative (a noise level, a threshold, a time): stated with
    #: an upper bound when U exceeds the value (:func:`gonio.result.statement.state`).
    nonnegative: bool = False

    @property
    def U(self) -> float | None:
        return None if self.uncertainty is None else self.uncertainty.U

    @property
    def u(self) -> float | None:
        return None if self.uncertainty is None else self.uncertainty.u_c

    @property
    def k(self) -> float | None:
        return None if self.uncertainty is None else self.uncertainty.k

    @property
    def nu_eff(self) -> float | None:
        return None if self.uncertainty is None else self.uncertainty.nu_eff

    def to_json(self) -> dict:
        measured = bool(self.measured)
        return {"key": self.key, "clause": self.clause, "title": self.title,
                "value": _f(self.value) if measured else None, "unit": self.unit,
                "measured": measured, "reason": self.reason,
                "uncertainty": (None if self.uncertainty is None or not measured
                                else self.uncertainty.to_json()),
                "conformity": None if self.conformity is None else self.conformity.to_json(),
                "nonnegative": bool(self.nonnegative), "details": json_safe(self.details),
                **({"upper_bound": self.upper_bound()} if self.nonnegative else {})}

    def upper_bound(self) -> float | None:
        """The upper bound the statement rule gives a non-negative item whose U exceeds its
        value (:func:`gonio.result.statement.state`), or None."""
        from gonio.result.statement import item_statement

        st = item_statement(self, nonnegative=True)
        return None if st.upper is None else float(f"{st.upper}e{st.exponent}")

    @classmethod
    def from_json(cls, d: dict, key: str | None = None) -> "Item":
        return cls(d.get("key") or key, d.get("title", ""), d.get("clause", ""),
                   d.get("unit", ""), d.get("value"), bool(d.get("measured", True)),
                   d.get("reason", ""), Uncertainty.from_json(d.get("uncertainty")),
                   dict(d.get("details") or {}), Conformity.from_json(d.get("conformity")),
                   bool(d.get("nonnegative", False)))


def not_measured(key: str, title: str, clause: str, unit: str, reason: str) -> Item:
    """An item the readings do not allow, with the reason."""
    if not reason:
        raise GonioError(f"item {key!r} is not measured: the reason must be given")
    return Item(key, title, clause, unit, None, False, reason)


def source_info(readings) -> dict:
    """The ``source`` of a result calibrated from ``readings`` (an object with ``path``, the
    file it was read from or None, and ``data``, its table as a DataFrame): the file's name,
    SHA-256 and row count; held in memory, ``<memory>`` and the SHA-256 of the table's
    values (:func:`pandas.util.hash_pandas_object`)."""
    import hashlib
    from pathlib import Path

    import pandas as pd

    from gonio.atomic import sha256_file

    if readings.path is not None and Path(readings.path).is_file():
        sha = sha256_file(readings.path)
        name = Path(readings.path).name
    else:
        sha = hashlib.sha256(pd.util.hash_pandas_object(readings.data, index=False)
                             .values.tobytes()).hexdigest()
        name = "<memory>"
    return {"file": name, "sha256": sha, "rows": int(len(readings.data))}


@dataclass
class Covariance:
    """Covariance matrix (in the items' units) between the values of ``items``, e.g. the
    elements of one row of a triad's system matrix and its bias from one least-squares fit."""

    items: list[str]
    matrix: list[list[float]]
    source: str = ""

    def to_json(self) -> dict:
        return {"items": list(self.items), "matrix": json_safe(self.matrix),
                "source": self.source}

    @classmethod
    def from_json(cls, d: dict) -> "Covariance":
        return cls(list(d["items"]), [list(r) for r in d["matrix"]], d.get("source", ""))


#: The top-level keys of results.json and the JSON type each must have (docs/formats.md);
#: ``spec`` and ``items`` are required.
_RESULT_SHAPE = {"spec": (str, "a string"), "items": (dict, "an object of items"),
                 "metadata": (dict, "an object"), "source": (dict, "an object"),
                 "extra": (dict, "an object"), "settings": (dict, "an object"),
                 "provenance": (dict, "an object"), "readings_taken": (list, "a list"),
                 "findings": (list, "a list"), "unused_readings": (list, "a list"),
                 "covariances": (list, "a list")}


def _json_type(x) -> str:
    return {dict: "an object", list: "a list", str: "a string", bool: "true/false",
            type(None): "null"}.get(type(x), "a number")


def _check_shape(d: dict) -> None:
    """Refuse a results.json whose top-level keys have the wrong JSON type, naming the key
    (GonioError ``key KEY: malformed results.json: must be …``), before anything reads them.

    >>> _check_shape({"spec": "x", "items": []})
    Traceback (most recent call last):
    gonio.errors.GonioError: key items: malformed results.json: must be an object of items, not a list
    """
    for key, (typ, what) in _RESULT_SHAPE.items():
        if key not in d:
            if key in ("spec", "items"):
                raise GonioError("malformed results.json: required key is missing", key=key)
            continue
        v = d[key]
        if v is None and key not in ("spec", "items"):
            continue
        if not isinstance(v, typ):
            raise GonioError(f"malformed results.json: must be {what}, not {_json_type(v)}",
                             key=key)
    for k, it in d["items"].items():
        if not isinstance(it, dict):
            raise GonioError(f"malformed results.json: must be an object, not "
                             f"{_json_type(it)}", key=f"items.{k}")


@dataclass
class Result:
    """A calibration's result (see the module docstring).

    The first seven fields are positional in the order the rate specifications built
    their results (key, title, items, metadata, source, readings taken, extra).
    ``tables`` (name → DataFrame) are written by :func:`gonio.result.tables.write_tables`
    beside results.json and are not part of it; everything a certificate shows (the
    series each figure draws included) is in results.json, so the certificate can be
    rendered again from the stored file.
    """

    spec_key: str
    spec_title: str
    items: dict[str, Item]
    metadata: dict
    source: dict
    readings_taken: list[str] = field(default_factory=list)
    extra: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    findings: list[Finding] = field(default_factory=list)
    unused_readings: list[dict] = field(default_factory=list)
    covariances: list[Covariance] = field(default_factory=list)
    gonio_version: str = __version__
    tables: dict = field(default_factory=dict, repr=False, compare=False)
    #: Where the readings come from (:func:`gonio.formats.provenance.provenance`), set by the
    #: pipeline from the readings; ``virtual`` also whenever the metadata say so.
    provenance: dict = field(default_factory=dict)

    @property
    def source_sha256(self) -> str:
        return (self.source or {}).get("sha256") or ""

    def item(self, key: str) -> Item:
        """The item ``key``; an unknown key is an error naming this specification's items."""
        if key not in self.items:
            raise GonioError(f"{self.spec_key} has no item {key!r} (its items: "
                             f"{', '.join(self.items)})")
        return self.items[key]

    def to_json(self) -> dict:
        """``results.json`` (plain JSON types, deterministic; docs/results.schema.json)."""
        return {"version": RESULTS_VERSION, "gonio_version": self.gonio_version,
                "spec": self.spec_key, "specification": self.spec_title,
                "source": json_safe(self.source), "metadata": json_safe(self.metadata),
                "settings": json_safe(self.settings),
                "items": {k: it.to_json() for k, it in self.items.items()},
                "covariances": [c.to_json() for c in self.covariances],
                "findings": findings_to_json(self.findings),
                "unused_readings": json_safe(self.unused_readings),
                "readings_taken": list(self.readings_taken),
                "extra": json_safe(self.extra),
                "provenance": json_safe(result_provenance(
                    {"provenance": self.provenance, "metadata": self.metadata}))}

    def to_dict(self) -> dict:
        return self.to_json()

    @classmethod
    def from_json(cls, d: dict) -> "Result":
        """The result back from its results.json (tables and analysis objects are not kept);
        a malformed document (a key missing, a list for an object) is a GonioError."""
        v = d.get("version") if isinstance(d, dict) else None
        if v != RESULTS_VERSION:
            raise GonioError(f"results.json version {v!r} is not the one this gonio reads "
                             f"({RESULTS_VERSION})", key="version")
        _check_shape(d)
        fnames = {f.name for f in fields(Finding)}
        try:
            return cls(d["spec"], d.get("specification", ""),
                       {k: Item.from_json(it, k) for k, it in d["items"].items()},
                       dict(d.get("metadata") or {}), dict(d.get("source") or {}),
                       list(d.get("readings_taken") or []), dict(d.get("extra") or {}),
                       dict(d.get("settings") or {}),
                       [Finding(**{k: x for k, x in f.items() if k in fnames})
                        for f in d.get("findings") or []],
                       list(d.get("unused_readings") or []),
                       [Covariance.from_json(c) for c in d.get("covariances") or []],
                       d.get("gonio_version", ""), provenance=dict(d.get("provenance") or {}))
        except (KeyError, AttributeError, IndexError, TypeError, ValueError) as exc:
            raise GonioError(f"malformed results.json: {type(exc).__name__} {str(exc)[:80]}",
                             key="results") from None

    def summary(self, lab: dict | None = None,
                temperature_keys: tuple[str, ...] | None = None,
                conformity_notes: tuple[str, ...] = ()) -> str:
        """One line per item: clause, title, value ± U (k, ν_eff) unit, or why not measured;
        then the conformity decisions and the screening findings (``summary.txt``); an
        identity the readings contradict flagged under the title (``lab``: the laboratory
        file the certificate is issued with; ``temperature_keys``: the readings' metadata
        keys that state the room temperature, the specification's, which the renderer
        passes: :func:`gonio.result.text.identity_lines`; ``conformity_notes``: sentences
        printed under the conformity decisions, which the renderer words)."""
        from gonio.result.text import summary_lines

        return "\n".join(summary_lines(self, lab, temperature_keys, conformity_notes)) + "\n"
