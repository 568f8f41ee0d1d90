"""Readings from the virtual bench are marked virtual on every output, whatever the laboratory
file says (docs/formats.md#provenance): ``gonio simulate`` then ``gonio calibrate --lab`` for
every specification gives the mark on every PDF page (poppler's text of each page), in the
HTML (Chromium's print of it: the mark in the text of every printed page, not only in the
watermark's picture), summary.txt, results.json (``provenance``) and the DCC. The same readings
with the bench's metadata lines taken out give no mark (the check can fail).

The instrument's identity and the conditions (docs/formats.md#identity-and-conditions): a
laboratory file whose serial or temperature contradicts the readings' metadata is refused with
one line (exit 2), for every specification; with ``[identity] on_mismatch = "proceed"`` the
contradiction is a flagged finding on the certificate (every format), summary.txt and
results.json.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gonio.formats.provenance import provenance, readings_provenance
from gonio.report.i18n import labels
from tests.own_readings import BENCH_KEYS, own_text, resaved

HERE = Path(__file__).resolve().parent
PINS = HERE / "data" / "pins"
ROOT = HERE.parent
#: (specification, a small protocol of tests/data/pins or None for the built-in one, seed)
RUNS = (("ogam-draft", "ogam-draft-small.toml", 3),
        ("jjf1535-2015", "jjf1535-2015-small.toml", 3),
        ("iec62047-20", "iec62047-20-small.toml", 3),
        ("triad-alignment", None, 3))
BANNER = labels("en")["virtual_short"]


#: The laboratory file's serial: no simulated instrument has it.
LAB_SERIAL = "SN-0001"


def lab_file(tmp: Path, identity: str = "", name: str = "lab.toml",
             temperature_c: float | None = None) -> Path:
    """The example laboratory file without its limits (they name the optical items), its
    instrument the serial :data:`LAB_SERIAL` only, its environment ``temperature_c`` (none:
    no [environment]), with ``identity`` as its [identity] section's body."""
    text = (ROOT / "protocols" / "lab-example.toml").read_text(encoding="utf-8")
    text = text[:text.index("# Statement of conformity")]
    text = re.sub(r"^\[instrument\]\n.*?\n\n", f'[instrument]\nserial = "{LAB_SERIAL}"\n\n', text,
                  flags=re.S | re.M)
    env = "" if temperature_c is None else f"[environment]\ntemperature_c = {temperature_c}\n\n"
    text = re.sub(r"^\[environment\]\n.*?\n\n", env, text, flags=re.S | re.M)
    if identity:
        text += f"\n[identity]\n{identity}\n"
    p = tmp / name
    p.write_text(text, encoding="utf-8")
    return p


def gonio(*args, cwd: Path, rc: int = 0) -> subprocess.CompletedProcess:
    r = subprocess.run([sys.executable, "-m", "gonio", *map(str, args)], cwd=cwd,
                       capture_output=True, text=True)
    assert r.returncode == rc, r.stderr
    return r


def pdf_pages(pdf: Path) -> list[str]:
    tool = shutil.which("pdftotext")
    if not tool:
        pytest.skip("pdftotext is missing: run scripts/install-test-system-deps.sh")
    n = int(re.search(r"Pages:\s+(\d+)", subprocess.run(
        [shutil.which("pdfinfo"), str(pdf)], capture_output=True, text=True,
        check=True).stdout).group(1))
    return [subprocess.run([tool, "-f", str(i), "-l", str(i), str(pdf), "-"],
                           capture_output=True, text=True, check=True).stdout
            for i in range(1, n + 1)]


def printed_pages(page: Path) -> list[str]:
    """The text of every page of Chromium's print of the HTML certificate ``page`` (Debian's
    chromium, as tests/test_certificate_render.py), page by page (poppler)."""
    tool = shutil.which("chromium")
    if not tool:
        pytest.skip("chromium is missing: run scripts/install-test-system-deps.sh")
    pdf = page.parent / (page.stem + "-printed.pdf")
    subprocess.run([tool, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                    "--no-first-run", f"--user-data-dir={page.parent / 'chromium-profile'}",
                    f"--print-to-pdf={pdf}", page.as_uri()], capture_output=True, timeout=180,
                   check=True)
    return pdf_pages(pdf)


#: The metadata lines a laboratory's own file lacks (``strip`` of :func:`simulate_calibrate`).
LAB_OWN = "|".join(BENCH_KEYS)


def simulated(sims, spec, protocol, seed, dst: Path) -> Path:
    """``dst`` holding what ``gonio simulate --spec spec [--protocol PINS/protocol] --seed
    seed`` writes, copied from the session's shared simulation (``sims``, the
    ``shared_simulation`` fixture of tests/conftest.py: the same bytes in any folder)."""
    shutil.copytree(sims(spec, None if protocol is None else PINS / protocol, seed), dst)
    return dst


def simulate_calibrate(spec, protocol, seed, work: Path, lab: Path, strip: str = "",
                       unmark: bool = True, resave: bool = False, *, sims) -> Path:
    """``gonio simulate``'s set (copied from ``sims``, :func:`simulated`) then
    ``gonio calibrate --lab lab --dcc``; ``strip``: a regular
    expression of metadata keys whose lines are deleted from the readings first
    (:data:`LAB_OWN`: a laboratory's own file, :func:`tests.own_readings.own_text`, its
    values without the bench's watermark unless ``unmark`` is False: then the header lines
    of the readings and of the files they name are edited alike, the watermark kept);
    ``resave``: the edited files then re-saved as a spreadsheet does
    (:func:`tests.own_readings.resaved`: ``60.0`` → ``60``, 15 significant digits)."""
    proto = [] if protocol is None else ["--protocol", PINS / protocol]
    sim, cal = work / "sim", work / "cal"
    simulated(sims, spec, protocol, seed, sim)
    readings = sim / "readings.csv"
    if strip:                        # a laboratory's own file: no bench, seed or generator
        lines = readings.read_text(encoding="utf-8").splitlines(keepends=True)
        readings = work / "lab-readings.csv"
        text = "".join(x for x in lines if not re.match(r"# (%s):" % strip, x))
        save = resaved if resave else (lambda t: t)
        readings.write_text(save(own_text(text, unmark) if strip == LAB_OWN else text),
                            encoding="utf-8")
        for extra in ("thermal.csv",):
            if (sim / extra).exists() and unmark and not resave:
                shutil.copy(sim / extra, work / extra)
            elif (sim / extra).exists():
                (work / extra).write_text(save(own_text((sim / extra).read_text(encoding="utf-8"),
                                                        unmark)), encoding="utf-8")
    gonio("calibrate", readings, "--spec", spec, *proto, "--lab", lab, "--dcc", "--out", cal,
          cwd=work)
    return cal


@pytest.fixture(scope="module", params=RUNS, ids=[r[0] for r in RUNS])
def run(request, tmp_path_factory, shared_simulation):
    """Simulated readings calibrated with a laboratory file that names another serial and
    proceeds (``on_mismatch = "proceed"``)."""
    spec, protocol, seed = request.param
    work = tmp_path_factory.mktemp(spec)
    lab = lab_file(work, 'on_mismatch = "proceed"')
    return spec, seed, simulate_calibrate(spec, protocol, seed, work, lab,
                                          sims=shared_simulation)


def test_contradicting_lab_file_is_refused(run):
    """The same readings with the laboratory file that does not proceed: exit 2, one line
    naming the serial both ways; a temperature 5 °C off (the readings' own metadata) too."""
    spec, seed, cal = run
    work = cal.parent
    proto = [a for r in RUNS if r[0] == spec and r[1] for a in ("--protocol", PINS / r[1])]
    r = gonio("calibrate", work / "sim" / "readings.csv", "--spec", spec, *proto, "--lab",
              lab_file(work, name="strict.toml"), "--out", work / "refused", cwd=work, rc=2)
    line = r.stderr.strip()
    assert "\n" not in line and "serial" in line and LAB_SERIAL in line, line
    assert not (work / "refused").exists()
    md = json.loads((cal / "results.json").read_text(encoding="utf-8"))["metadata"]
    # IEC 62047-20's room_temperature_c is its chamber's T_BASE, not the room's
    t = md.get("temperature_c") or (md.get("room_temperature_c") if spec != "iec62047-20"
                                    else None)
    if t is not None:                 # the triad's and IEC's readings state no room temperature
        hot = lab_file(work, 'on_mismatch = "refuse"', name="hot.toml",
                       temperature_c=float(t) + 5.0)
        hot.write_text(re.sub(r"^\[instrument\]\n.*?\n\n", "", hot.read_text(),
                              flags=re.S | re.M))
        r = gonio("calibrate", work / "sim" / "readings.csv", "--spec", spec, *proto, "--lab",
                  hot, "--out", work / "refused", cwd=work, rc=2)
        assert "temperature" in r.stderr and "more than 1 °C apart" in r.stderr, r.stderr


def test_the_measured_room_temperature_speaks_where_the_metadata_are_silent(run):
    """A JJF 1535 file without its ``# room_temperature_c`` line still measured the room: the
    laboratory file's temperature 5 °C off the median of the room tests' ``temperature_c``
    column is refused naming that column, and one within 1 °C of it calibrates."""
    spec, seed, cal = run
    if spec != "jjf1535-2015":
        pytest.skip("only JJF 1535's readings log the room (IEC 62047-20's every test runs "
                    "in the chamber: test_iec_base_temperature_is_not_the_room)")
    work = cal.parent
    proto = [a for r in RUNS if r[0] == spec and r[1] for a in ("--protocol", PINS / r[1])]
    text = (work / "sim" / "readings.csv").read_text(encoding="utf-8")
    room = float(re.search(r"^# room_temperature_c: (.*)$", text, re.M).group(1))
    quiet = work / "no-room-line.csv"
    quiet.write_text(re.sub(r"^# (room_)?temperature_c:.*\n", "", text, flags=re.M),
                     encoding="utf-8")
    for name, t, rc in (("hot.toml", room + 5.0, 2), ("room.toml", room + 0.5, 0)):
        lab = lab_file(work, 'on_mismatch = "refuse"', name=name, temperature_c=t)
        lab.write_text(re.sub(r"^\[instrument\]\n.*?\n\n", "", lab.read_text(),
                              flags=re.S | re.M))
        r = gonio("calibrate", quiet, "--spec", spec, *proto, "--lab", lab, "--out",
                  work / f"measured-{rc}", cwd=work, rc=rc)
        if rc:
            assert "temperature_c column" in r.stderr and "1 °C apart" in r.stderr, r.stderr


def test_the_measured_room_temperature_speaks_beside_an_agreeing_line(run):
    """A JJF 1535 file whose ``# room_temperature_c`` line agrees with the laboratory file
    while its room tests logged 7 °C more in ``temperature_c``: refused naming the column
    (before, the metadata line alone was compared and the certificate stated the laboratory
    file's temperature without a word)."""
    spec, seed, cal = run
    if spec != "jjf1535-2015":
        pytest.skip("only JJF 1535's readings log the room")
    work = cal.parent
    proto = [a for r in RUNS if r[0] == spec and r[1] for a in ("--protocol", PINS / r[1])]
    lines = (work / "sim" / "readings.csv").read_text(encoding="utf-8").splitlines(True)
    room = float(next(x for x in lines if x.startswith("# room_temperature_c:")).split(":")[1])
    head = next(i for i, x in enumerate(lines) if not x.startswith("#"))
    cols = lines[head].rstrip("\n").split(",")
    test, temp = cols.index("test"), cols.index("temperature_c")
    out = lines[:head + 1]
    for x in lines[head + 1:]:
        f = x.rstrip("\n").split(",")
        if f[test] not in ("sf_temperature", "bias_temperature") and f[temp].strip():
            f[temp] = f"{float(f[temp]) + 7.0:.3f}"
        out.append(",".join(f) + "\n")
    warm = work / "logged-warm.csv"
    warm.write_text("".join(out), encoding="utf-8")
    lab = lab_file(work, 'on_mismatch = "refuse"', name="agrees.toml", temperature_c=room + 0.1)
    lab.write_text(re.sub(r"^\[instrument\]\n.*?\n\n", "", lab.read_text(),
                          flags=re.S | re.M))
    r = gonio("calibrate", warm, "--spec", spec, *proto, "--lab", lab, "--out",
              work / "logged-warm", cwd=work, rc=2)
    assert "temperature_c column" in r.stderr and "1 °C apart" in r.stderr, r.stderr


def test_iec_base_temperature_is_not_the_room(run):
    """IEC 62047-20 runs every test in the chamber at a set point: its ``# room_temperature_c``
    is T_BASE (the midpoint of the operating range) and its ``temperature_c`` column logs the
    set points, so neither is the room. A laboratory whose room is 5 °C off T_BASE
    calibrates, with the line and without it, and no temperature contradiction is stated."""
    spec, seed, cal = run
    if spec != "iec62047-20":
        pytest.skip("IEC 62047-20's base temperature")
    work = cal.parent
    proto = [a for r in RUNS if r[0] == spec and r[1] for a in ("--protocol", PINS / r[1])]
    text = (work / "sim" / "readings.csv").read_text(encoding="utf-8")
    base = float(re.search(r"^# room_temperature_c: (.*)$", text, re.M).group(1))
    quiet = work / "iec-no-base-line.csv"
    quiet.write_text(re.sub(r"^# room_temperature_c:.*\n", "", text, flags=re.M),
                     encoding="utf-8")
    lab = lab_file(work, 'on_mismatch = "refuse"', name="room.toml", temperature_c=base - 5.0)
    lab.write_text(re.sub(r"^\[instrument\]\n.*?\n\n", "", lab.read_text(), flags=re.S | re.M))
    for i, readings in enumerate((work / "sim" / "readings.csv", quiet)):
        out = work / f"iec-room-{i}"
        gonio("calibrate", readings, "--spec", spec, *proto, "--lab", lab, "--out", out,
              cwd=work)
        res = json.loads((out / "results.json").read_text(encoding="utf-8"))
        assert not [f for f in res["findings"] if f["code"] == "identity-mismatch"], res
    # a room temperature the readings do state (# temperature_c) is still compared
    hot = work / "iec-stated-room.csv"
    hot.write_text(f"# temperature_c: {base - 5.0 + 3.0}\n" + text, encoding="utf-8")
    r = gonio("calibrate", hot, "--spec", spec, *proto, "--lab", lab, "--out",
              work / "iec-refused", cwd=work, rc=2)
    assert "temperature" in r.stderr and "more than 1 °C apart" in r.stderr, r.stderr


def test_proceeding_states_the_contradiction(run):
    spec, seed, cal = run
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    found = [f for f in res["findings"] if f["code"] == "identity-mismatch"]
    assert len(found) == 1 and found[0]["action"] == "flagged"
    # the message names its header line ("# serial"); it is not a readings column
    assert not found[0].get("column"), found[0]
    serial = res["metadata"]["serial"]
    assert serial in found[0]["message"] and LAB_SERIAL in found[0]["message"]
    text = " ".join(pdf_pages(cal / "certificate.pdf"))
    assert re.search(r"the\s+readings\s+say\s+\W?" + re.escape(serial), text), spec
    assert serial in (cal / "certificate.html").read_text(encoding="utf-8")
    summary = (cal / "summary.txt").read_text(encoding="utf-8")
    assert f"say '{serial}'" in summary and LAB_SERIAL in summary
    # no empty clause before the message ("[flagged] : serial: …")
    assert "] :" not in text and "] :" not in (cal / "certificate.html").read_text(
        encoding="utf-8")


def test_the_dcc_states_every_finding_the_certificate_states(run, dcc_schema):
    """The DCC certifies nothing the certificate qualifies silently: one dcc:statement per
    finding stated (all but "refused"), the identity contradiction among them naming both
    serials, in a schema-valid place (DCC 3.3.0 XSD)."""
    from lxml import etree

    from gonio.report.dcc import DCC_NS

    spec, seed, cal = run
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    stated = [f for f in res["findings"] if f["action"] != "refused"]
    dcc = cal / "certificate.dcc.xml"
    dcc_schema.validate(str(dcc))
    root = etree.parse(str(dcc)).getroot()
    sts = [s for s in root.iter(f"{{{DCC_NS}}}statement")
           if (s.get("id") or "").startswith("finding-")]
    assert len(sts) == len(stated), (len(sts), len(stated))
    texts = [" ".join(c.text for c in s.iter(f"{{{DCC_NS}}}content")) for s in sts]
    serial = res["metadata"]["serial"]
    assert any(f"say '{serial}'" in t and LAB_SERIAL in t for t in texts), texts
    for f in stated:                       # each finding's own message, in English
        assert any(f["message"] in t for t in texts), f["message"]


def test_virtual_readings_marked_everywhere_with_a_lab_file(run):
    spec, seed, cal = run
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    prov = res["provenance"]
    assert prov["virtual"] is True and prov["seed"] == str(seed) and prov["bench"]
    pages = pdf_pages(cal / "certificate.pdf")
    assert len(pages) >= 2
    for i, text in enumerate(pages, 1):
        assert BANNER in text, f"{spec}: PDF page {i} of {len(pages)} lacks the mark"
    printed = printed_pages(cal / "certificate.html")
    assert len(printed) >= 2
    for i, text in enumerate(printed, 1):
        assert BANNER in text, f"{spec}: printed HTML page {i} of {len(printed)} lacks the mark"
    page = (cal / "certificate.html").read_text(encoding="utf-8")
    assert labels("en")["virtual"] in page and prov["bench"] in page
    assert "Example Angle Metrology Laboratory" in page          # the lab file is still used
    summary = (cal / "summary.txt").read_text(encoding="utf-8")
    assert summary.startswith("VIRTUAL BENCH EXAMPLE") and f"seed {seed}" in summary.splitlines()[0]
    dcc = (cal / "certificate.dcc.xml").read_text(encoding="utf-8")
    assert 'id="virtual-bench"' in dcc and prov["bench"] in dcc


def test_laboratory_readings_are_not_marked(tmp_path, shared_simulation):
    """The same simulated readings less the bench's metadata lines and names: no mark anywhere."""
    cal = simulate_calibrate("jjf1535-2015", "jjf1535-2015-small.toml", 3, tmp_path,
                             lab_file(tmp_path, 'on_mismatch = "proceed"'), strip=LAB_OWN,
                             sims=shared_simulation)
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    assert res["provenance"]["virtual"] is False
    assert not any(BANNER in t for t in pdf_pages(cal / "certificate.pdf"))
    assert labels("en")["virtual"] not in (cal / "certificate.html").read_text(encoding="utf-8")
    assert "VIRTUAL" not in (cal / "summary.txt").read_text(encoding="utf-8")
    assert 'id="virtual-bench"' not in (cal / "certificate.dcc.xml").read_text(encoding="utf-8")


@pytest.mark.parametrize("spec, protocol, seed", RUNS, ids=[r[0] for r in RUNS])
def test_watermark_keeps_the_mark_without_any_bench_line(spec, protocol, seed, tmp_path,
                                                          shared_simulation):
    """Simulated readings with every metadata line that names the bench deleted (bench, seed,
    generator, noise) and every "virtual" name replaced, the file renamed and re-saved as a
    spreadsheet does ('%.15g' of every number: 60.0 → 60): the values' own watermark
    (gonio.formats.watermark) marks them virtual on every PDF page, in the HTML,
    summary.txt, results.json and the DCC, for every specification."""
    cal = simulate_calibrate(spec, protocol, seed, tmp_path,
                             lab_file(tmp_path, 'on_mismatch = "proceed"'), strip=LAB_OWN,
                             unmark=False, resave=True, sims=shared_simulation)
    lab_readings = (tmp_path / "lab-readings.csv").read_text(encoding="utf-8")
    assert not re.search(r"(?im)^# (bench|seed|generator|noise):|virtual", lab_readings)
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    prov = res["provenance"]
    assert prov["virtual"] is True and prov["bench"] is None, prov
    assert prov["evidence"][-1].endswith("watermark"), prov
    import jsonschema
    schema = json.loads((ROOT / "docs" / "results.schema.json").read_text(encoding="utf-8"))
    jsonschema.validate(res, schema)
    pages = pdf_pages(cal / "certificate.pdf")
    for i, text in enumerate(pages, 1):
        assert BANNER in text, f"{spec}: PDF page {i} of {len(pages)} lacks the mark"
    assert "watermark" in " ".join(pages[0].split())
    page = (cal / "certificate.html").read_text(encoding="utf-8")
    assert labels("en")["virtual"] in page and "watermark" in page
    first = (cal / "summary.txt").read_text(encoding="utf-8").splitlines()[0]
    assert first.startswith("VIRTUAL BENCH EXAMPLE") and "watermark" in first
    dcc = (cal / "certificate.dcc.xml").read_text(encoding="utf-8")
    assert 'id="virtual-bench"' in dcc and "watermark" in dcc


@pytest.mark.parametrize("spec, protocol", [("jjf1535-2015", "jjf1535-2015-small.toml"),
                                            ("triad-alignment", None)])
def test_deleting_bench_and_seed_lines_keeps_the_mark(spec, protocol, tmp_path,
                                                       shared_simulation):
    """Simulated readings whose ``# bench:``, ``# seed:`` (and ``# generator:``) lines were
    deleted still name the virtual bench in their other metadata (the instrument "… (virtual)"):
    marked on every PDF page, in the HTML, summary.txt, results.json and the DCC, naming the
    keys that said so."""
    cal = simulate_calibrate(spec, protocol, 3, tmp_path,
                             lab_file(tmp_path, 'on_mismatch = "proceed"'),
                             strip="bench|seed|generator", sims=shared_simulation)
    prov = json.loads((cal / "results.json").read_text(encoding="utf-8"))["provenance"]
    assert prov["virtual"] is True and prov["bench"] is None and "instrument" in prov["evidence"]
    pages = pdf_pages(cal / "certificate.pdf")
    for i, text in enumerate(pages, 1):
        assert BANNER in text, f"{spec}: PDF page {i} of {len(pages)} lacks the mark"
    assert "# instrument" in " ".join(pages[0].split())
    assert labels("en")["virtual"] in (cal / "certificate.html").read_text(encoding="utf-8")
    first = (cal / "summary.txt").read_text(encoding="utf-8").splitlines()[0]
    assert first.startswith("VIRTUAL BENCH EXAMPLE") and "# instrument" in first and "-," not in first
    dcc = (cal / "certificate.dcc.xml").read_text(encoding="utf-8")
    assert 'id="virtual-bench"' in dcc and "# instrument" in dcc


def test_provenance_rules(tmp_path):
    assert provenance({"seed": "0"})["evidence"] == ["seed"]
    assert provenance({"generator": "gonio 0.1.0"})["virtual"] is True
    # gonio's acquisition from instruments is not the virtual bench; its identification can be
    assert provenance({"generator": "gonio 0.1.0 acquire"})["virtual"] is False
    assert provenance({"generator": "gonio 0.1.0 acquire",
                       "table_idn": "gonio,virtual rotary table,0,1"})["evidence"] == ["table_idn"]
    assert provenance({"manufacturer": "gonio virtual bench"})["virtual"] is True
    assert provenance({"instrument": "Virtually-free FOG"})["virtual"] is False
    assert provenance({"generator": "gonioscope 2"})["virtual"] is False
    assert provenance({"bench": ""})["virtual"] is False
    f = tmp_path / "r.csv"
    f.write_text("# serial: X\n# bench: rlg\nangle\n# seed: 9\n", encoding="utf-8")
    p = readings_provenance(f)                 # only the lines above the header count
    assert p["virtual"] and p["bench"] == "rlg" and p["seed"] is None


@pytest.fixture(scope="module")
def run_zh(run):
    """``gonio calibrate --lang zh`` of the run's readings with the same laboratory file: the
    Chinese certificate the tests below only read (one calibration per specification)."""
    spec, seed, cal = run
    work = cal.parent
    proto = [a for r in RUNS if r[0] == spec and r[1] for a in ("--protocol", PINS / r[1])]
    zh = work / "cal-zh"
    gonio("calibrate", work / "sim" / "readings.csv", "--spec", spec, *proto, "--lab",
          lab_file(work, 'on_mismatch = "proceed"', name="lab-zh.toml"), "--lang", "zh",
          "--out", zh, cwd=work)
    return zh


def test_virtual_readings_marked_on_every_chinese_page(run, run_zh):
    """The Chinese certificate of the same readings and laboratory file: the mark on every
    PDF page and in the HTML, as the English one (the language changes no rule)."""
    spec, seed, cal = run
    zh = run_zh
    mark = labels("zh")["virtual_short"]
    pages = pdf_pages(zh / "certificate.pdf")
    assert len(pages) >= 2
    for i, text in enumerate(pages, 1):
        assert mark in re.sub(r"\s+", "", text), f"{spec}: zh PDF page {i} of {len(pages)} lacks the mark"
    printed = printed_pages(zh / "certificate.html")
    assert len(printed) >= 2
    for i, text in enumerate(printed, 1):
        assert mark in re.sub(r"\s+", "", text), \
            f"{spec}: zh printed HTML page {i} of {len(printed)} lacks the mark"
    assert labels("zh")["virtual"] in (zh / "certificate.html").read_text(encoding="utf-8")


def _first_page_text(pdf: Path) -> str:
    return " ".join(pdf_pages(pdf)[0].split())


def test_first_page_flags_the_contradicted_identity(run, run_zh):
    """Proceeding with a laboratory file whose serial the readings contradict: page 1 (PDF and
    the HTML, English and Chinese) prints the laboratory file's serial with the flag pointing
    to the finding, and only that line; summary.txt flags the serial it states; the DCC's
    identification carries the remark and refers to the finding's statement, which names the
    readings' serial."""
    from lxml import etree

    from gonio.report.dcc import DCC_NS

    spec, seed, cal = run
    res = json.loads((cal / "results.json").read_text(encoding="utf-8"))
    serial = res["metadata"]["serial"]
    en, zh = labels("en"), labels("zh")
    page1 = _first_page_text(cal / "certificate.pdf")
    assert f"{en['serial']} {LAB_SERIAL} {en['identity_flag']}" in page1, page1
    assert page1.count(en["identity_flag"]) == 1            # model, manufacturer: not flagged
    page = (cal / "certificate.html").read_text(encoding="utf-8")
    assert re.search(rf"<td>{en['serial']}</td><td><span class=\"nb\">{LAB_SERIAL}</span>"
                     rf"<span class=\"flag\"> {re.escape(en['identity_flag'])}</span></td>",
                     page), spec
    assert page.count('class="flag"') == 1
    summary = (cal / "summary.txt").read_text(encoding="utf-8").splitlines()
    assert sum(x.startswith(f"serial: {LAB_SERIAL} [CONTRADICTED") for x in summary) == 1
    root = etree.parse(str(cal / "certificate.dcc.xml")).getroot()
    ident = next(root.iter(f"{{{DCC_NS}}}identification"))
    assert ident.findtext(f"{{{DCC_NS}}}value") == LAB_SERIAL
    name = " ".join(c.text for c in ident.iter(f"{{{DCC_NS}}}content"))
    ref = ident.get("refId")
    assert ref and f"statement {ref}" in name and "contradicted" in name, name
    st = next(s for s in root.iter(f"{{{DCC_NS}}}statement") if s.get("id") == ref)
    said = " ".join(c.text for c in st.iter(f"{{{DCC_NS}}}content"))
    assert f"say '{serial}'" in said and LAB_SERIAL in said, said
    zh_out = run_zh                    # the Chinese certificate of the same readings
    page1 = re.sub(r"\s+", "", pdf_pages(zh_out / "certificate.pdf")[0])
    assert zh["serial"] + LAB_SERIAL + zh["identity_flag"] in page1, page1
    page = (zh_out / "certificate.html").read_text(encoding="utf-8")
    assert f'{LAB_SERIAL}</span><span class="flag">{zh["identity_flag"]}</span>' in page


def test_the_flag_follows_what_is_contradicted(tmp_path, shared_simulation):
    """A laboratory file with the readings' own serial and a temperature 5 °C off, proceeding:
    the temperature line is flagged, the serial is not (the flag follows the finding)."""
    from gonio.formats.provenance import readings_metadata

    simulated(shared_simulation, "jjf1535-2015", "jjf1535-2015-small.toml", 3, tmp_path / "sim")
    md = readings_metadata(tmp_path / "sim" / "readings.csv")
    t = float(md.get("temperature_c") or md["room_temperature_c"])
    lab = lab_file(tmp_path, 'on_mismatch = "proceed"', name="warm.toml", temperature_c=t + 5)
    lab.write_text(lab.read_text(encoding="utf-8").replace(LAB_SERIAL, md["serial"]),
                   encoding="utf-8")
    out = tmp_path / "warm"
    gonio("calibrate", tmp_path / "sim" / "readings.csv", "--spec", "jjf1535-2015",
          "--protocol", PINS / "jjf1535-2015-small.toml", "--lab", lab, "--dcc", "--out", out,
          cwd=tmp_path)
    res = json.loads((out / "results.json").read_text(encoding="utf-8"))
    assert [f["subject"] for f in res["findings"] if f["code"] == "identity-mismatch"] == \
        ["temperature"]
    en = labels("en")
    text = " ".join(pdf_pages(out / "certificate.pdf")[0:2])
    text = " ".join(text.split())
    assert f"{t + 5!r} °C {en['identity_flag']}" in text, text       # the temperature's line
    assert text.count(en["identity_flag"]) == 1
    summary = (out / "summary.txt").read_text(encoding="utf-8")
    assert f"temperature: {t + 5!r} °C [CONTRADICTED" in summary
    assert "serial: " + md["serial"] + " [" not in summary


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_a_stream_without_its_bench_lines_is_marked(fmt, tmp_path):
    """``gonio simulate --stream`` (the RLG bench at 20 Hz, the small optical programme), its
    bench, seed, generator and "virtual" names deleted — the ``#`` lines of a CSV stream, the
    key-value metadata of a Parquet stream — calibrated with the laboratory file: the
    stream's times carry the bench's watermark (gonio.formats.watermark), so every PDF page,
    summary.txt, results.json and the DCC say virtual; the same seed gives the same bytes."""
    bench = tmp_path / "rlg20.toml"
    bench.write_text((ROOT / "protocols/benches/rlg.toml").read_text(encoding="utf-8")
                     .replace("sample_rate_hz = 1000.0", "sample_rate_hz = 20.0"),
                     encoding="utf-8")
    assert "sample_rate_hz = 20.0" in bench.read_text(encoding="utf-8")
    name = f"stream.{fmt}"
    sims = []
    for run in ("a", "b"):
        gonio("simulate", "--protocol", PINS / "ogam-draft-small.toml", "--bench", bench,
              "--seed", 3, "--out", tmp_path / run, "--stream", "--stream-format", fmt,
              cwd=tmp_path)
        sims.append((tmp_path / run / name).read_bytes())
    assert sims[0] == sims[1]
    src, dst = tmp_path / "a" / name, tmp_path / f"lab-{name}"
    says_virtual = re.compile(r"(?i)^(bench|seed|generator|noise)$")
    if fmt == "csv":
        text = src.read_text(encoding="utf-8")
        kept = [ln for ln in text.splitlines(keepends=True)
                if not (ln.startswith("#") and (says_virtual.match(ln[1:].split(":")[0].strip())
                                                or "virtual" in ln.lower()))]
        dst.write_text("".join(kept), encoding="utf-8")
        assert "virtual" not in dst.read_text(encoding="utf-8").lower()
    else:
        import pyarrow.parquet as pq
        tab = pq.read_table(src)
        md = {k.decode(): v.decode() for k, v in (tab.schema.metadata or {}).items()}
        keep = {k: v for k, v in md.items()
                if not says_virtual.match(k) and "virtual" not in v.lower()}
        assert len(keep) < len(md) and "counter_bits" in keep
        pq.write_table(tab.replace_schema_metadata(keep), dst)

    def marked(readings, cal) -> dict:
        """``readings`` calibrated with the laboratory file: virtual in every output."""
        gonio("calibrate", readings, "--spec", "ogam-draft", "--protocol",
              PINS / "ogam-draft-small.toml", "--lab",
              lab_file(tmp_path, 'on_mismatch = "proceed"'), "--dcc", "--out", cal, cwd=tmp_path)
        prov = json.loads((cal / "results.json").read_text(encoding="utf-8"))["provenance"]
        assert prov["virtual"] is True and prov["evidence"] == ["watermark"], prov
        pages = pdf_pages(cal / "certificate.pdf")
        for i, text in enumerate(pages, 1):
            assert BANNER in text, f"{readings.name}: PDF page {i} of {len(pages)} lacks the mark"
        assert labels("en")["virtual"] in (cal / "certificate.html").read_text(encoding="utf-8")
        first = (cal / "summary.txt").read_text(encoding="utf-8").splitlines()[0]
        assert first.startswith("VIRTUAL BENCH EXAMPLE") and "watermark" in first
        assert 'id="virtual-bench"' in (cal / "certificate.dcc.xml").read_text(encoding="utf-8")
        return prov

    prov = marked(dst, tmp_path / "cal")
    assert prov["watermark"]["matching"] == prov["watermark"]["cells"] >= 1000
    # reduced to readings by gonio reduce: the readings carry the mark too (before, the
    # reduced readings of a stream without its lines were a clean laboratory file)
    red = tmp_path / "reduced.csv"
    gonio("reduce", dst, "--protocol", PINS / "ogam-draft-small.toml", "--out", red,
          cwd=tmp_path)
    assert "virtual" not in red.read_text(encoding="utf-8").lower()
    marked(red, tmp_path / "cal-reduced")
