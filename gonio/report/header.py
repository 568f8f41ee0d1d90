"""The ISO/IEC 17025 7.8 content every certificate carries, from the laboratory file.

Every specification's certificate (gonio's own and a plug-in's) opens and closes with the
same blocks, built here from the same laboratory file
(:mod:`gonio.formats.lab`) and the stored result; only the results pages between them are
the specification's own.

Contents
========
============================  ================================================================
:func:`certificate_id`        the identifier: the lab file's number, else ``VB-`` + readings hash
:func:`opening_blocks`        laboratory (accreditation, contact), customer and address,
                              instrument, dates, place, specification, readings file,
                              standards and traceability, environment (7.8.2.1 a–h, 7.8.4.1)
:func:`decision_rule_blocks`  the rule agreed with the customer and the limits' source (7.8.6)
:func:`conformity_section`    the conformity table of a per-item result with those lines
:func:`signature_blocks`      signatories with the approver's title, the statements, and a
                              recalibration interval only where one was agreed (7.8.4.3)
:func:`meta_text`             a readings metadata value in the page's language
:func:`record_notices`        a draft's notice; an amendment's: what it replaces and why (7.8.8)
:func:`record_rows`           the seal signed (short form) and the people required
:func:`is_draft`              a draft for review (watermarked DRAFT on every page)
============================  ================================================================

"Page x of y" on every page and the end-of-certificate mark are the renderer's
(:mod:`gonio.report.render`).
"""

from __future__ import annotations

from gonio.report.provenance import is_virtual, virtual_lines
from gonio.report.render import Block
from gonio.report.stated import FlagText
from gonio.report.stated import NoBreakText as NoBreak
from gonio.report.stated import conformity_blocks
from gonio.result.findings import identity_subjects

__all__ = ["certificate_id", "opening_blocks", "decision_rule_blocks", "conformity_section",
           "signature_blocks", "meta_text", "record_of", "is_draft", "record_notices",
           "record_rows", "room_temperature_keys", "room_temperature_text"]


def certificate_id(result, lab: dict | None = None) -> str:
    """The certificate's identifier: the lab file's number, else ``VB-`` + readings hash
    (``result``: the Result or its results.json).

    >>> class R: source_sha256 = "adf7d70bf7f73fcbe3e7897ae81a78dd"
    >>> certificate_id(R()), certificate_id(R(), {"certificate": {"number": "GON-2026-017"}})
    ('VB-ADF7D70BF7', 'GON-2026-017')
    """
    if lab:
        return lab["certificate"]["number"]
    sha = ((result.get("source") or {}).get("sha256") if isinstance(result, dict)
           else result.source_sha256) or "0" * 10
    return "VB-" + sha[:10].upper()


def meta_text(md: dict, key: str, L: dict, translate=None) -> str:
    """A readings metadata value as shown: the virtual bench's own descriptions in the page's
    language where the tables know them, data otherwise; "not stated" when absent.
    ``translate``: text → its Chinese or None, the specification's (its own phrases: the names
    of its virtual instruments; :func:`gonio.report.i18n.translator`); default: the shared
    tables alone."""
    v = md.get(key)
    if v in (None, ""):
        return L["not_stated"]
    if L.get("_lang") == "zh":
        if translate is None:
            from gonio.report.i18n import translator
            translate = translator()
        return translate(str(v)) or str(v)
    return str(v)


def _laboratory_rows(lab: dict | None, L: dict) -> list:
    if lab is None:
        return [(L["laboratory"], L["virtual_lab"]), (L["address"], "—")]
    la = lab["laboratory"]
    rows = [(L["laboratory"], la["name"]), (L["address"], la["address"])]
    if la["accreditation"]:
        rows.append((L["accreditation"], la["accreditation"]))
    if la["contact"]:
        rows.append((L["contact"], NoBreak(la["contact"])))
    return rows


#: The first page's line an identity finding's subject flags
#: (:func:`gonio.result.findings.identity_subjects`): the gyro type is part of the description.
FLAGGED_ROW = {"serial": "serial", "model": "model", "manufacturer": "manufacturer",
               "gyro type": "description", "temperature": "temperature",
               "humidity": "humidity"}


def flagged(rows: list, res: dict, L: dict) -> list:
    """``rows`` ((label, value)) with ``L["identity_flag"]`` beside each value an identity
    finding of ``res`` contradicts (the laboratory chose to proceed; the finding itself is
    stated under "Screening of the readings"): the signatory reads the first page.

    >>> from gonio.report.i18n import labels
    >>> L = labels("en")
    >>> res = {"findings": [{"code": "identity-mismatch", "action": "flagged",
    ...                      "subject": "serial", "message": "serial: the readings say 'A'"}]}
    >>> ["".join(map(str, v)) if isinstance(v, list) else v
    ...  for _, v in flagged([(L["serial"], "SN-1"), (L["model"], "M")], res, L)]
    ['SN-1 [contradicted: see “Screening of the readings”]', 'M']
    """
    keys = {L[FLAGGED_ROW[s]] for s in identity_subjects(res.get("findings"))
            if s in FLAGGED_ROW}
    sep = "" if L.get("_lang") == "zh" else " "
    return [(k, [v, FlagText(sep + L["identity_flag"])] if k in keys else v) for k, v in rows]


def _item_rows(res: dict, lab: dict | None, L: dict, specification: str,
               translate=None) -> list:
    """Customer and address, instrument, dates, place, specification and readings file
    (``translate``: :func:`meta_text`'s); a line the readings contradict flagged
    (:func:`flagged`)."""
    md = res.get("metadata", {})
    lab_ = lab or {}
    ns = L["not_stated"]
    cert = lab_.get("certificate", {})
    cust = lab_.get("customer", {"name": ns, "address": ""})
    inst = lab_.get("instrument", {})
    rows = [(L["customer"], cust["name"] or ns)]
    if cust.get("address"):
        rows.append((L["customer_address"], cust["address"]))
    src = res["source"]
    rows += [
        (L["description"], inst.get("description")
         or meta_text(md, "instrument", L, translate)),
        (L["model"], NoBreak(inst.get("model") or meta_text(md, "model", L, translate))),
        (L["serial"], NoBreak(inst.get("serial") or meta_text(md, "serial", L, translate))),
        (L["manufacturer"], inst.get("manufacturer")
         or meta_text(md, "manufacturer", L, translate)),
        (L["date_receipt"], cert.get("date_of_receipt") or ns),
        (L["date_calibration"], cert.get("date_of_calibration")
         or meta_text(md, "date", L, translate)),
        (L["date_issue"], cert.get("date_of_issue") or ns),
        (L["place"], cert.get("place") or (L["virtual_place"] if lab is None else ns)),
        (L["specification"], specification),
        *([(L["procedure"], cert["procedure"])] if cert.get("procedure") else []),
        (L["source_file"], src["file"] + L["paren"].format(
            x=f"SHA-256 {src['sha256'][:16]}…" + L["comma"] + L["rows_word"].format(
                n=src["rows"]))),
    ]
    return flagged(rows, res, L)


def condition_text(v) -> str:
    """An environment condition (temperature, humidity) as every output states it: the
    number as the readings' metadata give it (their text, trailing zeros and all: a logger's
    "20.0" states its resolution), or the laboratory file's number to at most 6 significant
    digits (the certificate's text; the DCC writes the same digits).

    A number text in exponent form or with a sign "+" (a valid number, not a logger's
    digits) is stated plainly, as a laboratory file's number is.

    >>> condition_text(20.1), condition_text(45.0), condition_text("22.50"), condition_text(20)
    ('20.1', '45', '22.50', '20')
    >>> condition_text("2e1"), condition_text("+21.5"), condition_text("2.05E1")
    ('20', '21.5', '20.5')

    A laboratory file's number keeps its digits as written there
    (:class:`gonio.formats.lab.WrittenNumber`: ``temperature_c = 20.0`` is "20.0").
    """
    if isinstance(getattr(v, "text", None), str):
        v = v.text
    if isinstance(v, str):
        t = v.strip()
        if not any(c in t for c in "eE+"):
            return t
        try:
            return f"{float(t):g}"
        except ValueError:
            return t
    return f"{float(v):g}"


def room_temperature_keys(spec_key: str | None) -> tuple[str, ...]:
    """The readings' metadata keys that state the room temperature for the result of the
    specification ``spec_key``, in order of preference: its registered
    ``room_temperature_keys`` (:class:`gonio.specs.Specification`), looked up in the
    registry when the stored result is rendered, so that a result stored before is rendered
    by the same rule; a key no installed specification has: the class's default. A key a
    specification uses for another temperature (a chamber's base temperature) is not among
    them, and its value is never stated as the room's.

    >>> room_temperature_keys(None)
    ('temperature_c', 'room_temperature_c')
    """
    from gonio.errors import GonioError
    from gonio.specs import Specification, get

    try:
        return tuple(get(spec_key).room_temperature_keys) if spec_key else \
            Specification.room_temperature_keys
    except GonioError:                  # not installed here: the default rule
        return Specification.room_temperature_keys


def room_temperature_text(md: dict, keys) -> str | None:
    """The first of ``keys`` (:func:`room_temperature_keys`) the readings' metadata ``md``
    state (a non-empty value), else None.

    >>> room_temperature_text({"room_temperature_c": "22.5"}, ("temperature_c",)) is None
    True
    >>> room_temperature_text({"temperature_c": "", "room_temperature_c": "20.0"},
    ...                       ("temperature_c", "room_temperature_c"))
    '20.0'
    """
    return next((md[k] for k in keys if md.get(k) not in (None, "")), None)


def _environment_rows(md: dict, lab: dict | None, L: dict, spec_key: str | None) -> list:
    """Temperature and humidity: the lab file's, else the readings file's (the temperature
    under the specification's :func:`room_temperature_keys` only). With a lab file,
    a value taken from the readings (none in ``[environment]``, or its ``source =
    "readings"``) is stated as such."""
    ns = L["not_stated"]
    env = (lab or {}).get("environment") or {}
    tagged = L["paren"].format(x=L["from_readings"]) if lab is not None else ""
    said = tagged if env.get("source") == "readings" else ""
    t, h = env.get("temperature_c"), env.get("humidity_pct")
    t_md = room_temperature_text(md, room_temperature_keys(spec_key))
    t_txt = f"{condition_text(t)} °C{said}" if t is not None else (
        f"{condition_text(t_md)} °C{tagged}" if t_md else ns)
    h_txt = f"{condition_text(h)} %{said}" if h is not None else (
        f"{condition_text(md['humidity_pct'])} %{tagged}" if md.get("humidity_pct") else ns)
    return [(L["temperature"], t_txt), (L["humidity"], h_txt)]   # flagged by the caller


def opening_blocks(res: dict, lab: dict | None, L: dict, *, specification: str,
                   standard_row: list, environment=(), summarise=None,
                   translate=None) -> list[Block]:
    """The certificate's opening (ISO/IEC 17025 7.8.2.1 a–h; JJF 1535 clause 8 a–j): the
    virtual-bench notice when the readings come from the virtual bench or there is no
    laboratory file (:func:`gonio.report.provenance.is_virtual`), the laboratory with its
    accreditation and contact, the customer with the address, the instrument, the dates, the
    place, the specification followed (``specification``, in the page's language), the
    readings file, the standards with their traceability (``standard_row``, four cells in
    the page's language, when the lab file names none), and the environment (then
    ``environment``: more (label, value) rows, e.g. a chamber's profile).
    ``summarise(kind, data)`` shortens a long table (default: none); ``translate``: the
    specification's translator of the readings' descriptions (:func:`meta_text`)."""
    md = res.get("metadata", {})
    out: list[Block] = []

    def add(kind, data, extra=None):
        out.append(Block(kind, summarise(kind, data) if summarise else data, extra))
    if is_virtual(res, lab):            # the readings' provenance, not the lab file's absence
        add("notice", " ".join(virtual_lines(res, L)))
    out += record_notices(lab, L)
    add("kv", _laboratory_rows(lab, L))
    add("kv", _item_rows(res, lab, L, specification, translate))
    add("h", L["standards"])
    std_rows = [[s["name"], NoBreak(s["identifier"] or "—"), s["accuracy"] or "—",
                 NoBreak(s["certificate"] or "—"), s["traceability"] or "—"]
                for s in ((lab or {}).get("standards") or [])]
    if not std_rows:
        std_rows = [list(standard_row) + [L["virtual_trace"] if lab is None
                                          else L["not_stated"]]]
    add("table", ([L["std_name"], L["std_id"], L["std_spec"], L["std_cert"], L["std_trace"]],
                  std_rows), (0.30, 0.13, 0.17, 0.15, 0.25))
    add("h", L["environment"])
    add("kv", flagged(_environment_rows(md, lab, L, res.get("spec")), res, L)
        + list(environment))
    return out


def _source_text(c, L: dict) -> str:
    g = (lambda k: c.get(k)) if isinstance(c, dict) else (lambda k: getattr(c, k, None))  # noqa: E731
    src = (g("source") or "").strip()
    if g("limits_from") == "lab file" or not g("limits_from"):
        return src or L["c_source_unstated"]
    return (src or L["not_stated"]) + " " + L["c_default"]


def decision_rule_blocks(lab: dict | None, decided, L: dict, name_of) -> list[Block]:
    """What the statements of conformity rest on (ISO/IEC 17025 7.1.3, 7.8.6.2): the decision
    rule as agreed with the customer (the lab file's ``[decision_rule] agreed``), and the
    source of each item's specification limits. ``decided``: (item key, Conformity or its
    results.json dict) of every item decided; ``name_of(key)`` its name on the page."""
    out: list[Block] = []
    agreed = ((lab or {}).get("decision_rule") or {}).get("agreed")
    if agreed:
        out.append(Block("p", [L["rule_agreed"].format(a=agreed)]))
    by_source: dict[str, list[str]] = {}
    for key, c in decided:
        by_source.setdefault(_source_text(c, L), []).append(name_of(key))
    if by_source:
        sep = "；" if L.get("_lang") == "zh" else "; "
        out.append(Block("p", [L["c_source_line"].format(s=sep.join(
            f"{L['list_sep'].join(names)}{'：' if L.get('_lang') == 'zh' else ': '}{src}"
            for src, names in by_source.items()))]))
    return out


def conformity_section(items: dict, L: dict, name_of, unit_of, lab: dict | None) -> list[Block]:
    """The statement-of-conformity section of a per-item result (results.json
    ``items.<key>.conformity``, decided by the pipeline; none: no section): the rule, the
    rule as agreed and the limits' source (:func:`decision_rule_blocks`), the table."""
    # every limit with its unit: a quantity of dimension one says so (never a bare "≤ 1")
    blocks = conformity_blocks(items, L, name_of, lambda k: unit_of(k) or L["unit_one"], Block)
    if not blocks:
        return []
    at = next(i for i, b in enumerate(blocks) if b.kind == "table")
    decided = [(k, it["conformity"]) for k, it in items.items() if it.get("conformity")]
    return blocks[:at] + decision_rule_blocks(lab, decided, L, name_of) + blocks[at:]


def signature_blocks(lab: dict | None, L: dict) -> list[Block]:
    """Signatories (the approver with the title), the statements on scope and reproduction,
    and a recalibration interval only where the laboratory file says one was agreed with the
    customer (``[recalibration]``; ISO/IEC 17025 7.8.4.3: no recommendation otherwise, whatever
    a specification's document suggests)."""
    sig = (lab or {}).get("signatory", {})
    approved = sig.get("approved_by") or "—"
    if sig.get("approved_title"):
        approved += f", {sig['approved_title']}"
    rec = record_of(lab)
    asked = [(L["amendment_asked_by"], rec["amendment_asked_by"])] if rec.get(
        "amendment_asked_by") else []
    out = [Block("h", L["signatory"]),
           Block("kv", [(L["calibrated_by"], sig.get("calibrated_by") or "—"),
                        (L["checked_by"], sig.get("checked_by") or "—"), *asked,
                        (L["approved_by"], approved), *record_rows(rec, L)]),
           Block("p", [L["statement_item"]]), Block("p", [L["statement_copy"]])]
    recal = (lab or {}).get("recalibration")
    if recal:
        out.append(Block("p", [L["statement_recal_agreed"].format(
            n=recal["interval_months"], a=recal["agreed"])]))
    return [Block("keep", out)]                  # one page, printed or PDF


def record_of(lab: dict | None) -> dict:
    """The laboratory file's ``[record]`` (how the certificate stands in the records), or
    ``{}`` when it has none."""
    return (lab or {}).get("record") or {}


def is_draft(lab: dict | None) -> bool:
    """A draft rendered for review before issue: watermarked DRAFT on every page."""
    return record_of(lab).get("status") == "draft"


def record_notices(lab: dict | None, L: dict) -> list[Block]:
    """The notices at the head of a certificate from its ``[record]``: a draft for review
    says so; an amendment names the certificate it replaces and why (ISO/IEC 17025 7.8.8.2,
    7.8.8.3)."""
    rec = record_of(lab)
    out = []
    if is_draft(lab):
        out.append(Block("notice", L["draft"]))
    if rec.get("replaces"):
        out.append(Block("notice", L["amendment"].format(
            old=rec["replaces"], reason=rec.get("amendment_reason") or L["not_stated"])))
    return out


def record_rows(rec: dict, L: dict) -> list[tuple]:
    """The signature block's rows of an issued record: the seal of the result the
    signatories signed (its first 16 hexadecimal digits; the DCC carries all 64) and the
    number of different people the laboratory requires."""
    rows = []
    if rec.get("seal_sha256"):
        rows.append((L["seal"], L["seal_value"].format(short=rec["seal_sha256"][:16])))
    if rec.get("min_people"):
        rows.append((L["people_required"], L[people_key(rec)]))
    return rows


def people_key(rec: dict) -> str:
    """The label of the duties an issued record was issued under: ``people_3``, ``people_2``,
    or ``people_2_amendment`` for an amendment (``replaces``) under 2, whose approver may be
    the calibration's creator (the records' duties: one changes, another approves)."""
    n = int(rec["min_people"])
    return f"people_{n}" + ("_amendment" if n == 2 and rec.get("replaces") else "")

