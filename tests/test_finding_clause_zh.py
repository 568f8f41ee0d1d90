"""A finding's clause is translated on a Chinese certificate like its message: the triad's
"thesis eq. 6.20" reads 论文式 6.20 (it was printed in English)."""

from __future__ import annotations

from gonio.report.i18n import finding_text, labels
from gonio.specs.triad_alignment.certificate import PHRASES_ZH


def test_the_clause_goes_through_the_specifications_phrases():
    f = {"action": "flagged", "clause": "thesis eq. 6.20", "column": "n_samples",
         "line": None, "message": "no static record: the biases b_i are the in-run bias over "
         "this record, without the bias-instability term, and the averaging time is not "
         "measured"}
    zh = finding_text(f, labels("zh"), PHRASES_ZH)
    assert zh.startswith("[标记] 论文式 6.20，n_samples 列：无静态记录") and "thesis" not in zh
    assert finding_text(f, labels("en"), PHRASES_ZH).startswith(
        "[flagged] thesis eq. 6.20, column n_samples: no static record")
    # a numbered clause no table knows stays as it is
    assert finding_text({**f, "clause": "5.3.3.1"}, labels("zh"), PHRASES_ZH).startswith(
        "[标记] 5.3.3.1，")


def test_the_triad_screenings_own_clause_in_chinese():
    f = {"action": "set_aside", "clause": "triad screening", "message": "x"}
    assert finding_text(f, labels("zh"), PHRASES_ZH).startswith("[剔除] 三轴组件数据筛查：")
