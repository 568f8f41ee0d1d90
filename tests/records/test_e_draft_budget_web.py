"""The records and the web state E (7.4) under the draft's own budget as the certificate does.

``gonio calibrate --budget draft --record`` on simulated readings (seed 3): the calibration's
web page gives E one row, the interval of max|E_i| recomputed here from results.json's
per-point E_i with the one budget's u_c and ν_eff (tests/test_e_draft_budget.py), the same
upper end as the certificate the command wrote, and no ± U or k; the results.json the web
serves is the one the command wrote; the stored row keeps E as stated by its interval.
"""

from __future__ import annotations

import json
import re

from gonio.cli import main
from tests.statement_numbers import cell_numbers, expected_cell
from tests.test_e_draft_budget import hand_draft_interval
from tests.test_e_extreme_statement import upper_text

from .test_web_numbers import page_rows, web_client
from .conftest import make_people


def test_web_states_e_by_the_draft_budget_interval(tmp_path, capsys):
    from sqlalchemy import select

    from gonio.records.db import open_store
    from gonio.records.models import ResultItem

    data, out = tmp_path / "data", tmp_path / "cal"
    assert main(["simulate", "--spec", "ogam-draft", "--seed", "3", "--out",
                 str(tmp_path / "sim")]) == 0
    assert main(["calibrate", str(tmp_path / "sim" / "readings.csv"), "--budget", "draft",
                 "--out", str(out), "--record", "--data", str(data)]) == 0
    assert "recorded as calibration 1" in capsys.readouterr().err
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    lo, hi, m = hand_draft_interval(res)
    hi_t = upper_text(hi, m)
    cert = (out / "certificate.html").read_text(encoding="utf-8")
    assert re.search(rf"≤(\xa0| |&nbsp;){re.escape(hi_t)}",
                     cert.split("Angle-position deviation E")[1].split("</tr>")[0])
    store = open_store(None, data)
    try:
        make_people(store)
        web = web_client(store)
        r = web.get("/calibrations/1")
        assert r.status_code == 200
        cells = page_rows(r.text)["angle_deviation"]
        assert len(cells) == 1
        got = cell_numbers(cells[0])
        assert got == expected_cell(res["items"]["angle_deviation"]), cells[0]
        assert got["upper"] == hi_t and got["interval"] == ("0", hi_t)
        assert "U" not in got and "k" not in got
        served = web.get("/calibrations/1/files/results.json")
        assert json.loads(served.content) == res
        with store.session() as s:       # the stored row keeps E's statement
            row = s.execute(select(ResultItem).where(ResultItem.calibration_id == 1,
                                                     ResultItem.key == "angle_deviation")
                            ).scalar_one()
            assert row.stated == "interval" and row.interval_low == 0.0
            assert row.interval_high == float(hi_t) and row.k is None
    finally:
        store.close()
