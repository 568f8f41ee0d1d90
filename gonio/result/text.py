"""The one ``summary()`` of a :class:`~gonio.result.model.Result` (``summary.txt`` and the
command line): one line per item, stated by the one statement rule
(:func:`gonio.result.statement.state`: U to two significant digits, the value to U's decimal
place, k, ν_eff and p beside it), then the conformity decisions and the screening findings.
"""

from __future__ import annotations

from gonio.formats.provenance import (metadata_evidence, result_provenance, source_evidence,
                                      watermark_chance)
from gonio.result.findings import identity_subjects
from gonio.result.statement import decimals_for_sig, given_text, item_statement, round_half_up

#: summary.txt's first line for readings from the virtual bench (their own metadata say so).
VIRTUAL_LINE = ("VIRTUAL BENCH EXAMPLE - NOT A CALIBRATION CERTIFICATE: the readings name the "
                "virtual bench {bench}, seed {seed}, in their own metadata")
#: ... where the bench's or the seed's line is missing: the metadata keys that say so.
VIRTUAL_EVIDENCE_LINE = ("VIRTUAL BENCH EXAMPLE - NOT A CALIBRATION CERTIFICATE: the readings' "
                         "own metadata ({keys}) name the virtual bench")
#: ... where a derived result used with them (a tilt estimate) was computed from the bench's.
VIRTUAL_SOURCE_LINE = ("VIRTUAL BENCH EXAMPLE - NOT A CALIBRATION CERTIFICATE: {files} was "
                       "computed from the virtual bench's readings (its source says so)")
#: ... where every metadata line naming the bench is missing: the values' watermark.
VIRTUAL_WATERMARK_LINE = ("VIRTUAL BENCH EXAMPLE - NOT A CALIBRATION CERTIFICATE: the readings' "
                          "own values carry the virtual bench's watermark ({cells} cells, "
                          "chance on other readings {p})")


def virtual_line(res: dict) -> list[str]:
    """``[VIRTUAL_LINE]`` filled in for a results.json dict whose readings come from the virtual
    bench (:func:`gonio.formats.provenance.result_provenance`), else ``[]``."""
    prov = result_provenance(res)
    if not prov["virtual"]:
        return []
    if prov["bench"] and prov["seed"]:
        return [VIRTUAL_LINE.format(bench=prov["bench"], seed=prov["seed"])]
    keys = ", ".join(f"# {k}" for k in metadata_evidence(prov))  # the bench's line deleted
    if keys:
        return [VIRTUAL_EVIDENCE_LINE.format(keys=keys)]
    if source_evidence(prov):                    # a derived result's source: the bench's
        return [VIRTUAL_SOURCE_LINE.format(files=", ".join(source_evidence(prov)))]
    wm = prov.get("watermark") or {}            # every bench line deleted: the watermark
    return [VIRTUAL_WATERMARK_LINE.format(cells=wm.get("cells", "?"),
                                          p=watermark_chance(wm.get("p_value")))]


def item_text(it) -> str:
    """``value ± U unit (k, ν_eff, p)`` of one measured item by the one statement rule
    (:func:`gonio.result.statement.item_statement`: the certificate's and the DCC's numbers);
    an item stated by its interval adds the ν the certificate's ν_eff column prints beside
    it (:func:`gonio.result.statement.interval_nu_clause`): "; ν = 105" for a χ² interval (a
    standard deviation's, or a dispersion's bound-condition limit; never ∞), "; ν_eff = 7"
    for another whose coverage factor came from a ν_eff (a bound-condition interval
    value ± (a + k·u), a non-negative item's upper bound)."""
    from gonio.result.statement import interval_nu_clause

    doc = it.to_json()
    st = item_statement(doc)                           # as results.json states it (ν_eff ∞: null)
    nu = interval_nu_clause(st, (doc.get("uncertainty") or {}).get("k_source"))
    return st.text() if not nu else f"{st.text()}; {nu}"


def band_text(w: float) -> str:
    """A guard band as summary.txt and the records print it: the w the decision used, exactly
    (w = r·U of printed numbers, so a short decimal: 6 significant digits clear the binary
    floating point's tail), in the certificate's number form (never "1.2e-05"), as the
    certificate's guard-band note derives it: 0.0685 = (0.290 − 0.153)/2, never a rounded
    "0.069" beside it.

    >>> band_text(1.234e-5), band_text(0.0685), band_text(1.5 * 0.011), band_text(90.0)
    ('1.234×10⁻⁵', '0.0685', '0.0165', '90')
    """
    return given_text(float(round_half_up(float(w), decimals_for_sig(float(w), 6))))


def limits_text(lower, upper) -> str:
    """The limits as the laboratory gave them, in the certificate's form (:func:`given_text`:
    never rounded, one minus sign): "[lo, hi]", "≤ hi" or "≥ lo".

    >>> limits_text(-1000.0, 1000.0), limits_text(None, 76434.86), limits_text(-0.5, None)
    ('[-1000, 1000]', '≤ 76434.86', '≥ -0.5')
    """
    if lower is None:
        return f"≤ {given_text(upper)}"
    if upper is None:
        return f"≥ {given_text(lower)}"
    return f"[{given_text(lower)}, {given_text(upper)}]"


def conformance_clause(c) -> str:
    """", probability of conformance 98.5 %" (3 significant digits, the certificate's column),
    or "" where a decision states none: the one text every summary.txt line takes.

    Three significant digits with their trailing zeros, as the certificate prints them
    ("95.0 %", never "95 %").

    >>> from types import SimpleNamespace
    >>> conformance_clause(SimpleNamespace(conformance_probability=0.98533))
    ', probability of conformance 98.5 %'
    >>> conformance_clause(SimpleNamespace(conformance_probability=0.95))
    ', probability of conformance 95.0 %'
    >>> conformance_clause(SimpleNamespace(conformance_probability=0.99996))
    ', probability of conformance 100 %'
    """
    p = c.conformance_probability
    if p is None:
        return ""
    t = f"{100 * p:#.3g}"
    return f", probability of conformance {t[:-1] if t.endswith('.') else t} %"


def false_accept_bound_clause(c) -> str:
    """"; specific false-accept probability ≤ 5.0 %": the bound an item accepted on its
    interval under a guard band states where no probability is computed
    (``false_accept_bound`` = 1 − p, two significant digits rounded up, as the certificate's
    false-accept column prints it: :func:`gonio.result.statement.bound_up_text`), else "".

    >>> from types import SimpleNamespace
    >>> false_accept_bound_clause(SimpleNamespace(false_accept_bound=0.05))
    '; specific false-accept probability ≤ 5.0 %'
    >>> false_accept_bound_clause(SimpleNamespace(false_accept_bound=1 - 0.99305))
    '; specific false-accept probability ≤ 0.70 %'
    >>> false_accept_bound_clause(SimpleNamespace(false_accept_bound=None))
    ''
    """
    from gonio.result.statement import bound_up_text

    b = getattr(c, "false_accept_bound", None)
    if b is None:
        return ""
    return f"; specific false-accept probability ≤ {bound_up_text(100.0 * float(b))} %"


def conformity_text(c) -> str:
    """One conformity decision as a line (limits and guard bands as :func:`limits_text` and
    :func:`band_text` print them)."""
    lims = limits_text(c.lower, c.upper)
    if c.outcome is None:
        return f"{c.item}: limits {lims} ({c.rule}): no decision: {c.reason}"
    pc = conformance_clause(c)
    if c.conformance_probability is None and (c.probability_model or "").startswith("not given"):
        pc = f", probability {c.probability_model}"
    pc += false_accept_bound_clause(c)
    gb = "" if not c.guard_band else f", guard band {band_text(c.guard_band)}"
    if c.guard_band and getattr(c, "guard_band_lower", None) is not None:
        # an interval not symmetric about its value: its own reach on each side
        gb = f", guard bands {band_text(c.guard_band_lower)} at the lower limit, " \
             f"{band_text(c.guard_band)} at the upper"
    dm = measured_clause(c)
    return f"{c.item}: limits {lims} ({c.rule}{gb}): {c.outcome}{pc}{'; ' + dm if dm else ''}"


#: The clause summary.txt and the DCC add to a decision the measured value before rounding
#: decided (:func:`gonio.analysis.conformity.stricter_of`; the certificate's note under the
#: conformity table says the same, ``c_measured_note``).
MEASURED_CLAUSE = ("decided on the measurement result before rounding: its value {value}{against} "
                   "lies beyond the acceptance limit, where the printed numbers do not")
#: The acceptance interval the measured decision used, in :data:`MEASURED_CLAUSE`.
MEASURED_AGAINST = " against its acceptance interval {acceptance} (from the value and U before rounding)"


def measured_clause(c) -> str:
    """:data:`MEASURED_CLAUSE` for a decision (a Conformity or its results.json dict) whose
    outcome the measured value before rounding decided (``decided_on_measured``), else "".

    With ``decided_on_measured_acceptance`` it names the acceptance interval that decision
    used (:data:`MEASURED_AGAINST`): where U's rounding moved the limit, the printed value can
    lie inside the printed acceptance interval and the measured one inside it too.

    >>> measured_clause({"decided_on_measured": "76434.850926"}).split(" lies")[0]
    'decided on the measurement result before rounding: its value 76434.850926'
    >>> measured_clause({"decided_on_measured": "786.4851027",
    ...     "decided_on_measured_acceptance": "≤ 783.94479"}).split(" (from")[0]
    'decided on the measurement result before rounding: its value 786.4851027 against its \
acceptance interval ≤ 783.94479'
    >>> measured_clause({"decided_on_measured": None})
    ''
    """
    def get(name):
        return c.get(name) if isinstance(c, dict) else getattr(c, name, None)

    m = get("decided_on_measured")
    if not m:
        return ""
    acc = get("decided_on_measured_acceptance")
    return MEASURED_CLAUSE.format(value=m, against=MEASURED_AGAINST.format(acceptance=acc)
                                  if acc else "")


#: Where the certificate takes each identity subject's text from: (laboratory file section and
#: key, the readings' metadata keys, unit) (:func:`identity_lines`).
IDENTITY_SOURCES = {"serial": ("instrument", "serial", ("serial",), ""),
                    "model": ("instrument", "model", ("model",), ""),
                    "manufacturer": ("instrument", "manufacturer", ("manufacturer",), ""),
                    "gyro type": ("instrument", "gyro_type", ("gyro_type",), ""),
                    "temperature": ("environment", "temperature_c",
                                    ("temperature_c", "room_temperature_c"), " °C"),
                    "humidity": ("environment", "humidity_pct", ("humidity_pct",), " %")}


def identity_lines(findings, metadata: dict, lab: dict | None,
                   temperature_keys: tuple[str, ...] | None = None) -> list[str]:
    """summary.txt's lines for each identity or condition the readings contradict where the
    laboratory chose to proceed: the text the certificate states (the laboratory file's,
    else the readings'), flagged and pointing to the finding below; ``[]`` where none is.
    ``temperature_keys``: the readings' metadata keys that state the room temperature (the
    specification's ``room_temperature_keys``; None: those of :data:`IDENTITY_SOURCES`).

    >>> identity_lines([{"code": "identity-mismatch", "action": "flagged", "subject": "serial",
    ...                  "message": "serial: the readings say 'A'"}], {"serial": "A"},
    ...                {"instrument": {"serial": "SN-1"}})
    ["serial: SN-1 [CONTRADICTED by the readings: see the flagged finding 'serial: ...' below]"]
    """
    out = []
    for subject in identity_subjects(findings):
        section, key, md_keys, unit = IDENTITY_SOURCES.get(subject, ("", "", (), ""))
        if subject == "temperature" and temperature_keys is not None:
            md_keys = tuple(temperature_keys)
        v = ((lab or {}).get(section) or {}).get(key)
        if v in (None, ""):
            v = next((metadata.get(k) for k in md_keys if metadata.get(k) not in (None, "")),
                     None)
        text = "not stated" if v in (None, "") else (
            (getattr(v, "text", None) or f"{v:g}") if isinstance(v, float)
            else str(v).strip()) + unit     # a laboratory file's number as written ("25.0")
        out.append(f"{subject}: {text} [CONTRADICTED by the readings: see the flagged finding "
                   f"'{subject}: ...' below]")
    return out


def summary_lines(result, lab: dict | None = None,
                  temperature_keys: tuple[str, ...] | None = None,
                  conformity_notes: tuple[str, ...] = ()) -> list[str]:
    """The lines of :meth:`~gonio.result.model.Result.summary` (``lab``: the laboratory file
    the certificate is issued with, whose identity texts a contradiction flags;
    ``temperature_keys``: :func:`identity_lines`'; ``conformity_notes``: sentences printed
    under the conformity decisions, as the renderer words them, e.g. the guard-band note:
    :func:`gonio.report.item_outputs.band_notes`)."""
    lines = virtual_line({"provenance": result.provenance, "metadata": result.metadata})
    lines.append(result.spec_title or result.spec_key)
    lines += identity_lines(result.findings, result.metadata, lab, temperature_keys)
    for it in result.items.values():
        head = f"  {it.clause:10s} {it.title}"
        if not it.measured or it.value is None:
            lines.append(f"{head}: not measured ({it.reason})")
        else:
            lines.append(f"{head}: {item_text(it)}")
    decided = [it.conformity for it in result.items.values() if it.conformity is not None]
    if decided:
        lines.append("conformity:")
        lines += [f"  {conformity_text(c)}" for c in decided]
        lines += [f"  {note}" for note in conformity_notes]
    for f in result.findings:
        where = f.location()
        lines.append(f"{f.action.replace('_', ' ')}: {where + ': ' if where else ''}{f.message}")
    if result.unused_readings:
        lines.append(f"readings not used: {len(result.unused_readings)}")
    return lines
