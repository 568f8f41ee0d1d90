"""Issue 18's last gap: the triad calibration on the certificate (alignment-matrix page,
temperature-model page), results.json in the per-item shape, damaged triad readings through
the CLI, and the certificate layout rule that keeps a table's head with its first rows.

Checked from the outside: the CLI on a simulated triad folder; the certificate's numbers
(``data-src`` spans) against results.json re-rounded here (half up, U to 2 significant
digits, value to U's decimal place, JCGM 100 7.2.6); the estimate against the bench's truth.
"""

from __future__ import annotations

import math

import html
import json
import re
from decimal import ROUND_CEILING, ROUND_FLOOR, ROUND_HALF_UP, Decimal
from pathlib import Path

import numpy as np
import pytest

from gonio.cli import main
from gonio.errors import GonioError
from gonio.report.render import Block, KEEP_FIRST_ROWS, layout_pages
from gonio.report.i18n import labels

AX = "xyz"
SPANS = re.compile(r'<span class="num" data-src="([^"]+)" data-rule="([^"]+)">([^<]*)</span>')


def half_up(x: float, dec: int) -> str:
    """``x`` half up at ``dec`` places as the certificate prints it (minus sign U+2212)."""
    s = f"{Decimal(repr(x)).quantize(Decimal(1).scaleb(-dec), rounding=ROUND_HALF_UP):f}"
    return s.replace("-", "\u2212")


def two_sig(U: float) -> tuple[str, int]:
    """U to two significant digits, half up, and its decimal place — computed afresh."""
    e = Decimal(repr(U)).adjusted()
    dec = 1 - e
    if Decimal(repr(U)).quantize(Decimal(1).scaleb(-dec), rounding=ROUND_HALF_UP).adjusted() > e:
        dec -= 1
    return half_up(U, dec), dec


def lookup(res, path):
    for p in path.split("."):
        res = res[int(p)] if isinstance(res, list) else res[p]
    return res


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("triadcert")
    assert main(["simulate", "--spec", "triad-alignment", "--bench", "mems-triad",
                 "--out", str(d / "sim")]) == 0
    assert main(["calibrate", str(d / "sim" / "readings.csv"), "--out", str(d / "cal"),
                 "--monte-carlo", "300", "--dcc"]) == 0
    return {"dir": d, "res": json.loads((d / "cal" / "results.json").read_text()),
            "html": (d / "cal" / "certificate.html").read_text(encoding="utf-8"),
            "truth": json.loads((d / "sim" / "truth.json").read_text())}


def test_results_json_per_item_shape(run):
    res = run["res"]
    assert res["spec"] == "triad-alignment"
    keys = {"value", "unit", "clause", "measured", "reason", "uncertainty"}
    for key in [f"M_{a}{b}" for a in AX for b in AX] + [f"b_{a}" for a in AX] \
            + [f"S_{a}{b}" for a in AX for b in AX if a != b] + ["averaging_time"]:
        it = res["items"][key]
        assert keys <= set(it), key
        assert it["measured"], (key, it["reason"])
    it = res["items"]["M_xy"]
    u = it["uncertainty"]
    assert {"components", "u_c", "U", "k", "nu_eff"} <= set(u)
    # one statement: the bound-condition interval; the Monte Carlo u and the JCGM 100 U are
    # in the details, not certified
    assert u["k"] is None and "monte_carlo" not in u
    nc = it["details"]["not_certified"]
    assert nc["monte_carlo"]["trials"] == 300 and nc["monte_carlo"]["status"] == "not certified"
    # the JCGM 100 reading's k is Student's t for 95.45 % at its ν_eff (the fit's ν and the
    # table's Type B line, ν = ∞, by Welch–Satterthwaite; its integer part, ∞ above NU_INFINITE)
    from scipy import stats
    from gonio.result.statement import NU_INFINITE
    fit, table = u["components"]
    assert table["symbol"] == "M_xy_table" and table["type"] == "B" and fit["type"] == "A"
    gum = nc["gum"]
    nu = gum["nu_eff"] if gum["nu_eff"] is not None else math.inf
    assert nu == pytest.approx(u["u_c"] ** 4 / (fit["u"] ** 4 / fit["dof"]), rel=1e-9)
    nu_s = math.floor(nu) if nu <= NU_INFINITE else math.inf
    assert gum["k"] == pytest.approx(stats.t.ppf(0.5 + 0.9545 / 2, nu_s), rel=1e-9)
    # the certified U: the table's worst-case offset plus t(ν_fit)·u_fit (u_fit the fit's line)
    bc = it["details"]["bound_condition"]
    assert bc["u_rest"] == pytest.approx(fit["u"], rel=1e-12)
    assert u["U"] == pytest.approx(bc["a_table"] + stats.t.ppf(0.5 + 0.9545 / 2, math.floor(
        fit["dof"] + 1e-9)) * fit["u"], rel=1e-9)
    assert u["interval"] == pytest.approx([it["value"] - u["U"], it["value"] + u["U"]])
    # the thermal programme (named by the readings' metadata) gives the model's items
    assert res["items"]["K_z_t1_v1"]["measured"] and res["items"]["b_z_t1_v1"]["measured"]
    assert res["extra"]["thermal_model"]["channels"]["z"]["scale"]["criterion"] == "bic"


def test_estimate_within_uncertainty_of_the_bench_truth(run):
    """The truth is the bench's M; |M̂ − M| ≤ U for nearly all of the nine elements
    (95 % each, a 5 % error in any element would miss by far)."""
    m_true = np.array(run["truth"]["system_matrix"])
    res = run["res"]["items"]
    inside = 0
    for i, a in enumerate(AX):
        for j, b in enumerate(AX):
            it = res[f"M_{a}{b}"]
            assert abs(it["value"] - m_true[i, j]) < 5 * it["uncertainty"]["U"], (a, b)
            inside += abs(it["value"] - m_true[i, j]) <= it["uncertainty"]["U"]
    assert inside >= 7


def test_certificate_shows_the_matrix_values_of_results_json(run):
    res, page = run["res"], run["html"]
    spans = {src: text for src, rule, text in SPANS.findall(page)}
    for a in AX:
        for b in AX:
            key = f"M_{a}{b}"
            it = res["items"][key]
            U_txt, dec = two_sig(it["uncertainty"]["U"])
            # the uncertainty table's U = a + k·u of the interval (no U span beside an interval)
            assert spans[f"items.{key}.details.bound_condition.U"] == U_txt
            assert f"items.{key}.uncertainty.U" not in spans
            assert spans[f"items.{key}.value"] == half_up(it["value"], dec)
    for key in ("b_z_t5_v2",):   # the certified points, value ± U (k)
        it = res["items"][key]
        U_txt, dec = two_sig(it["uncertainty"]["U"])
        assert spans[f"items.{key}.uncertainty.U"] == U_txt, key
        assert spans[f"items.{key}.value"] == half_up(it["value"], dec), key
        assert f"items.{key}.uncertainty.k" in spans, key
    for key in ("K_z_t1_v1", "K_z_t8_v3"):  # K: the bound-condition interval, k of the rest
        it = res["items"][key]
        U_txt, dec = two_sig(it["uncertainty"]["U"])
        lo, hi = it["uncertainty"]["interval"]
        q = Decimal(1).scaleb(-dec)
        ends = (str(Decimal(repr(lo)).quantize(q, rounding=ROUND_FLOOR)),
                str(Decimal(repr(hi)).quantize(q, rounding=ROUND_CEILING)))
        assert spans[f"items.{key}.value"] == half_up(it["value"], dec), key
        assert f"{spans[f'items.{key}.value']}</span> [{ends[0]}, {ends[1]}]" in page, key
        assert f"items.{key}.details.bound_condition.k_rest" in spans, key
        assert f"items.{key}.uncertainty.k" not in spans, key
    for src, rule, text in SPANS.findall(page):        # every span points at results.json
        assert lookup(res, src) is not None, src
    assert 'id="alignment-matrix"' in page and 'id="cross-axis"' in page
    assert 'id="thermal-z"' in page and 'id="points-K-z"' in page and 'id="points-b-z"' in page
    assert 'id="fig-alignment"' in page and 'id="fig-thermal-model-z"' in page
    text = html.unescape(re.sub(r"<[^>]+>", " ", re.sub(r"<svg.*?</svg>", " ", page, flags=re.S)))
    assert "Averaging time from the Allan deviation" in text
    assert "Bayesian information criterion" in text
    # the bench's readings state no room temperature: "not stated", with no unit after it
    assert "not stated" in text and not re.search(r"not stated\s*°C", text)


def test_certified_points_print_each_k_with_the_nu_it_was_computed_from(run):
    """Every k of the certified-points tables (K's k of the lines beside the table's bound,
    b's own k) is printed with its ν in brackets, and k = t_p(⌊ν⌋) recomputed with scipy from
    the printed ν and the stated p is the printed k: a k with no ν, or a ν other than the one
    k came from, fails."""
    from scipy import stats

    res, page = run["res"], run["html"]
    checked = 0
    for table in re.findall(r'id="points-[Kb]-[xyz]".*?</table>', page, flags=re.S):
        for k_src, k_txt, nu_src, nu_txt in re.findall(
                r'data-src="([^"]+\.k(?:_rest)?)" data-rule="k">([^<]*)</span>(?:\s|\u00a0|&nbsp;)\(<span '
                r'class="num" data-src="([^"]+)" data-rule="nu">([^<]*)</span>\)', table):
            base = k_src.rsplit(".", 1)[0]
            assert nu_src == base + (".nu_rest" if k_src.endswith("k_rest") else ".nu_eff")
            nu = math.floor(lookup(res, nu_src) + 1e-9)
            assert nu_txt == str(nu), (nu_src, nu_txt)
            key = k_src.split(".")[1]
            p = res["items"][key]["uncertainty"]["coverage_probability"]
            assert k_txt == f"{stats.t.ppf(0.5 + p / 2, int(nu_txt)):.2f}", (k_src, k_txt)
            checked += 1
        # no k cell without its ν
        assert len(re.findall(r'data-rule="k"', table)) == len(re.findall(r'data-rule="nu"',
                                                                          table))
    n_points = sum(1 for k in res["items"] if re.fullmatch(r"[Kb]_[xyz]_t\d+_v\d+", k)
                   and res["items"][k]["measured"])
    assert checked == n_points > 0


def _damaged(src: Path, dst: Path, edit) -> int:
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    out, edited = edit(lines)
    dst.write_text("".join(out), encoding="utf-8")
    return edited


def test_damaged_readings_give_items_not_measured_with_the_reason(run, tmp_path, capsys):
    src = run["dir"] / "sim" / "readings.csv"
    (tmp_path / "thermal.csv").write_text((run["dir"] / "sim" / "thermal.csv").read_text())

    def swap_sign(lines):             # the rate sign of one alignment dwell flipped
        head = next(i for i, s in enumerate(lines) if s.startswith("test,"))
        k = head + 3
        cells = lines[k].split(",")
        cells[6] = str(-float(cells[6]))
        lines[k] = ",".join(cells)
        return lines, k + 1
    line = _damaged(src, tmp_path / "swapped.csv", swap_sign)
    # as the rate specifications treat a typo: the dwell set aside, named, the rest
    # calibrated; M and b as from the same file with that dwell deleted (a second route)
    capsys.readouterr()
    assert main(["calibrate", str(tmp_path / "swapped.csv"), "--out", str(tmp_path / "sw")]) == 0
    err = capsys.readouterr()
    assert f"set aside: {tmp_path / 'swapped.csv'} line {line}" in err.out + err.err
    res = json.loads((tmp_path / "sw" / "results.json").read_text())
    (f,) = [f for f in res["findings"] if f["action"] == "set_aside"]
    assert f["line"] == line and "sign" in f["message"]
    lines = (tmp_path / "swapped.csv").read_text().splitlines(keepends=True)
    (tmp_path / "deleted.csv").write_text("".join(lines[:line - 1] + lines[line:]))
    from gonio.specs import get
    ref = get("triad-alignment").calibrate(tmp_path / "deleted.csv")
    for key in ("M_xx", "M_yz", "b_x", "b_z"):
        it = res["items"][key]
        assert it["measured"] and it["value"] == ref.items[key].value, key
        assert it["uncertainty"]["U"] == pytest.approx(ref.items[key].uncertainty.U, rel=1e-12)
    assert ref.items["M_xx"].value != pytest.approx(run["res"]["items"]["M_xx"]["value"],
                                                    rel=1e-15, abs=0)  # the dwell counts

    def two_typos(lines):             # two dwells' signs flipped: refused, naming a line
        lines, _ = swap_sign(lines)
        head = next(i for i, s in enumerate(lines) if s.startswith("test,"))
        cells = lines[head + 6].split(",")
        cells[6] = str(-float(cells[6]))
        lines[head + 6] = ",".join(cells)
        return lines, 0
    _damaged(src, tmp_path / "two.csv", two_typos)
    capsys.readouterr()
    assert main(["calibrate", str(tmp_path / "two.csv"), "--out", str(tmp_path / "tw")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gonio: error: ") and err.count("\n") == 1 and "set aside" in err
    assert not (tmp_path / "tw").exists()

    def drop_z(lines):                # no rotation about z: M's third column undetermined
        return [s for s in lines if not (s.startswith("alignment,") and ",+z," in s
                                         or s.startswith("alignment,") and ",-z," in s)], 0
    _damaged(src, tmp_path / "noz.csv", drop_z)
    assert main(["calibrate", str(tmp_path / "noz.csv"), "--out", str(tmp_path / "o")]) == 0
    res = json.loads((tmp_path / "o" / "results.json").read_text())
    m = res["items"]["M_xz"]
    assert not m["measured"] and "all three axes" in m["reason"]
    assert res["items"]["K_z_t1_v1"]["measured"]      # the thermal model still stands
    page = (tmp_path / "o" / "certificate.html").read_text(encoding="utf-8")
    assert "not measured" in page and "all three axes" in page

    def no_up(lines):                 # an orientation cell left empty: a format error
        head = next(i for i, s in enumerate(lines) if s.startswith("test,"))
        cells = lines[head + 1].split(",")
        cells[3] = ""
        lines[head + 1] = ",".join(cells)
        return lines, head + 2
    line = _damaged(src, tmp_path / "noup.csv", no_up)
    capsys.readouterr()
    # the triad has a DCC now (issue 25): --dcc writes it beside the certificate
    assert main(["calibrate", str(src), "--out", str(tmp_path / "o3"), "--dcc"]) == 0
    assert (tmp_path / "o3" / "certificate.dcc.xml").read_bytes().startswith(b"<?xml")
    assert main(["calibrate", str(tmp_path / "noup.csv"), "--out", str(tmp_path / "o2")]) == 2
    err = capsys.readouterr().err
    assert f"noup.csv:{line}" in err and "up" in err and len(err.strip().splitlines()) == 1


def test_readings_without_thermal_programme_say_so(run, tmp_path):
    src = run["dir"] / "sim" / "readings.csv"
    text = "".join(s for s in src.read_text().splitlines(keepends=True)
                   if not s.startswith("# thermal_readings:"))
    (tmp_path / "r.csv").write_text(text)
    from gonio.specs import get
    r = get("triad-alignment").calibrate(tmp_path / "r.csv")
    assert not r.items["thermal_model"].measured
    assert "no thermal programme" in r.items["thermal_model"].reason
    assert r.items["M_xx"].measured


def test_table_head_kept_with_its_first_rows():
    """A heading and a table placed where the page has room for the head and one row only:
    the head must move to the next page with its rows (short table: all of them)."""
    L = labels("en")

    def content(n_rows, n_lines):
        blocks = [Block("p", [f"filler line {i}"]) for i in range(n_lines)]
        blocks += [Block("sub", "THE TABLE"),
                   Block("table", (["HEADCOL", "b"], [[f"ROW{i}", "x"] for i in range(n_rows)]),
                         (0.5, 0.5))]
        return {"blocks": blocks, "id": "X", "virtual": False, "lab_name": "L"}

    def where(pages, token):
        for p, ops in enumerate(pages):
            for _, op in ops:
                for d in (op.__defaults__ or ()):
                    if token in repr(d):
                        return p
        return None
    hits = 0
    for n_lines in range(40, 75):
        for n_rows in (6, 20):
            pages = layout_pages(content(n_rows, n_lines), L)
            head = where(pages, "HEADCOL")
            first = [where(pages, f"ROW{i}") for i in range(min(n_rows, 8 if n_rows <= 8
                                                                else KEEP_FIRST_ROWS))]
            assert all(f == head for f in first), (n_lines, n_rows, head, first)
            assert where(pages, "THE TABLE") == head
            hits += head > 0
    assert hits > 0                   # some placements did push the table to page 2


def test_robust_fit_takes_the_swapped_dwell_and_names_it(run, tmp_path):
    """With --robust the dwell with the swapped sign is down-weighted and listed by its line,
    and M is recovered within its uncertainty of the bench's truth."""
    src = run["dir"] / "sim" / "readings.csv"
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    head = next(i for i, s in enumerate(lines) if s.startswith("test,"))
    cells = lines[head + 3].split(",")
    cells[6] = str(-float(cells[6]))
    lines[head + 3] = ",".join(cells)
    (tmp_path / "r.csv").write_text("".join(lines), encoding="utf-8")
    from gonio.specs import get
    with pytest.raises(GonioError, match="thermal_readings.*not there"):
        get("triad-alignment").calibrate(tmp_path / "r.csv", robust=True)   # named, missing
    (tmp_path / "thermal.csv").write_text((run["dir"] / "sim" / "thermal.csv").read_text())
    r = get("triad-alignment").calibrate(tmp_path / "r.csv", robust=True)
    flagged = {(o["line"], o["channel"]): o["weight"] for o in r.alignment.outliers}
    assert all(flagged.get((head + 4, c)) == 0.0 for c in ("out_x", "out_y", "out_z"))
    assert len({line for line, _ in flagged}) <= 3       # the bad dwell, at most a clean pair
    m_true = np.array(run["truth"]["system_matrix"])
    for i, a in enumerate(AX):
        it = r.items[f"M_{a}{a}"]
        assert it.measured and abs(it.value - m_true[i, i]) < 3 * it.uncertainty.U


def test_results_are_deterministic_and_zh_notes_complete(run):
    from gonio.specs import get
    from gonio.specs.triad_alignment.calibration import READINGS_TAKEN
    from gonio.specs.triad_alignment.certificate import READINGS_TAKEN_ZH, TEXT
    src = run["dir"] / "sim" / "readings.csv"
    a = get("triad-alignment").calibrate(src, monte_carlo_trials=50, seed=3).to_json()
    b = get("triad-alignment").calibrate(src, monte_carlo_trials=50, seed=3).to_json()
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
    assert len(READINGS_TAKEN_ZH) == len(READINGS_TAKEN)
    assert all(len(v) == 2 and v[1] for v in TEXT.values())


def test_short_paragraph_never_split():
    L = labels("en")
    para = "word " * 60                     # wraps to a few lines
    for n_lines in range(40, 75):
        blocks = [Block("p", [f"filler line {i}"]) for i in range(n_lines)]
        blocks += [Block("sub", "HEADING"), Block("p", ["PARA " + para])]
        pages = layout_pages({"blocks": blocks, "id": "X", "virtual": False, "lab_name": "L"}, L)
        where = [p for p, ops in enumerate(pages) for _, op in ops
                 if any("PARA" in repr(d) or "word word" in repr(d)
                        for d in (op.__defaults__ or ()))]
        assert len(set(where)) == 1 and len(where) >= 2, (n_lines, where)


@pytest.mark.parametrize("old,new,key,var", [
    ("duration_s = 300.0", "duration_s = 1e9", "static.duration_s", "GONIO_MAX_READING_ROWS"),
    ("soak_s = 1800.0", "soak_s = 1e12", "thermal.soak_s", "GONIO_MAX_SAMPLES"),
])
def test_triad_programme_beyond_the_limits_is_refused_naming_the_key(tmp_path, capsys, old, new,
                                                                     key, var):
    """Issue 14 for the triad bench: a typo of 10⁹ s or 10¹² s in a protocol is refused in
    one line naming the protocol key and the limit, before any large allocation, nothing
    written (it ran out of memory before)."""
    from pathlib import Path

    from gonio.cli import main

    text = (Path(__file__).parents[1] / "protocols" / "triad-alignment.toml").read_text()
    assert old in text
    p = tmp_path / "p.toml"
    p.write_text(text.replace(old, new, 1))
    rc = main(["simulate", "--spec", "triad-alignment", "--protocol", str(p),
               "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert key in err[0] and var in err[0]
    assert not (tmp_path / "o").exists()


def test_environment_states_the_chamber_profile(run):
    """The triad's environment block had no chamber-profile row (leftover 5): the set points
    the thermal programme soaked at, read here from thermal.csv's soak rows, are stated
    there; a calibration without a thermal programme states none."""
    import pandas as pd
    from gonio.report.i18n import labels

    th = pd.read_csv(run["dir"] / "sim" / "thermal.csv", comment="#")
    points = list(dict.fromkeys(round(float(x), 1) for x in th[th["phase"] == "soak"]["chamber_c"]))
    assert len(points) >= 3
    want = (", ".join(f"{x:g}" for x in points) + " °C").replace("-", "\u2212")
    assert run["res"]["extra"]["chamber_profile_c"] == points
    L = labels("en")
    row = re.search(rf"<td>{re.escape(html.escape(L['chamber_profile']))}</td><td>([^<]*)</td>",
                    run["html"])
    assert row is not None and row[1] == html.escape(want), row


def test_every_column_has_its_own_k_and_p_is_stated_alike(run):
    """The matrix table's b cell states b's own k (the row's k column is M's); S and L in ‰
    carry their k; one p everywhere: the k are t for the p results.json carries (0.9545),
    and the certificate (en, zh notes), summary.txt and the DCC state that same p
    ("95.45 %", si:coverageProbability 0.9545), never "approximately 95 %" beside it."""
    res, page = run["res"], run["html"]
    spans = [(src, text) for src, rule, text in SPANS.findall(page)]
    srcs = [s for s, _ in spans]
    for a in AX:
        assert f"items.b_{a}.uncertainty.k" in srcs          # b's own k in its cell
        k_b = dict(spans)[f"items.b_{a}.uncertainty.k"]
        assert float(k_b) == pytest.approx(res["items"][f"b_{a}"]["uncertainty"]["k"], rel=5e-3)
    for a in AX:                                # M's rows: the bound statement's own k
        for b in AX:
            assert f"items.M_{a}{b}.details.bound_condition.k_rest" in srcs
            assert f"items.M_{a}{b}.uncertainty.k" not in srcs
    for p in ("xy", "xz", "yx", "yz", "zx", "zy"):  # S and L: the interval, no k of the whole
        assert f"items.S_{p}.uncertainty.k" not in srcs
        assert f"items.L_{p}.uncertainty.k" not in srcs
    ps = {it["uncertainty"]["coverage_probability"] for k, it in res["items"].items()
          if it.get("uncertainty") and it["uncertainty"].get("U") is not None}
    # one p for every item, the ARW's one-sided χ² interval (a dispersion, no k) included
    assert ps == {0.9545}, ps
    assert any(k.startswith("ARW_") for k in res["items"])
    stated = "95.45"
    text = html.unescape(re.sub(r"<[^>]+>", " ", re.sub(r"<svg.*?</svg>", " ", page, flags=re.S)))
    # p is chosen (the k are t for it): "p = 95.45 %", never "approximately 95.45 %"
    assert f"p = {stated} %" in text and "p = 95 %" not in text     # one p on the page
    assert not re.search(r"(approximately|≈|约) ?95(\.45)? %", text)
    summary = (run["dir"] / "cal" / "summary.txt").read_text(encoding="utf-8")
    assert f"p = {stated} %" in summary and not re.search(r"≈ ?95(\.45)? %", summary)
    dcc = run["dir"] / "cal" / "certificate.dcc.xml"
    if dcc.exists():
        xml = dcc.read_text(encoding="utf-8")
        assert 'id="result-ARW_' in xml
        got = set(re.findall(r"<si:coverageProbability>([^<]*)<", xml))
        assert got and {float(x) for x in got} == {float(stated) / 100}, got
    from gonio.specs.triad_alignment.certificate import READINGS_TAKEN_ZH, TEXT
    zh = " ".join(READINGS_TAKEN_ZH) + " ".join(v[1] for v in TEXT.values())
    assert f"p = {stated} %" in zh and not re.search(r"约 ?95(\.45)? %", zh)
    assert "p = 95 %" not in zh and "p = 95 %" not in summary


def test_bias_monte_carlo_is_of_the_same_long_term_quantity_as_the_gum(run):
    """b's GUM u is long-term (the fit plus the bias instability over a day); its Monte Carlo
    refits this record only. The Monte Carlo u kept (not certified) in the details is the
    refits' u with the same bias-instability term in quadrature, so it is of the same
    quantity: the refits agree with the fit's own line, and the totals agree."""
    for a in AX:
        unc = run["res"]["items"][f"b_{a}"]["uncertainty"]
        mc = run["res"]["items"][f"b_{a}"]["details"]["not_certified"]["monte_carlo"]
        assert "monte_carlo" not in unc and mc["status"] == "not certified"
        comp = {c["symbol"]: c["u"] for c in unc["components"]}
        assert mc["u_long_term"] == pytest.approx(comp[f"b_{a}_BI"], rel=1e-12)
        assert mc["u_long_term"] > 2 * mc["u_fit"]            # the term the refits lack
        fit_gum = np.sqrt(unc["u_c"] ** 2 - comp[f"b_{a}_BI"] ** 2)
        assert 0.75 < mc["u_fit"] / fit_gum < 1.33              # 300 refits vs the fit's u
        assert 0.9 < mc["u"] / unc["u_c"] < 1.1
        assert mc["u"] == pytest.approx(np.hypot(mc["u_fit"], mc["u_long_term"]), rel=1e-12)


def test_one_statement_per_item_everywhere(run):
    """Every item has one statement: M, S, L and K(ϑ, U) the bound-condition interval, the
    others value ± U with their k. The certificate has no second column (no "U (bound)",
    no Monte Carlo, no GUM U beside the certified one); summary.txt, items.csv and the DCC
    state the same interval ends; results.json keeps the other readings in the details as
    "not certified"."""
    import csv

    res, page = run["res"], run["html"]
    text = html.unescape(re.sub(r"<[^>]+>", " ", re.sub(r"<svg.*?</svg>", " ", page, flags=re.S)))
    for gone in ("U (bound)", "Two statements", "u (Monte Carlo)", "U Monte Carlo", "u (GUM)",
                 "This certificate certifies"):
        assert gone not in text, gone
    assert "One statement per item" in text
    cal = run["dir"] / "cal"
    summary = (cal / "summary.txt").read_text(encoding="utf-8")
    dcc = (cal / "certificate.dcc.xml").read_text(encoding="utf-8")
    rows = {r["item"]: r for r in csv.DictReader((cal / "tables" / "items.csv").open(
        encoding="utf-8"))}
    bound_keys = [k for k in res["items"] if k[:2] in ("M_", "S_", "L_") or k.startswith("K_")]
    assert len(bound_keys) == 9 + 6 + 6 + 24
    # summary.txt lists the items in results.json's order; the interval lines are these
    stated = re.findall(r"interval \[([^,]+), ([^\]]+)\]", "\n".join(
        ln for ln in summary.splitlines() if "angle random walk" not in ln))
    assert len(stated) == len(bound_keys)
    for key, (s_lo, s_hi) in zip(bound_keys, stated):
        it = res["items"][key]
        u = it["uncertainty"]
        assert u["k"] is None and "gum" not in it["details"], key
        assert it["details"]["not_certified"]["gum"]["status"] == "not certified", key
        lo, hi = u["interval"]
        block = dcc[dcc.index(f'id="result-{key}"'):]
        block = block[:block.index("</dcc:result>")]
        assert "expandedMU" not in block and "coverageFactor" not in block, key
        ends = re.search(r"<si:labelXMLList>intervalMin intervalMax</si:labelXMLList>\s*"
                         r"<si:valueXMLList>([^<]+)<", block)[1].split()
        d_lo, d_hi = ends
        assert (float(s_lo.replace("−", "-")), float(s_hi.replace("−", "-"))) == (
            float(d_lo), float(d_hi)), key
        step = 10.0 ** math.floor(math.log10(abs(hi - lo)) - 2)
        assert float(d_lo) <= lo + 1e-12 and float(d_lo) > lo - 10 * step, key
        assert float(d_hi) >= hi - 1e-12 and float(d_hi) < hi + 10 * step, key
        assert rows[key]["U"] == "" and rows[key]["k"] == "", key
        assert float(rows[key]["interval_low"]) == pytest.approx(lo, rel=1e-12)
    for key in ("b_x", "b_z_t1_v1"):
        u = res["items"][key]["uncertainty"]
        assert u["k"] is not None and u.get("interval") is None, key


def test_dcc_states_no_uncertainty_the_certificate_does_not(run, dcc_schema):
    """The DCC states an item's standard uncertainty (si:valueStandardMU) only where the
    certificate states that item's u_c: the bound-condition items (M, S, L, K(ϑ, U)) are
    certified by value ± (a + k·u), their row states a, u of the other lines, ν and k, and
    their JCGM 100 u_c is kept in results.json "not certified" — the DCC writes their
    interval's ends (p = 95.45 %) without a standard uncertainty. The DCC is valid against
    the carried DCC 3.3.0 schema."""
    res, page = run["res"], run["html"]
    dcc_path = run["dir"] / "cal" / "certificate.dcc.xml"
    dcc = dcc_path.read_text(encoding="utf-8")
    dcc_schema.validate(str(dcc_path))
    on_cert = {src.split(".")[1] for src, _, _ in SPANS.findall(page)
               if src.startswith("items.") and src.endswith(".uncertainty.u_c")}
    blocks = {m[1]: m[2] for m in re.finditer(
        r'<dcc:result id="result-([^"]+)">(.*?)</dcc:result>', dcc, flags=re.S)}
    stated_u = {k for k, b in blocks.items() if "valueStandardMU" in b}
    assert stated_u <= on_cert, sorted(stated_u - on_cert)[:5]
    assert "valueStandardMUXMLList" not in dcc or all(
        k in on_cert for k in res["items"] if k.startswith("M_"))
    bound = [k for k, it in res["items"].items()
             if (it.get("details") or {}).get("bound_condition")]
    assert bound
    for key in bound:
        b = blocks[key]
        assert "valueStandardMU" not in b and "intervalMin intervalMax" in b, key
        assert "p = 95.45 %" in b, key


def test_arw_is_stated_by_its_one_sided_chi2_bound_alone_everywhere(run):
    """ARW(ϑ) at a set point is a dispersion (the static dwells' sample standard deviations):
    one statement, the one-sided χ² interval at the certificate's one p = 95.45 %,
    [0, N·√(ν/χ²_0.0455,ν)] with ν = ½(N/u_c)²
    (computed here by scipy's χ² from the stored N and budget, ν as stated: its integer part),
    no k, no "± U" — the same
    upper end on the certificate's ARW table, in summary.txt, in the DCC (intervalMin 0,
    intervalMax, p 0.9545) and in results.json's upper_bound. Its budget holds the dwells' χ²
    under white rate noise and the bias-instability lift correction (half the full-band
    lift, value = uncorrected·√(1 − x/2))."""

    from scipy.stats import chi2

    res, page = run["res"], run["html"]
    cal = run["dir"] / "cal"
    summary = (cal / "summary.txt").read_text(encoding="utf-8")
    dcc = (cal / "certificate.dcc.xml").read_text(encoding="utf-8")
    table = page[page.index('id="points-ARW-z"'):]
    table = html.unescape(re.sub(r"<[^>]+>", " ", table[:table.index("</table>")])).replace(
        "\u00a0", " ")
    assert "± " not in table and "k =" not in table
    spans = {src: text for src, rule, text in SPANS.findall(page)}
    keys = [k for k in res["items"] if k.startswith("ARW_")]
    assert len(keys) == 8
    for key in keys:
        it = res["items"][key]
        u = it["uncertainty"]
        assert u["k"] is None and u["k_source"] == "chi-square" and u["coverage_probability"] == 0.9545
        assert it["nonnegative"] is True
        u_c = math.sqrt(sum(c["u"] ** 2 for c in u["components"]))
        assert u["u_c"] == pytest.approx(u_c, rel=1e-12)
        nu = 0.5 * (it["value"] / u_c) ** 2
        nu_s = max(1, math.floor(nu))   # as stated and as the bound is computed, never ∞
        hi = it["value"] * math.sqrt(nu_s / chi2.ppf(1 - 0.9545, nu_s))
        assert u["interval"][0] == 0.0 and u["interval"][1] == pytest.approx(hi, rel=1e-9), key
        syms = [c["symbol"] for c in u["components"]]
        assert syms[:2] == [f"{key}_chi2", f"{key}_BI"], syms
        d = it["details"]
        assert it["value"] == pytest.approx(d["arw_uncorrected"]
                                            * math.sqrt(1 - d["lift_full_rel_var"] / 2), rel=1e-12)
        # the printed upper end: rounded up at its stated decimal place, the same everywhere
        dec = len(spans[f"items.{key}.value"].partition(".")[2])   # the value's place
        up = str(Decimal(repr(hi)).quantize(Decimal(1).scaleb(-dec), rounding=ROUND_CEILING))
        assert float(up) == it["upper_bound"], key
        assert f"≤ {up} (p = 95.45 %)" in table, key
        line = next(ln for ln in summary.splitlines() if key in ln or
                    f"at {it['details']['setpoint_c']:g} °C:" in ln and "angle random walk" in ln)
        assert f"upper bound: ≤ {up} °/√h (interval [0, {up}], p = 95.45 %)" in line, line
        assert "±" not in line and "k =" not in line, line
        block = dcc[dcc.index(f'id="result-{key}"'):]
        block = block[:block.index("</dcc:result>")]
        assert f"<si:intervalMax>{up}</si:intervalMax>" in block, key
        assert "<si:coverageProbability>0.9545<" in block and "coverageFactor" not in block, key
