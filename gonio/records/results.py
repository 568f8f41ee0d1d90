"""The records' items of a ``results.json``, read through the one reader of the stored result
(:meth:`gonio.result.model.Result.from_json`): a document that reader refuses (another
version, a malformed shape) is refused here too, with its message.

>>> from gonio.result.model import RESULTS_VERSION
>>> items = result_items({"version": RESULTS_VERSION, "spec": "x", "items": {"K": {
...     "title": "scale factor", "clause": "7.1", "value": 2.0, "unit": "counts/deg",
...     "measured": True, "uncertainty": {"u_c": 0.05, "U": 0.1, "k": 2.0}}}})
>>> [(i.key, i.value, i.U) for i in items]
[('K', 2.0, 0.1)]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gonio.errors import GonioError
from gonio.result.model import Result


@dataclass(frozen=True)
class Item:
    """One result item as the records keep it."""

    key: str
    title: str
    clause: str
    unit: str
    measured: bool
    value: float | None
    U: float | None
    k: float | None
    limits: tuple[float | None, float | None] | None = None   # (lower, upper) if stated
    outcome: str | None = None           # the conformity decision, if limits were given
    rule: str | None = None              # its decision rule


def _num(x) -> float | None:
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _item(it) -> Item:
    """The records' view of a :class:`gonio.result.model.Item`."""
    c = it.conformity
    limits = None
    if c is not None and (_num(c.lower) is not None or _num(c.upper) is not None):
        limits = (_num(c.lower), _num(c.upper))
    return Item(key=str(it.key), title=str(it.title or it.key), clause=str(it.clause or ""),
                unit=str(it.unit or ""), measured=bool(it.measured), value=_num(it.value),
                U=_num(it.U), k=_num(it.k), limits=limits,
                outcome=None if c is None or c.outcome is None else str(c.outcome),
                rule=None if c is None or c.rule is None else str(c.rule))


def result_items(results: dict) -> list[Item]:
    """The items of a results.json, in its order (:meth:`Result.from_json`); a document
    with no items is refused."""
    if not isinstance(results, dict):
        raise GonioError("results.json is not a JSON object", key="results")
    items = [_item(it) for it in Result.from_json(results).items.values()]
    if not items:                        # an empty list of items: nothing to record
        raise GonioError("results.json holds no items", key="items")
    return items


# ------------------------------------------------ the stored result as the pages state it


def stored_result(store, results_sha256: str):
    """The stored results.json (the sealed result) as read from its blob."""
    import json

    from gonio.records.blobs import get_bytes

    return json.loads(get_bytes(store.blob_root, results_sha256))


def stated_items(store, results_sha256: str) -> dict:
    """Item key → its statement by the one statement rule
    (:func:`gonio.result.statement.item_statement`), from the stored results.json itself
    (the sealed result), as every certificate states it; an item the rule refuses to state
    is left out (the page then says "not stated")."""
    return statements_of(stored_result(store, results_sha256))


def items_of(doc) -> dict:
    """Item key → its results.json dict as :func:`statements_of` states it, whatever the
    stored result's shape (a dict of items, a list of them, the optical draft's older one
    item per key; a list's U and k beside the value as its uncertainty); none for anything
    else."""
    items = doc.get("items") if isinstance(doc, dict) else None
    if isinstance(items, list):
        items = {str(it.get("key")): it for it in items if isinstance(it, dict)}
    if not isinstance(items, dict):        # the optical draft's older shape: one per key
        items = {k: v for k, v in (doc or {}).items()
                 if isinstance(v, dict) and "value" in v and "unit" in v}
    out = {}
    for key, it in items.items():
        if not isinstance(it, dict):
            continue
        if "uncertainty" not in it:          # the unified list's U and k beside the value
            it = dict(it, uncertainty={"U": it.get("U"), "k": it.get("k")})
        out[key] = it
    return out


def statements_of(doc) -> dict:
    """:func:`stated_items` of a results.json already read (a dict; anything else: none)."""
    from gonio.errors import GonioError
    from gonio.result.statement import item_statement

    out = {}
    for key, it in items_of(doc).items():
        try:
            out[key] = item_statement(it)
        except (GonioError, TypeError, ValueError):
            continue
    return out


#: The statement columns of a result row whose item the stored result does not state (the
#: statement rule refuses it, or the stored result has no such item).
NOT_STATED = {"stated": "none", "interval_low": None, "interval_high": None}


def stated_columns(doc) -> dict:
    """Item key → the columns a result row keeps of its statement (:func:`statements_of` of
    the results.json ``doc``): ``stated`` "interval" (stated by one coverage interval, whose
    rounded ends as numbers are ``interval_low`` and ``interval_high``, the history figure's
    bar) or "value" (value ± U, or the value alone); an item the rule refuses to state is
    left out (its row: :data:`NOT_STATED`)."""
    from decimal import Decimal

    out = {}
    for key, st in statements_of(doc).items():
        if st.interval is None:
            out[key] = {"stated": "value", "interval_low": None, "interval_high": None}
        else:
            lo, hi = (float(Decimal(x).scaleb(st.exponent)) for x in st.interval)
            out[key] = {"stated": "interval", "interval_low": lo, "interval_high": hi}
    return out


def result_rows(cal_id: int, doc: dict) -> list[dict]:
    """The result rows of calibration ``cal_id`` from its results.json ``doc``: each item
    (:func:`result_items`, text cut to its column) with its statement (:func:`stated_columns`),
    as the records write them when a result is stored."""
    stated = stated_columns(doc)
    return [{"calibration_id": cal_id, "key": it.key, "title": it.title[:200],
             "clause": it.clause[:64], "unit": it.unit[:32], "measured": it.measured,
             "value": it.value, "U": it.U, "k": it.k, **stated.get(it.key, NOT_STATED)}
            for it in result_items(doc)]


def stored_columns(blob_root, results_sha256: str) -> dict | None:
    """:func:`stated_columns` of a stored results.json, None when it cannot be read (missing,
    changed on disk, not JSON)."""
    import json

    from gonio.records.blobs import get_bytes

    try:
        return stated_columns(json.loads(get_bytes(blob_root, results_sha256)))
    except (GonioError, ValueError, RecursionError):
        return None


def fill_stated(blob_root, rows: list[dict], sha_of) -> int:
    """Give every result row (a dict with ``key``) whose ``stated`` is missing or None its
    statement columns from its calibration's stored results.json (``sha_of(row)``: its
    SHA-256, or None), each stored result read once; a row whose result cannot be read keeps
    None (the history then reads the stored result itself). Every row ends with the three
    statement keys. Returns how many rows were filled (a database, or a backup, written before
    the rows kept their statements)."""
    read: dict[str, dict | None] = {}
    filled = 0
    for row in rows:
        for name in NOT_STATED:
            row.setdefault(name, None)
        sha = sha_of(row) if row["stated"] is None else None
        if not sha:
            continue
        if sha not in read:
            read[sha] = stored_columns(blob_root, sha)
        if read[sha] is not None:
            row.update(read[sha].get(row.get("key"), NOT_STATED))
            filled += 1
    return filled


def stated_intervals(store, results_sha256: str) -> dict:
    """Item key → (low, high) of each item the stored result states by one coverage interval
    (:func:`stated_columns`), for the history figure's bars of a row that does not keep its
    statement (``stated`` None); read once per stored result (a stored file never changes)."""
    def read():
        cols = stored_columns(store.blob_root, results_sha256)
        return ({key: (c["interval_low"], c["interval_high"])
                 for key, c in (cols or {}).items() if c["stated"] == "interval"},
                cols is not None)

    return _read_once(_INTERVALS, (str(store.blob_root), results_sha256), read)


def _read_once(cache: dict, at: tuple, read):
    """``cache[at]``, else ``read()`` → (value, read_ok): a value read from a stored file is
    kept (a stored file never changes; the 1024 newest kept), one not read (absent,
    unreadable) is returned and not kept, so the next call reads again."""
    got = cache.get(at)
    if got is None:
        got, ok = read()
        if ok:
            cache[at] = got
            while len(cache) > 1024:
                cache.pop(next(iter(cache)))
    return got


_INTERVALS: dict[tuple[str, str], dict] = {}


def max_abs_keys(store, results_sha256: str) -> frozenset:
    """The keys of the items the stored result states by the interval of an extreme of
    magnitudes max_i |x_i| (``uncertainty.k_source``
    :data:`gonio.result.statement.K_SOURCE_MAX_ABS`: the optical draft's E, whose value a
    result written before 2026-12-02 holds as the signed extreme beside an interval of its
    magnitude; later ones hold the magnitude itself), read once per stored result (a
    stored file never changes); none where the result cannot be read, and that is not
    kept: the next call reads again."""
    from gonio.result.statement import K_SOURCE_MAX_ABS

    def read():
        import json

        from gonio.records.blobs import get_bytes
        try:
            doc = json.loads(get_bytes(store.blob_root, results_sha256))
        except (GonioError, ValueError, RecursionError):
            doc = None
        items = doc.get("items") if isinstance(doc, dict) else None
        if isinstance(items, list):
            items = {str(it.get("key")): it for it in items if isinstance(it, dict)}
        return frozenset(
            key for key, it in (items if isinstance(items, dict) else {}).items()
            if isinstance(it, dict) and isinstance(it.get("uncertainty"), dict)
            and it["uncertainty"].get("k_source") == K_SOURCE_MAX_ABS), doc is not None

    return _read_once(_MAX_ABS, (str(store.blob_root), results_sha256), read)


_MAX_ABS: dict[tuple[str, str], frozenset] = {}


# ------------------------------------------------ the stored decisions as the certificate states them


def conformity_of(doc, lang: str = "en", titles: dict | None = None) -> dict:
    """The statement of conformity of the results.json ``doc`` as the certificate states it,
    for a page: ``rules`` (the decision rule's paragraph of each rule used), ``rows`` (one per
    item with a stored decision, ``items.<key>.conformity``, in the result's order: ``key``,
    ``title``, ``limits``, ``acceptance``, ``guard_band``, ``outcome``, ``pc``, ``pfa``) and
    ``notes`` (the guard band of an item decided on its interval, the items with no
    probability). The texts are the certificate's
    (:func:`gonio.report.stated.conformity_blocks`: limits as given, the acceptance interval
    as decided and rounded once in the Result, the outcome) and the guard band as
    ``summary.txt`` prints it (:func:`gonio.result.text.band_text`, with its lower band where
    the interval is not symmetric); each negative number with U+2212. A pure function of the
    stored result: nothing is decided or computed again; no decision, no rows. ``lang``: the
    page's language, ``titles``: each item's name as the certificate in that language names
    it (:func:`gonio.records.queries.result_texts`' ``titles``; else the stored titles).

    >>> doc = {"items": {"B": {"title": "Bias", "unit": "deg/h", "value": 1.0,
    ...     "conformity": {"item": "B", "U": 0.2, "lower": -1.0, "upper": 1.0,
    ...         "rule": "simple", "guard_band": 0.0, "acceptance_lower": -1.0,
    ...         "acceptance_upper": 1.0, "outcome": "pass", "accepted": True,
    ...         "conformance_probability": 0.5, "false_accept_probability": 0.5}}}}
    >>> r = conformity_of(doc)["rows"][0]
    >>> r["limits"], r["acceptance"], r["guard_band"], r["outcome"], r["pc"]
    ('[−1, 1] °/h', '[−1, 1] °/h', '0 °/h', 'pass', '50.0 %')
    """
    from gonio.report.i18n import labels, minus_sign
    from gonio.report.stated import conformity_blocks
    from gonio.result.statement import unit_text
    from gonio.result.text import band_text

    items = doc.get("items") if isinstance(doc, dict) else None
    if not isinstance(items, dict):
        return {"rules": [], "rows": [], "notes": []}
    items = {k: it for k, it in items.items() if isinstance(it, dict)}
    L = labels(lang)

    def name_of(k):
        return str((titles or {}).get(k) or items[k].get("title") or k)

    def unit_of(k):
        return unit_text(items[k].get("unit")) or L["unit_one"]

    blocks = conformity_blocks(items, L, name_of, unit_of,
                               lambda kind, data, extra: (kind, data))
    decided = [(k, it["conformity"]) for k, it in items.items() if it.get("conformity")]
    at = next((i for i, (kind, _) in enumerate(blocks) if kind == "table"), None)
    if at is None:
        return {"rules": [], "rows": [], "notes": []}
    _, (_, table) = blocks[at]
    rules = [minus_sign(str(d[0])) for kind, d in blocks[:at] if kind == "p"]
    notes = [minus_sign(str(d[0])) for kind, d in blocks[at + 1:] if kind == "p"]
    rows = []
    for (key, c), row in zip(decided, table):   # conformity_blocks: one row per decision
        name, limits, acceptance, outcome, pc, pfa = (minus_sign(str(x)) for x in row)
        u = unit_of(key)
        w, w_lo = c.get("guard_band"), c.get("guard_band_lower")
        if not c.get("outcome"):
            band = "—"
        elif w_lo is not None and w:
            band = L["c_band_two"].format(lo=f"{band_text(w_lo)} {u}", hi=f"{band_text(w)} {u}")
        else:
            band = f"{band_text(w) if w else '0'} {u}"
        rows.append({"key": key, "title": name, "limits": limits, "acceptance": acceptance,
                     "guard_band": minus_sign(band), "outcome": outcome, "pc": pc, "pfa": pfa})
    return {"rules": rules, "rows": rows, "notes": notes}
