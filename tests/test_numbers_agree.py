"""One number per item across every output. For each of the four built-in specifications a
small virtual programme is calibrated once (``gonio calibrate --dcc``, English) and its stored
results.json rendered again in Chinese (the renderer is a pure function of the stored Result).
Every measured item's statement is then parsed back, field by field, from every output that
prints it — summary.txt, the certificate's HTML (en, zh), the DCC (en, zh) — and from the
full-precision files (results.json, tables/items.csv):

- the printed outputs state the item the same way (one ± U, or one interval) and agree on
  every number each of them prints: the value, U, k, ν, p, the interval's ends;
- each printed number is results.json's number as printed (within one unit of its last
  digit: half a unit by rounding, a whole unit where a bound is rounded outwards), the value
  inside its own interval and, for a quantity that cannot be negative, not below zero;
- items.csv holds results.json's numbers, and its ν is the ν printed beside k.

Nothing here is hard-coded: the numbers come from the calibration, the parsing is written
here (not gonio's display code), so a renderer that rounds, picks or signs a number
differently from the others fails."""

from __future__ import annotations

import csv
import html as html_mod
import json
import math
import re
from decimal import Decimal

import pytest
from lxml import etree

from gonio.cli import main
from gonio.report.dcc import DCC_NS, SI_NS
from gonio.result.statement import K_SOURCE_MAX_ABS as MAX_ABS

NS = {"dcc": DCC_NS, "si": SI_NS}
SPECS = ("ogam-draft", "jjf1535-2015", "iec62047-20", "triad-alignment")
SMALL = "tests/data/small-protocol.toml"
PRINTED = ("summary", "html-en", "html-zh", "dcc-en", "dcc-zh")

# --------------------------------------------------------------------------- the runs


def _readings(key: str, d):
    """The calibrate arguments of a small virtual programme of ``key`` written into ``d``."""
    if key == "ogam-draft":
        assert main(["simulate", "--protocol", SMALL, "--seed", "2411", "--out",
                     str(d / "sim")]) == 0
        return [str(d / "sim" / "readings.csv"), "--protocol", SMALL]
    if key == "triad-alignment":
        assert main(["simulate", "--spec", key, "--bench", "mems-triad", "--out",
                     str(d / "sim")]) == 0
        return [str(d / "sim" / "readings.csv")]
    from tests.test_rate_dcc import _simulate
    _, proto, path, _ = _simulate(key, d, 5)
    return [str(path), "--protocol", str(proto)]


@pytest.fixture(scope="module", params=SPECS)
def run(request, tmp_path_factory):
    import contextlib
    import io

    from gonio.result.model import Result
    from gonio.specs import get

    key = request.param
    d = tmp_path_factory.mktemp(key)
    args = _readings(key, d)
    en, zh = d / "en", d / "zh"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["calibrate", *args, "--dcc", "--out", str(en)]) == 0
    res = json.loads((en / "results.json").read_text(encoding="utf-8"))
    get(key).renderer().write(Result.from_json(res), zh, lang="zh", dcc=True)
    with open(en / "tables" / "items.csv", newline="", encoding="utf-8") as f:
        rows = {r["item"]: r for r in csv.DictReader(f)}
    return {"key": key, "res": res, "csv": rows,
            "summary": (en / "summary.txt").read_text(encoding="utf-8"),
            "html-en": (en / "certificate.html").read_text(encoding="utf-8"),
            "html-zh": (zh / "certificate.html").read_text(encoding="utf-8"),
            "dcc-en": (en / "certificate.dcc.xml").read_bytes(),
            "dcc-zh": (zh / "certificate.dcc.xml").read_bytes()}


def measured(res: dict) -> dict:
    return {k: it for k, it in res["items"].items()
            if it["measured"] and it["value"] is not None and it.get("uncertainty")
            and it["uncertainty"].get("U") is not None}


# --------------------------------------------------------------------------- parsing

_SUP = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")
_NUM = r"[−\-+]?\d+(?:\.\d+)?(?:×10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)?"


def number(text: str) -> Decimal:
    """A printed number ("−1.5×10⁻⁴", "+0.11", "∞") as a Decimal (infinite for ∞)."""
    t = text.strip().replace("\u2212", "-").replace("\xa0", "").replace(" ", "")
    if t in ("∞", "inf"):
        return Decimal("Infinity")
    mant, _, exp = t.partition("×10")
    try:
        d = Decimal(mant)
    except ArithmeticError:
        raise AssertionError(f"not a number: {text!r}") from None
    return d.scaleb(int(exp.translate(_SUP))) if exp else d


def last_digit(text: str) -> Decimal:
    """One unit of the last printed digit of ``text``."""
    d = number(text)
    return Decimal(1).scaleb(d.as_tuple().exponent)


def statement_fields(text: str) -> dict:
    """The numbers of one item's statement in a line or cell of text (English or Chinese):
    value (first number unless the text opens with an upper bound), U (after ±), k, ν, p,
    the interval's ends (``[lo, hi]``, or ``≤ hi`` from the natural bound 0)."""
    t = html_mod.unescape(text).replace("\xa0", " ")
    for zh, en in (("；", "; "), ("：", ": "), ("（", " ("), ("）", ")"), ("，", ", "),
                   ("上限", "upper bound"), ("区间", "interval")):
        t = t.replace(zh, en)
    out: dict = {}
    m = re.match(r"\s*(" + _NUM + ")", t)
    if m and not re.match(r"\s*(upper bound|≤)", t):
        out["value"] = m.group(1)
    for field, pat in (("U", r"± (" + _NUM + ")"), ("k", r"\bk = (" + _NUM + ")"),
                       ("nu", r"ν(?:_eff)? = (" + _NUM + "|∞)"),
                       ("p", r"p [=≈] (" + _NUM + ") ?%")):
        found = set(re.findall(pat, t))
        if found:
            out[field] = found
    ivs = set(re.findall(r"\[(" + _NUM + r"), (" + _NUM + r")\]", t))
    ivs |= {("0", hi) for hi in re.findall(r"≤ (" + _NUM + ")", t)}
    if ivs:
        out["interval"] = ivs
    return out


def _one(found: dict, where: str) -> dict:
    """Each field's one text (a field printed twice with different numbers fails)."""
    out = {}
    for f, v in found.items():
        if isinstance(v, set):
            nums = {tuple(number(x) for x in e) if isinstance(e, tuple) else number(e)
                    for e in v}
            assert len(nums) == 1, f"{where}: {f} printed as {sorted(map(str, v))}"
            v = sorted(v)[0]
        out[f] = v
    return out


def summary_fields(run: dict) -> dict:
    """item → its statement's fields in summary.txt."""
    lines = run["summary"].splitlines()
    out = {}
    items = list(run["res"]["items"])
    table = [ln for ln in lines if re.match(r"\d+  ", ln)]
    for key, it in measured(run["res"]).items():
        if table:                      # the optical draft's fixed-width table
            row = next(ln for ln in table if int(ln.split()[0]) == items.index(key) + 1)
            cols = re.split(r"\s{2,}", row.strip())
            text = cols[3] + (" ± " + cols[4] if cols[4] != "—" else "")
        else:
            hits = [ln for ln in lines if f" {it['title']}: " in ln]
            assert len(hits) == 1, (key, hits)
            text = hits[0].split(f" {it['title']}: ", 1)[1]
        text = re.sub(r"\(signed extreme.*?\)", "", text)
        out[key] = _one(statement_fields(text), f"summary {key}")
    return out


_CELL = re.compile(r"<(td|tr)\b[^>]*>((?:(?!</\1>).)*)</\1>", re.S)


def html_fields(html: str, res: dict) -> dict:
    """item → its statement's fields in the certificate: every table cell (or row, where
    the row is the item's alone) that holds the item's value span, its spans and its text;
    the table of the draft's readings "given beside and not certified" is no statement."""
    out = {}
    html = re.sub(r'<table id="beside">.*?</table>', "", html, flags=re.S)
    rows = re.findall(r"<tr\b[^>]*>(?:(?!</tr>).)*</tr>", html, re.S)
    for key, it in measured(res).items():
        src = "details.max_abs_arcsec" if it["uncertainty"].get("k_source") == \
            "max-abs-interval" else "value"
        span = f'data-src="items.{key}.{src}"'
        bound = f'data-src="items.{key}.upper_bound"'     # a bound printed alone
        found: dict = {}
        for row in rows:
            if span not in row and bound not in row:
                continue
            own = set(re.findall(r'data-src="items\.(\w+)\.(?:value|uncertainty)', row))
            if own - {key}:           # a matrix row: the item's own cell
                cells = [c for _, c in _CELL.findall(row[3:]) if span in c or bound in c]
                if not cells:
                    continue
                row = cells[0]
            cells = re.findall(r"<td\b[^>]*>(.*?)</td>", row, re.S)
            # a budget row (a, u, ν, k of the lines) is no statement
            if any('uncertainty.u_c"' in c or "bound_condition" in c for c in cells):
                continue
            spans = dict((w, t) for w, t in re.findall(
                r'data-src="items\.' + re.escape(key) + r'\.([\w.]+)" data-rule="[^"]+">'
                r"([^<]*)<", row))
            text = re.sub(r"<[^>]+>", " ", row)
            text = re.sub(r"signed extreme.*?(″|°)", "", text)
            text = re.sub(r"\(at [^)]*\)|（在[^）]*）", "", text)
            f = statement_fields(" ".join(text.split()))
            f.pop("value", None)
            if src in spans:
                f["value"] = {spans[src]}
            for w, fld in (("uncertainty.U", "U"), ("uncertainty.k", "k"),
                           ("uncertainty.nu_eff", "nu")):
                if w in spans:
                    f[fld] = {spans[w]}
            for fld, v in f.items():
                found.setdefault(fld, set()).update(v)
        if found:
            out[key] = _one(found, f"certificate {key}")
    return out


def dcc_fields(doc: bytes, res: dict) -> dict:
    """item → its statement in the DCC (the result's measured quantity's si:real), its
    numbers divided back by a unit factor the DCC states."""
    root = etree.fromstring(doc)
    out = {}
    for key in measured(res):
        r = root.find(f".//dcc:result[@id='result-{key}']", NS)
        if r is None:
            continue
        q = r.find(".//dcc:quantity", NS)
        real = q.find("si:real", NS)
        if real is None and q.findtext("si:realListXMLList/si:labelXMLList", None, NS) \
                == "intervalMin intervalMax":
            # an item stated by its upper bound alone (its estimate below zero): the
            # interval [0, bound] and its p, no value (the certificate states none)
            lo, hi = q.findtext("si:realListXMLList/si:valueXMLList", None, NS).split()
            p = re.search(r"p = (\S+) %", "".join(q.find("dcc:name", NS).itertext()))[1]
            out[key] = {"interval": (lo, hi), "p": p, "factor": None}
            continue
        note = " ".join(c.text for c in q.iter(etree.Comment))
        m = re.search(r"factor=([0-9.eE+-]+)", note)
        factor = Decimal(m.group(1)) if m else None

        def get(path, real=real):
            e = real.find(path, NS)
            return None if e is None else e.text.strip()
        f = {"value": get("si:value")}
        if get(".//si:expandedMU") is not None or real.find(".//si:expandedMU", NS) is not None:
            f |= {"U": get(".//si:valueExpandedMU"), "k": get(".//si:coverageFactor"),
                  "p": get(".//si:coverageProbability")}
        iv = real.find(".//si:coverageIntervalMU", NS)
        nxt = q.getnext()
        if iv is None and nxt is not None and nxt.findtext(
                "si:realListXMLList/si:labelXMLList", None, NS) == "intervalMin intervalMax":
            # a bound-condition interval: its ends, its p in the name, no standard uncertainty
            lo, hi = nxt.findtext("si:realListXMLList/si:valueXMLList", None, NS).split()
            p = re.search(r"p = (\S+) %", "".join(nxt.find("dcc:name", NS).itertext()))[1]
            f |= {"interval": (lo, hi), "p": str(Decimal(p).scaleb(-2))}
        if iv is not None:
            f |= {"interval": (get(".//si:intervalMin"), get(".//si:intervalMax")),
                  "p": get(".//si:coverageIntervalMU/si:coverageProbability"),
                  "u_std": get(".//si:valueStandardMU")}
        f = {k: v for k, v in f.items() if v is not None}
        if "p" in f:
            f["p"] = str(Decimal(f["p"]) * 100).rstrip("0").rstrip(".")
        f["factor"] = factor
        out[key] = f
    return out


# --------------------------------------------------------------------------- the checks


def _raw(it: dict) -> dict:
    """results.json's numbers of an item's statement, by field."""
    u = it["uncertainty"]
    v = it["details"]["max_abs_arcsec"] if u.get("k_source") == "max-abs-interval" \
        else it["value"]
    out = {"value": v, "U": u["U"], "k": u.get("k"), "p": 100 * u["coverage_probability"]
           if u.get("coverage_probability") is not None else None}
    if u.get("interval") is not None:
        out["interval"] = tuple(u["interval"])
    elif it.get("nonnegative") and u["U"] > v:     # [0, value + U]: it cannot be negative
        out["interval"] = (0.0, v + u["U"])
    return out


@pytest.fixture(scope="module")
def printed(run):
    return {"summary": summary_fields(run),
            "html-en": html_fields(run["html-en"], run["res"]),
            "html-zh": html_fields(run["html-zh"], run["res"]),
            "dcc-en": dcc_fields(run["dcc-en"], run["res"]),
            "dcc-zh": dcc_fields(run["dcc-zh"], run["res"])}


def _as_number(v):
    if isinstance(v, tuple):
        return tuple(number(x) for x in v)
    return number(v)


def test_every_output_states_every_measured_item(run, printed):
    for key in measured(run["res"]):
        missing = [w for w in PRINTED if key not in printed[w]]
        assert not missing, f"{run['key']} {key}: not stated in {missing}"


def test_printed_outputs_state_each_item_the_same_way(run, printed):
    """One kind of statement per item (± U with k, or one interval) in every output, and
    every number printed in two outputs the same number."""
    for key in measured(run["res"]):
        kinds = {w: ("interval" if "interval" in printed[w][key] else "U")
                 for w in PRINTED if key in printed[w]}
        assert len(set(kinds.values())) == 1, f"{run['key']} {key}: stated as {kinds}"
        for w in PRINTED:
            f = printed[w].get(key, {})
            assert not ("interval" in f and "U" in f), \
                f"{run['key']} {key}: {w} states ± U beside an interval: {f}"
        for field in ("value", "U", "k", "nu", "p", "interval"):
            seen = {}
            for w in PRINTED:
                f = printed[w].get(key, {})
                if field not in f:
                    continue
                n = _as_number(f[field])
                fac = f.get("factor")
                if fac and field in ("value", "U", "interval"):
                    n = tuple(x / fac for x in n) if isinstance(n, tuple) else n / fac
                    n = tuple(round(x, 8) for x in n) if isinstance(n, tuple) else round(n, 8)
                    continue        # a per-g item written per m s⁻²: compared with results.json
                seen[w] = n
            assert len(set(seen.values())) <= 1, \
                f"{run['key']} {key}: {field} differs between outputs: {seen}"


def _close(text, raw: float, where: str, outward: bool = False,
           unit: Decimal | None = None) -> None:
    got = number(text)
    unit = max(last_digit(text), unit or Decimal(0))
    if math.isinf(raw):
        assert got.is_infinite(), where
        return
    tol = unit * (1 if outward else Decimal("0.5")) + Decimal(abs(raw)) * Decimal("1e-12")
    assert abs(got - Decimal(repr(raw))) <= tol, f"{where}: printed {text}, results.json {raw}"


def test_printed_numbers_are_results_json_as_printed(run, printed):
    """Each printed number is results.json's number rounded at the printed digit (a
    bound one unit outwards at most); the printed value lies inside its own interval, and a
    quantity that cannot be negative is printed with no negative value."""
    for key, it in measured(run["res"]).items():
        raw = _raw(it)
        for w in PRINTED:
            f = printed[w].get(key)
            if not f or f.get("factor"):
                continue
            where = f"{run['key']} {key} {w}"
            # "820 ± 110": U at two significant digits, the value at U's decimal place
            # (an interval's value: at the decimal place of two digits of its width, "50; ≤ 220")
            ref = number(f["U"]) if "U" in f else (
                number(f["interval"][1]) - number(f["interval"][0]) if "interval" in f else 0)
            at_U = Decimal(1).scaleb(ref.adjusted() - 1) if ref else None
            below = it.get("nonnegative") and raw["value"] < 0
            if below and "value" in f:      # stated by its bound alone: that bound, as printed
                assert "interval" in f and number(f["value"]) == number(f["interval"][1]), \
                    f"{where}: value {f['value']} of an estimate below zero is not its bound"
            for field in ("value", "U", "k"):
                if field == "value" and below:
                    continue
                if field in f and raw.get(field) is not None:
                    _close(f[field], raw[field], f"{where} {field}",
                           unit=at_U if field != "k" else None)
            if "p" in f:    # a computed p is printed rounded down (never overstated)
                got = number(f["p"])
                assert got <= Decimal(repr(raw["p"])) + Decimal("1e-9") and \
                    _close(f["p"], raw["p"], f"{where} p", outward=True) is None, where
            if "interval" in f:
                assert "interval" in raw, f"{where}: an interval results.json does not hold"
                lo, hi = f["interval"]
                _close(lo, raw["interval"][0], f"{where} interval low", True, at_U)
                _close(hi, raw["interval"][1], f"{where} interval high", True, at_U)
                if "value" in f:
                    assert number(lo) <= number(f["value"]) <= number(hi), \
                        f"{where}: value {f['value']} outside its interval [{lo}, {hi}]"
            if it.get("nonnegative") and "value" in f:
                assert number(f["value"]) >= 0, \
                    f"{where}: a non-negative quantity printed as {f['value']}"


def test_nu_printed_is_the_nu_k_was_computed_from(run, printed):
    """ν beside k in every output is one number, items.csv's ``nu``, and k is Student's t
    of it (scipy) or, for ν ∞, the normal quantile."""
    from scipy.stats import norm, t

    for key, it in measured(run["res"]).items():
        row = run["csv"][key]
        nus = {w: number(printed[w][key]["nu"]) for w in PRINTED
               if "nu" in printed[w].get(key, {})}
        if row["nu"] not in ("", None):
            for w, nu in nus.items():
                assert nu == Decimal(row["nu"]) or (nu.is_infinite() and row["nu"] == "inf"), \
                    f"{run['key']} {key}: ν {nu} in {w}, items.csv {row['nu']}"
        u = it["uncertainty"]
        if not nus or u.get("k") is None or u.get("k_source") in (
                "fixed", "jcgm101-convolution") or "interval" in printed["summary"][key]:
            continue
        nu = next(iter(nus.values()))
        q = 0.5 + u["coverage_probability"] / 2
        k = norm.ppf(q) if nu.is_infinite() else t.ppf(q, float(nu))
        assert u["k"] == pytest.approx(k, rel=1e-6), (run["key"], key, nu, u["k"], k)


def test_items_csv_holds_results_json_numbers(run):
    """items.csv: results.json's numbers at full precision; an item stated by its interval
    has its ends and no U/k, an item stated by ± U has no interval."""
    for key, it in measured(run["res"]).items():
        row, raw = run["csv"][key], _raw(it)
        where = f"{run['key']} {key} items.csv"
        if row["interval_low"] not in ("", None):
            assert "interval" in raw, where
            assert (float(row["interval_low"]), float(row["interval_high"])) == \
                pytest.approx(raw["interval"], rel=1e-12, abs=1e-300), where
            assert row["U"] == "" and row["k"] == "", where
        else:
            assert float(row["U"]) == pytest.approx(raw["U"], rel=1e-12), where
            assert float(row["k"]) == pytest.approx(raw["k"], rel=1e-12), where
        if row["value"] not in ("", None):
            assert float(row["value"]) == pytest.approx(raw["value"], rel=1e-12), where
        p = it["uncertainty"].get("p_stated")        # "p ≈ 99.6 %": the p printed
        want = float(number(re.search(_NUM, p).group(0))) if p else raw["p"]
        assert float(row["p"]) * 100 == pytest.approx(want, rel=1e-12), where


def test_items_csv_states_no_u_the_certificate_does_not(run):
    """An extreme of magnitudes stated by its interval (the optical E) has no u in items.csv:
    the certificate says no combined standard uncertainty of E is certified, and the u_c of
    the extreme's point (results.json keeps it) is no u of max|E_i|."""
    for key, it in measured(run["res"]).items():
        if it["uncertainty"].get("k_source") == MAX_ABS:
            assert run["csv"][key]["u"] in ("", None), (key, run["csv"][key]["u"])


def test_the_parsing_can_fail():
    """The parser reads a second, different statement as a disagreement."""
    with pytest.raises(AssertionError):
        _one(statement_fields("0.15; ≤ 0.67 (p = 95 %); ≤ 0.68 (p = 95 %)"), "x")
    f = statement_fields("−1.5×10⁻⁴ ± 2.0×10⁻⁵ (k = 2.01, ν_eff = 50, p = 95 %)")
    assert _as_number(f["value"]) == Decimal("-0.00015")
    assert f["nu"] == {"50"} and f["k"] == {"2.01"}


def test_a_laboratory_files_conditions_keep_their_digits(run, tmp_path):
    """``temperature_c = 20.0`` and ``humidity_pct = 45.50`` in the laboratory file are
    printed "20.0 °C" and "45.50 %" on the certificate (en, zh) and written with the same
    digits in the DCC, as a logger's "20.0" in the readings is: the number as written."""
    from gonio.formats.lab import load_lab
    from gonio.resources import protocols_dir
    from gonio.result.model import Result
    from gonio.specs import get

    text = (protocols_dir() / "lab-example.toml").read_text(encoding="utf-8")
    text = text[:text.index("[decision_rule]")]          # no limits: they name one spec
    text = re.sub(r"(?m)^\[instrument\]\n(?:(?!\[).*\n)*", "", text)   # the readings' own
    text = re.sub(r"(?m)^temperature_c = .*$", "temperature_c = 20.0", text)
    text = re.sub(r"(?m)^humidity_pct = .*$", "humidity_pct = 45.50", text)
    path = tmp_path / "lab.toml"
    path.write_text(text, encoding="utf-8")
    for lang in ("en", "zh"):
        out = tmp_path / lang
        get(run["key"]).renderer().write(Result.from_json(run["res"]), out, lab=load_lab(path),
                                         lang=lang, dcc=True)
        page = re.sub(r"<[^>]+>", " ", (out / "certificate.html").read_text(encoding="utf-8"))
        page = " ".join(html_mod.unescape(page).replace("\xa0", " ").split())
        assert "20.0 °C" in page and "45.50 %" in page, (run["key"], lang)
        root = etree.parse(str(out / "certificate.dcc.xml")).getroot()
        values = [e.text for e in root.iterfind(".//dcc:influenceCondition//si:value", NS)]
        assert "20.0" in values and "45.50" in values, (run["key"], lang, values)
