"""Make (or recompute) the pins of tests/test_pins.py: every item's value and U of one
virtual calibration per specification, on one seed and a small protocol.

    python tests/data/pins/make_pins.py            # rewrite tests/data/pins/pins.json
    python tests/data/pins/make_pins.py ogam-draft # recompute one specification's pins only

The pins were first made from main at commit ae98dc5 (before the issue-23 refactors: one
result model, one specification interface), so that the refactors can be shown to change no
number. A deliberate change of a number (a new budget term, a fixed estimator) must
regenerate them with this script, and the commit must say which numbers changed and why.

Each calibration goes through the command line (``gonio simulate`` then ``gonio calibrate``,
the same path as ``gonio demo`` without the certificate's figures mattering), so the script
runs unchanged on the code before and after the refactors; :func:`item_numbers` reads both
the results.json shape before the refactors and the one result model's shape (a
``version`` field).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
PINS = HERE / "pins.json"
#: (specification, protocol file in this folder or None for the built-in one, seed)
RUNS = (("ogam-draft", "ogam-draft-small.toml", 7),
        ("jjf1535-2015", "jjf1535-2015-small.toml", 7),
        ("iec62047-20", "iec62047-20-small.toml", 7),
        ("triad-alignment", None, 7))
#: The optical draft's items in the results.json shape before the refactors.
LEGACY_OPTICAL = ("scale_factor", "scale_factor_nonlinearity", "zero_stability",
                  "angle_deviation", "repeatability", "rate_consistency",
                  "pointing_consistency")


def _num(x):
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def item_numbers(d: dict) -> dict[str, dict]:
    """{item key: {"value", "U"}} of a results.json (either shape); not measured → None."""
    if "version" in d:                                   # the one result model
        items = d["items"]
    elif "items" in d:                                   # rate and triad, before
        items = d["items"]
    else:                                                # the optical draft, before
        items = {k: d[k] for k in LEGACY_OPTICAL}
    out = {}
    for key, it in items.items():
        unc = it.get("uncertainty") or {}
        out[key] = {"value": _num(it.get("value")) if it.get("measured", True) else None,
                    "U": _num(unc.get("U"))}
    return out


def gonio(*args: str, cwd: Path) -> None:
    r = subprocess.run([sys.executable, "-m", "gonio", *args], cwd=cwd, capture_output=True,
                       text=True)
    if r.returncode != 0:
        raise RuntimeError(f"gonio {' '.join(args)} failed ({r.returncode}):\n{r.stderr}")


def results(spec: str, protocol: str | None, seed: int, work: Path) -> dict:
    """One simulate + calibrate of ``spec``: its results.json."""
    proto = [] if protocol is None else ["--protocol", str(HERE / protocol)]
    sim, cal = work / f"{spec}-sim", work / f"{spec}-cal"
    gonio("simulate", "--spec", spec, *proto, "--seed", str(seed), "--out", str(sim), cwd=work)
    gonio("calibrate", str(sim / "readings.csv"), "--spec", spec, *proto, "--out", str(cal),
          cwd=work)
    return json.loads((cal / "results.json").read_text(encoding="utf-8"))


def run(spec: str, protocol: str | None, seed: int, work: Path) -> dict[str, dict]:
    """One simulate + calibrate of ``spec``: its :func:`item_numbers`."""
    return item_numbers(results(spec, protocol, seed, work))


def compute(specs=None) -> dict:
    """The pins' content: {spec: {"protocol", "seed", "items": item_numbers}}, of every
    specification of :data:`RUNS` or of those named in ``specs``."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for spec, protocol, seed in RUNS:
            if specs and spec not in specs:
                continue
            out[spec] = {"protocol": protocol, "seed": seed,
                         "items": run(spec, protocol, seed, Path(tmp))}
    return out


def main() -> None:
    specs = sys.argv[1:]
    unknown = set(specs) - {r[0] for r in RUNS}
    if unknown:
        raise SystemExit(f"make_pins: unknown specification(s) {sorted(unknown)}")
    pins = compute(specs)
    if specs:            # the others keep their pins
        pins = {**json.loads(PINS.read_text(encoding="utf-8")), **pins}
    PINS.write_text(json.dumps(pins, indent=1, sort_keys=True, allow_nan=False) + "\n",
                    encoding="utf-8")
    print(f"wrote {PINS} ({sum(len(v['items']) for v in pins.values())} items)")


if __name__ == "__main__":
    main()
