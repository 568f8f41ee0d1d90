"""An in-process memo of the records' one pipeline call (:func:`gonio.records.compute.
calibrate_folder`) for the records tests, where one test process computes the same result
again and again: every ``gonio db import`` computes the imported folder's result again from
the stored inputs (about one calibration each), and the tests import the same few folders
(``computed_folder``, the small protocol's seed-1 readings) dozens of times.

The pipeline is a pure, deterministic function of its inputs (same inputs, byte-identical
output files, wherever ``out`` is). The memo's key is the SHA-256 of every input it reads:
gonio's version, the specification's key, the options (and the bytes of a file an option
names), record and gyro type, the readings' file name and the bytes of every file in the
readings' folder (the readings and every file they name beside them, and more), the protocol,
laboratory and table calibration files' names and bytes and those of the files beside each (a
laboratory file may name a table calibration file by its name; a built-in protocol by its
name), the ``GONIO_*`` environment variables and today's date. A changed byte in any of them is another key: the pipeline runs
(``tests/records/test_pipeline_memo.py`` checks each). The folders the inputs lie in are not
in the key (an import computes in a new temporary folder each time): a run whose output
files name one of those folders, or ``out``, is not kept (:func:`names_a_folder`), and the
test checks that the real pipeline gives the same bytes from other folders. A hit writes
the stored output files into ``out`` (an empty or new folder; otherwise the pipeline runs)
and returns what the pipeline returned; a failed run is never stored.

Only the test suite uses it (the ``pipeline_memo`` fixture of ``tests/records/conftest.py``,
on for every records test; ``@pytest.mark.real_pipeline`` runs a test without it): in
production the same readings are never imported twice. It holds only what this process
computed, and what another process of the same test session (an xdist worker) computed
(:class:`SessionMemo`: one file per key in the session's temporary folder, gone with it)."""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import os
import pickle
import threading
from pathlib import Path

import gonio

_MEMO: dict[str, tuple[dict[str, bytes], object]] = {}
STATS = {"hits": 0, "misses": 0}


def _add(h, tag: str, data: bytes) -> None:
    h.update(tag.encode("utf-8") + b"\0" + len(data).to_bytes(8, "big") + data)


#: where a worker process finds the records (gonio.records.worker reads them before it
#: calls the pipeline; the pipeline and the rendering never read them): not part of a key
RECORDS_LOCATION = ("GONIO_RECORDS_DATABASE", "GONIO_RECORDS_DATA")


def _environment() -> dict:
    """The ``GONIO_*`` variables a key holds (all but :data:`RECORDS_LOCATION`)."""
    return {k: v for k, v in os.environ.items()
            if k.startswith("GONIO_") and k not in RECORDS_LOCATION}


def pipeline_key(readings, *, spec_key: str, protocol=None, lab=None, table_calibration=None,
                 gyro_type=None, options=None, record=None) -> str:
    """The SHA-256 of every input :func:`gonio.records.compute.calibrate_folder` reads."""
    h = hashlib.sha256()
    _add(h, "gonio", gonio.__version__.encode())
    _add(h, "spec", str(spec_key).encode())
    _add(h, "args", json.dumps({"gyro_type": gyro_type, "options": options, "record": record},
                               sort_keys=True, default=repr).encode())
    for name, v in sorted((options or {}).items()):      # an option naming a file: its bytes
        if isinstance(v, (str, Path)) and len(str(v)) < 4096 and Path(v).is_file():
            _add(h, "option-file:" + name, Path(v).read_bytes())
    readings = Path(readings)
    _add(h, "readings", readings.name.encode())
    folder = readings.parent
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            _add(h, "file:" + p.relative_to(folder).as_posix(), p.read_bytes())
    for name, f in (("protocol", protocol), ("lab", lab), ("table", table_calibration)):
        if f is None:
            _add(h, name, b"")
        elif Path(f).is_file():
            _add(h, name + ":" + Path(f).name, Path(f).read_bytes())
            for q in sorted(Path(f).parent.iterdir()):   # the files beside it (a laboratory
                if q.is_file() and q.stat().st_size < 2**24:   # file names its table file)
                    _add(h, name + "-beside:" + q.name, q.read_bytes())
        else:                                  # a built-in protocol's name
            _add(h, name + "=" + str(f), b"")
    _add(h, "env", json.dumps(_environment(), sort_keys=True).encode())
    _add(h, "date", dt.date.today().isoformat().encode())
    return h.hexdigest()


def names_a_folder(files: dict[str, bytes], *paths) -> bool:
    """Whether an output file names the folder of an input or of ``out`` (its text files;
    a PDF renders the HTML's text): such an output depends on where the inputs were, which
    the key leaves out (it hashes their names and bytes), so it is not kept."""
    folders = {str(Path(p).resolve().parent) for p in paths if p is not None} | \
              {str(Path(p).parent) for p in paths if p is not None}
    folders |= {str(Path(paths[-1])), str(Path(paths[-1]).resolve())}
    folders = {f.encode("utf-8") for f in folders if len(f) > 1}
    return any(f in data for name, data in files.items() if not name.endswith(".pdf")
               for f in folders)


def through_memo(memo: dict, stats: dict, key: str, out: Path, compute, paths) -> object:
    """One memoised call: a hit (``key`` in ``memo``) writes the stored output files into
    ``out`` and returns what the call returned; a miss runs ``compute()``, and keeps its
    files and return value unless an output names the folder of one of ``paths``
    (:func:`names_a_folder`). ``stats`` counts hits and misses."""
    if key in memo:
        stats["hits"] += 1
        files, returned = memo[key]
        for name, data in files.items():
            (out / name).parent.mkdir(parents=True, exist_ok=True)
            (out / name).write_bytes(data)
        return list(returned) if isinstance(returned, list) else returned
    stats["misses"] += 1
    returned = compute()
    files = {p.relative_to(out).as_posix(): p.read_bytes()
             for p in sorted(out.rglob("*")) if p.is_file()}
    if not names_a_folder(files, *paths):
        memo[key] = (files, list(returned) if isinstance(returned, list) else returned)
    return returned


def _held(memo, key: str):
    """The memo's lock on ``key`` where it has one (:meth:`SessionMemo.lock`: another process
    computing the same key is waited for, then read), else nothing."""
    import contextlib

    lock = getattr(memo, "lock", None)
    return lock(key) if lock is not None else contextlib.nullcontext()


class SessionMemo:
    """A memo shared by every process of one test session (the xdist workers): this
    process's ``local`` dict in front of one file per key in ``folder`` (the pickled output
    files and return value, written to a temporary name and renamed into place, so that a
    reader sees a whole entry or none). Two workers missing the same key at once both run
    the call and write the same bytes; an entry that cannot be pickled or read stays in this
    process only (a miss elsewhere)."""

    def __init__(self, folder: Path, local: dict):
        self.folder, self.local = Path(folder), local
        self.folder.mkdir(parents=True, exist_ok=True)

    def _path(self, key: str) -> Path:
        return self.folder / f"{key}.pickle"

    def lock(self, key: str):
        """An exclusive lock on ``key`` across processes, held while one computes it: a
        second process asking for it (a browser test's server worker; the month's two back
        ends at once under xdist) waits, then reads the entry (:func:`_held`)."""
        import contextlib
        import fcntl

        @contextlib.contextmanager
        def held():
            with open(self.folder / f"{key}.lock", "w") as f:
                fcntl.flock(f, fcntl.LOCK_EX)
                yield

        return held()

    def __contains__(self, key: str) -> bool:
        if key in self.local:
            return True
        try:
            self.local[key] = pickle.loads(self._path(key).read_bytes())
        except Exception:                      # noqa: BLE001 - absent or unreadable: a miss
            return False
        return True

    def __getitem__(self, key: str):
        if key not in self:
            raise KeyError(key)
        return self.local[key]

    def __setitem__(self, key: str, value) -> None:
        self.local[key] = value
        try:
            data = pickle.dumps(value)
        except Exception:                      # noqa: BLE001 - kept in this process only
            return
        tmp = self.folder / f"{key}.{os.getpid()}.{threading.get_ident()}.partial"
        tmp.write_bytes(data)
        os.replace(tmp, self._path(key))


def memoised(real, memo: dict | None = None, stats: dict | None = None):
    """``real`` (calibrate_folder's signature) behind the memo (this process's one, or
    ``memo``; hits and misses counted in ``stats``)."""
    memo = _MEMO if memo is None else memo
    stats = STATS if stats is None else stats

    def calibrate_folder(readings, out, *, spec_key, protocol=None, lab=None,
                         table_calibration=None, gyro_type=None, options=None, record=None):
        kw = dict(spec_key=spec_key, protocol=protocol, lab=lab,
                  table_calibration=table_calibration, gyro_type=gyro_type, options=options,
                  record=record)
        out = Path(out)
        if out.exists() and any(out.iterdir()):
            return real(readings, out, **kw)             # not the case the memo knows
        key = pipeline_key(readings, **kw)
        with _held(memo, key):
            return through_memo(memo, stats, key, out, lambda: real(readings, out, **kw),
                                (readings, protocol, lab, table_calibration, out))
    calibrate_folder.__wrapped__ = real
    return calibrate_folder


# ---------------------------------------------------------------------------------------------
# The certificate's rendering (:func:`gonio.records.compute.render_folder`): every issue, every
# draft rendered again after an attach renders the stored results.json with the laboratory
# details of the moment (about 5 s of PDF and figures each). The records tests issue the
# session's one computed result again and again with the same details (the same certificate
# number, people, dates, on SQLite and on PostgreSQL): the same bytes each time. Rendering is a
# pure function of the stored result's bytes, the laboratory file (and the files beside it),
# the specification and the language (the standards: the renderer is a pure function of the
# stored Result); the key is the SHA-256 of these, gonio's version, the ``GONIO_*`` variables
# and today's date, and the same rules as the pipeline's memo hold (an output naming a folder
# is not kept, a filled ``out`` renders, a failure is never stored).

_RENDER_MEMO: dict[str, tuple[dict[str, bytes], object]] = {}
RENDER_STATS = {"hits": 0, "misses": 0}


def render_key(results: bytes, *, spec_key: str, lab, lang: str = "en") -> str:
    """The SHA-256 of every input :func:`gonio.records.compute.render_folder` reads."""
    h = hashlib.sha256()
    _add(h, "gonio", gonio.__version__.encode())
    _add(h, "spec", str(spec_key).encode())
    _add(h, "lang", str(lang).encode())
    _add(h, "results", bytes(results))
    lab = Path(lab)
    _add(h, "lab:" + lab.name, lab.read_bytes())
    for q in sorted(lab.parent.iterdir()):            # the files beside it (it may name them)
        if q.is_file() and q.stat().st_size < 2**24:
            _add(h, "lab-beside:" + q.name, q.read_bytes())
    _add(h, "env", json.dumps(_environment(), sort_keys=True).encode())
    _add(h, "date", dt.date.today().isoformat().encode())
    return h.hexdigest()


def memoised_render(real, memo: dict | None = None, stats: dict | None = None):
    """``real`` (render_folder's signature) behind the memo (this process's one, or ``memo``;
    hits and misses counted in ``stats``)."""
    memo = _RENDER_MEMO if memo is None else memo
    stats = RENDER_STATS if stats is None else stats

    def render_folder(results, out, *, spec_key, lab, lang="en"):
        kw = dict(spec_key=spec_key, lab=lab, lang=lang)
        out = Path(out)
        if (out.exists() and any(out.iterdir())) or not Path(lab).is_file():
            return real(results, out, **kw)              # not the case the memo knows
        key = render_key(results, **kw)
        with _held(memo, key):
            return through_memo(memo, stats, key, out, lambda: real(results, out, **kw),
                                (lab, out))
    render_folder.__wrapped__ = real
    return render_folder


# ---------------------------------------------------------------------------------------------
# The same memos across processes: the browser tests drive a real ``gonio serve``, whose worker
# processes run the pipeline and the rendering (about 25 s and 12 s each); the month of the
# laboratory on SQLite and on PostgreSQL computes and renders the same calibrations with the
# same details (the same bytes). :class:`SessionMemo` keeps a memo's entries as files in a
# folder shared by the session (every xdist worker and every server process); ``server_memo/
# sitecustomize.py`` puts the server's workers behind it (:func:`install_in_process`) where the
# environment names that folder (:data:`SERVER_MEMO_VARIABLE`: not a ``GONIO_*`` variable, so
# not part of any key). The first process to meet a key computes it for real.

#: the environment variable that names the folder of the memo a server's workers share
SERVER_MEMO_VARIABLE = "RECORDS_TEST_SERVER_MEMO"
SERVER_MEMO_BOOT = Path(__file__).resolve().parent / "server_memo"


def install_in_process(folder) -> None:
    """Put this process's :func:`gonio.records.compute.calibrate_folder` and
    :func:`~gonio.records.compute.render_folder` behind the memos kept in ``folder``
    (:class:`SessionMemo`: the test session's), before :mod:`gonio.records.worker` imports
    them."""
    from gonio.records import compute

    if hasattr(compute.calibrate_folder, "__wrapped__"):
        return
    folder = Path(folder)
    compute.calibrate_folder = memoised(compute.calibrate_folder,
                                        SessionMemo(folder / "pipeline", {}),
                                        {"hits": 0, "misses": 0})
    compute.render_folder = memoised_render(compute.render_folder,
                                            SessionMemo(folder / "render", {}),
                                            {"hits": 0, "misses": 0})


def server_environment(folder) -> dict:
    """The environment of a ``gonio serve`` whose workers share the memo in ``folder``."""
    path = [str(SERVER_MEMO_BOOT)]
    if os.environ.get("PYTHONPATH"):
        path.append(os.environ["PYTHONPATH"])
    path.append(str(Path(__file__).resolve().parents[2]))       # tests.records importable
    return dict(os.environ, PYTHONPATH=os.pathsep.join(path),
                **{SERVER_MEMO_VARIABLE: str(folder)})
