"""The rendering kit: what a specification that draws its own certificate uses.

A specification whose ``calibrate`` returns a per-item :class:`gonio.kit.Result` renders with
:data:`gonio.kit.ITEM_RENDERER` and needs nothing here. One whose certificate has pages of its
own (the optical draft's: its Annex B page, eight figures and DCC lists) writes its
``outputs`` module and the rendering modules it draws with (``certificate_pages``,
``figures``, ``dcc``, ``stated``) on these names, gonio's own objects re-exported, so that
every certificate shares one layout, one 17025 content, one statement rule and one DCC
builder set (docs/kit.md#the-rendering-kit).

==============================  ==========================================================
Layout (HTML and A4 PDF)        :class:`Block`, :func:`render_html`, :func:`render_pdf`,
                                :func:`render_pdf_figures`, :func:`font_families`
The content every certificate   :func:`certificate_id`, :func:`opening_blocks`,
shares (ISO/IEC 17025 7.8)      :func:`decision_rule_blocks`, :func:`signature_blocks`,
                                :func:`conformity_section`, :func:`meta_text`,
                                :func:`is_virtual`, :func:`is_draft`, :func:`clean_tree`
Labels and numbers              :func:`labels`, :func:`display`, :func:`display_number`,
                                :func:`display_uncertainty`, :func:`rule_at_U`,
                                :func:`coverage_text`, :func:`finding_text`,
                                :func:`reason_text`, :func:`clause_text`,
                                :func:`parse_display`,
                                :class:`Num`, :class:`NoBreakText`, :func:`num`,
                                :func:`lookup`, :func:`item_nums`,
                                :func:`conformity_texts`, :func:`no_probability_note`,
                                :func:`measured_note`, :func:`skewed_note`,
                                :func:`condition_text`,
                                :func:`interval_band_note`, :func:`stated_p`,
                                :func:`pc_text` (a decision's probability of conformance
                                as the conformity table's column prints it),
                                :func:`declaration_parts`, :func:`interval_legend`
Figures                         :func:`figure_svg`, :func:`mpl_style`,
                                :func:`legend_above`, :func:`plain_axes`,
                                :func:`empty_panel`, :func:`plain_log_ticks`,
                                :data:`HTML_FIGSIZE`
The DCC (PTB DCC 3.3.0)         :func:`new_document`, :func:`administrative_data`,
                                :func:`measurement_result`, :func:`influence_conditions`, :func:`environment_conditions`,
                                :func:`element`, :func:`text_element`, :func:`quantity`,
                                :func:`list_quantity`,
                                :func:`not_measured_quantity`, :func:`interval_quantity`
                                (an interval without a standard uncertainty),
                                :func:`below_zero_quantity` (an item stated by its upper
                                bound alone: [0, upper], no si:value),
                                :func:`nu_quantity` (the ν of an item stated by a χ²
                                interval, beside its quantity),
                                :func:`probability_quantities` (a conformity statement's
                                probabilities at the certificate's digits),
                                :func:`unit_dsi`, :func:`tree_bytes`,
                                :func:`bilingual`, :func:`label_translator`,
                                :data:`DCC_CONFORMITY`
==============================  ==========================================================

Importing this module imports the report (Matplotlib, lxml); :mod:`gonio.kit` itself does
not, so a specification's calibrating modules stay light.
"""

from __future__ import annotations

from gonio.report.dcc import (DCC_CONFORMITY, administrative_data, below_zero_quantity, bilingual,
                              element, environment_conditions, influence_conditions,
                              interval_quantity, label_translator, list_quantity,
                              measurement_result, new_document, not_measured_quantity,
                              nu_quantity, probability_quantities, quantity, text_element,
                              tree_bytes, unit_dsi)
from gonio.report.figures import (HTML_FIGSIZE, empty_panel, figure_svg, legend_above,
                                  mpl_style, plain_axes, plain_log_ticks)
from gonio.report.header import (certificate_id, condition_text, conformity_section,
                                 decision_rule_blocks,
                                 is_draft, meta_text, opening_blocks, signature_blocks)
from gonio.report.i18n import (clause_text, coverage_text, display, display_number,
                               display_uncertainty, finding_text, labels, parse_display,
                               reason_text, rule_at_U)
from gonio.report.provenance import is_virtual
from gonio.report.render import (Block, font_families, render_html, render_pdf,
                                 render_pdf_figures)
from gonio.report.stated import (NoBreakText, Num, conformity_texts, declaration_parts,
                                 interval_legend, item_nums, lookup, interval_band_note,
                                 measured_note, no_probability_note, num, pc_text,
                                 skewed_note, stated_p)
from gonio.report.text import clean_tree

__all__ = [
    "Block", "DCC_CONFORMITY", "HTML_FIGSIZE", "NoBreakText", "Num", "administrative_data",
    "bilingual", "certificate_id", "clause_text", "clean_tree", "condition_text",
    "conformity_section", "conformity_texts", "coverage_text", "decision_rule_blocks",
    "display", "display_number", "display_uncertainty", "element", "empty_panel",
    "environment_conditions",
    "no_probability_note", "measured_note", "skewed_note", "interval_band_note", "stated_p",
    "pc_text",
    "declaration_parts",
    "interval_legend", "interval_quantity", "below_zero_quantity",
    "figure_svg", "finding_text", "font_families", "influence_conditions", "is_draft",
    "is_virtual",
    "item_nums", "label_translator", "labels", "legend_above", "list_quantity", "lookup",
    "measurement_result", "meta_text", "mpl_style", "new_document", "not_measured_quantity",
    "nu_quantity", "probability_quantities", "num", "opening_blocks", "parse_display", "plain_axes", "plain_log_ticks",
    "quantity",
    "reason_text", "render_html", "render_pdf", "render_pdf_figures", "rule_at_U",
    "signature_blocks", "text_element", "tree_bytes", "unit_dsi",
]
