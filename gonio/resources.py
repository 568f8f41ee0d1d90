"""Where the installed protocol and bench files are.

The repository's top-level ``protocols/`` folder is installed as the package
``gonio.protocols`` (see ``pyproject.toml``); in a source checkout it is found
beside the ``gonio`` folder.
"""

from __future__ import annotations

import os
from pathlib import Path

from gonio.errors import GonioError, NotFoundError


def protocols_dir() -> Path:
    """The folder holding the built-in protocols and ``benches/``."""
    here = Path(__file__).resolve().parent
    for cand in (here / "protocols", here.parent / "protocols"):
        if (cand / "benches").is_dir() and any(cand.glob("*.toml")):
            return cand
    raise GonioError("the protocols folder (protocols/*.toml, benches/) is not installed with "
                     "gonio")


def builtin_names(kind: str = "protocol") -> list[str]:
    """Names of the built-in protocols (files with a ``[protocol]`` table; the laboratory
    example ``lab-example.toml`` is not one) or benches.

    >>> "lab-example" in builtin_names(), len(builtin_names()) > 1
    (False, True)
    """
    base = protocols_dir() if kind == "protocol" else protocols_dir() / "benches"
    names = []
    for q in sorted(base.glob("*.toml")):
        if kind == "protocol":
            text = q.read_text(encoding="utf-8")
            if not any(line.strip() == "[protocol]" for line in text.splitlines()):
                continue
        names.append(q.stem)
    return names


def resolve(name_or_path: str | Path, kind: str = "protocol") -> Path:
    """A path as given if it exists, else a named built-in protocol or bench (``rlg``).

    >>> name = builtin_names()[0]
    >>> resolve(name).name == name + ".toml"
    True
    >>> resolve("rlg", kind="bench").name
    'rlg.toml'
    """
    p = Path(name_or_path)
    if p.is_file():
        return p
    base = protocols_dir() if kind == "protocol" else protocols_dir() / "benches"
    cand = base / (p.name if p.suffix == ".toml" else p.name + ".toml")
    builtin = cand.is_file() and p.parent == Path(".")
    if os.path.lexists(p) and not (builtin and p.is_dir()):
        # a folder named like a built-in (`simulate --spec X --out X`, then `cd` back) is
        # never a protocol: the built-in name wins; a FIFO, device or other folder is named
        from gonio.errors import check_input_file
        check_input_file(p, f"{kind} file")
    if builtin:
        return cand
    names = builtin_names(kind)
    plural = "benches" if kind == "bench" else f"{kind}s"
    raise NotFoundError(f"{kind} file not found: {name_or_path} (built-in {plural}: {', '.join(names)})")


def readings_protocol(metadata_name: str | None, readings_path, default: str | None):
    """The protocol a readings file's ``# protocol:`` metadata names: ``default`` when it
    names none (or the default itself), else a built-in name, a path, or a file of that
    name next to the readings (``NAME`` or ``NAME.toml``). A name that cannot be found is a
    GonioError naming the readings file and the key, never replaced by the default.
    """
    from gonio.errors import GonioError, NotFoundError

    name = (metadata_name or "").strip()
    if not name or name == default:
        return default
    cands: list = [name]
    if readings_path is not None:
        base = Path(readings_path).parent
        cands += [base / name, base / f"{name}.toml"]
    for c in cands:
        try:
            return resolve(c)
        except NotFoundError:
            continue
    raise GonioError(f"the readings file names protocol {name!r}, which is neither a "
                     "built-in protocol nor a file next to it: give --protocol FILE",
                     file=readings_path, key="protocol")


def protocol_provenance(path: str | Path | None) -> dict:
    """``results.json``'s ``settings`` entries naming the protocol a calibration used: the
    built-in name (or the file's path) and the SHA-256 of its bytes, so the records can
    store the very file and check it (empty for a protocol that is not a file).

    >>> name = builtin_names()[0]
    >>> d = protocol_provenance(resolve(name))
    >>> d["protocol"] == name, len(d["protocol_sha256"])
    (True, 64)
    """
    if path is None or not Path(path).is_file():
        return {}
    from gonio.atomic import sha256_file
    p = Path(path)
    builtin = p.resolve().parent == protocols_dir().resolve()
    return {"protocol": p.stem if builtin else str(p), "protocol_sha256": sha256_file(p)}

