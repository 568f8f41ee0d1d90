"""Safe output: checked places, atomic files, and whole output sets.

Three layers, all raising :class:`gonio.errors.GonioError` (one line naming the
place) for anything a user can cause — a full disk, a read-only folder, a name
too long, a FIFO, a device or a symlink where a file is to go:

* :func:`write_bytes` / :func:`write_text` — one file, via a temporary file
  beside it and ``os.replace``; the old file or the new one, never half a file.
  A target that exists and is not a regular file (a symlink, FIFO, device,
  folder) is refused, never replaced.
* :func:`check_output_file` — the checks a command runs on a single output file
  (``gonio reduce --out``, ``--plot``) before any work: not empty, not an input,
  not a special file, and an existing readings/stream file only with ``force``.
* :func:`output_set` — a whole run's outputs (results, summary, tables,
  certificate, DCC, truth, readings) staged in a hidden folder beside ``out`` and
  swapped in with one atomic ``renameat2(RENAME_EXCHANGE)`` only after every
  part is written, with ``gonio-manifest.json`` (every file's SHA-256 and the
  source's). The folder is locked (``flock``) for the run, so two runs into the
  same ``--out`` cannot mix: the second is refused. A failed or interrupted run
  leaves the previous set untouched; a staging folder left by a killed run is
  removed (and reported) by the next run into the same place.

:func:`output_dir` is the API's per-part form: inside an active
:func:`output_set` it hands out that set's staging folder; alone, it stages its
own files and moves them into ``out`` together (other files in ``out`` stay).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import hashlib
import json
import os
import shutil
import signal
import stat
import sys
import tempfile
from pathlib import Path
from typing import Callable, Iterable, Iterator

from gonio.errors import GonioError

#: The manifest written into every output set.
MANIFEST = "gonio-manifest.json"
#: File names that hold a laboratory's data: never replaced without ``force``.
PROTECTED_NAMES: tuple[str, ...] = ("readings.csv", "stream.csv")

_ACTIVE: dict[str, Path] = {}          # resolved out folder -> staging folder of the open set
_COMMAND: list[str | None] = [None]     # the CLI command running (recorded in the manifest)
#: Files that mark a folder as a coverage study of ``gonio validate``.
STUDY_NAMES: tuple[str, ...] = ("validation.json", ".validate-partial")


def set_command(name: str | None) -> None:
    """Record which ``gonio`` command is running: the manifests it writes name it, and a
    folder holding another command's outputs is refused where the two would mix."""
    _COMMAND[0] = name


def current_command() -> str | None:
    """The command :func:`set_command` recorded (None when gonio is used as a library)."""
    return _COMMAND[0]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _kind(st_mode: int) -> str:
    for test, name in ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a folder"),
                       (stat.S_ISREG, "a file")):
        if test(st_mode):
            return name
    return "a special file"


def _oserror(exc: OSError, path, doing: str) -> GonioError:
    reason = exc.strerror or str(exc)
    return GonioError(f"cannot {doing}: {reason}", file=path)


def _lstat(path: Path):
    try:
        return os.lstat(path)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise _oserror(exc, path, "inspect the output place") from None


def _check_parent(path: Path, what: str) -> None:
    """Every existing ancestor of ``path`` must be a folder (a file or loop is named)."""
    for anc in reversed(path.parents):
        st = _lstat(anc)
        if st is None:
            return
        if stat.S_ISLNK(st.st_mode):
            try:
                st = os.stat(anc)
            except OSError as exc:
                raise _oserror(exc, anc, f"use {what} here") from None
        if not stat.S_ISDIR(st.st_mode):
            raise GonioError(f"{what}: {anc} is {_kind(st.st_mode)}, not a folder", file=path)


def _same(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.abspath(a) == os.path.abspath(b)


def _nonempty(path, what: str) -> Path:
    if path is None or str(path).strip() == "":
        raise GonioError(f"{what} is empty; give a file or folder name")
    return Path(path)


def check_output_file(path, *, what: str = "--out", inputs: Iterable = (),
                      force: bool = False, protected: bool = False) -> Path:
    """Refuse an output file place before any work is done.

    Refused: an empty name; a place that exists and is not a regular file
    (symlink, FIFO, device, folder); a file that is one of ``inputs``; an existing
    file when ``protected`` (a readings or stream file) unless ``force``.

    >>> check_output_file("")
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: --out is empty; give a file or folder name
    """
    path = _nonempty(path, what)
    _check_parent(path, what)
    st = _lstat(path)
    for inp in inputs:
        if inp is not None and (_same(path, Path(inp)) if st is not None
                                else os.path.abspath(path) == os.path.abspath(inp)):
            raise GonioError(f"{what} would replace the input {inp}; choose another name",
                             file=path)
    if st is None:
        return path
    if not stat.S_ISREG(st.st_mode):
        raise GonioError(f"{what} is {_kind(st.st_mode)}; only a regular file is replaced",
                         file=path)
    if protected and not force:
        raise GonioError(f"{what} exists and holds data; give --force to replace it", file=path)
    return path


#: Suffixes of the files a laboratory's data and gonio's results live in.
DATA_SUFFIXES: tuple[str, ...] = (".csv", ".parquet", ".toml", ".json", ".npz", ".xml", ".txt")


def holds_data(path) -> bool:
    """Whether ``path`` is an existing file that holds data (by suffix, or by content: a
    ``#`` metadata line or a Parquet file), which a figure or report never replaces."""
    p = Path(path)
    if not p.is_file():
        return False
    if p.suffix.lower() in DATA_SUFFIXES:
        return True
    try:
        with open(p, "rb") as fh:
            head = fh.read(4)
    except OSError:
        return False
    return head.startswith((b"#", b"\xef\xbb\xbf#", b"PAR1"))


def check_output_files(places: dict, *, inputs: Iterable = (),
                       formats: dict | None = None) -> dict:
    """:func:`check_output_file` for each named output (``{"--report": path, ...}``, None
    skipped) against every input, before any work; two outputs at one place are refused,
    so is a suffix not in ``formats[what]`` (e.g. a figure named ``out.parquet``) and an
    existing data file (:func:`holds_data`).

    >>> check_output_files({"--plot": "a.png", "--report": "a.png"})
    Traceback (most recent call last):
    ...
    gonio.errors.GonioError: --report and --plot name the same file a.png
    """
    inputs = [i for i in inputs if i is not None]
    seen: dict[str, str] = {}
    for what, path in places.items():
        if path is None:
            continue
        check_output_file(path, what=what, inputs=inputs)
        allowed = (formats or {}).get(what)
        if allowed and Path(path).suffix.lstrip(".").lower() not in allowed:
            raise GonioError(f"{what}: cannot write a file of type "
                             f"{Path(path).suffix or '(none)'!r}; use "
                             f"{', '.join('.' + f for f in allowed)}", file=path)
        if holds_data(path):
            raise GonioError(f"{what} would replace {path}, a data file (readings, stream, "
                             "protocol, results); a figure or page never replaces one",
                             file=path)
        owner = _set_owning(path)
        if owner is not None:
            raise GonioError(f"{what} would replace {path}, a file of the output set in "
                             f"{owner} ({MANIFEST} lists it: another gonio run's); choose "
                             "another place", file=path)
        key = os.path.abspath(path)
        if key in seen:
            raise GonioError(f"{what} and {seen[key]} name the same file {path}")
        seen[key] = what
    return places


def _set_owning(path) -> Path | None:
    """The output folder (this file's folder or up to two above) whose manifest lists the
    existing file ``path``: a figure or page of one command never replaces a file of
    another command's set (``align --report CAL/certificate.html``
    replaced a calibration's certificate, exit 0)."""
    p = Path(path)
    if not p.is_file():
        return None
    real = Path(os.path.realpath(p))
    for folder in list(real.parents)[:3]:
        m = read_manifest(folder)
        if m is not None and real.relative_to(folder).as_posix() in m["files"]:
            return folder
    return None


def write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temporary file + ``os.replace``).

    An existing non-regular target (symlink, FIFO, device, folder) is refused; any
    failure (full disk, permissions, name too long) is a GonioError naming the file
    and leaves no temporary file behind.
    """
    path = Path(path)
    _check_parent(path, "output")
    st = _lstat(path)
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise GonioError(f"output place is {_kind(st.st_mode)}; only a regular file is replaced",
                         file=path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _oserror(exc, path.parent, "create the output folder") from None
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=".gonio-", suffix=".tmp", dir=path.parent)
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        if isinstance(exc, OSError):
            raise _oserror(exc, path, "write") from None
        raise
    return path


def write_text(path: str | Path, text: str) -> Path:
    """Write UTF-8 text atomically, with ``\\n`` line ends on every platform."""
    return write_bytes(path, text.encode("utf-8"))


def sha256_file(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# ----------------------------------------------------------------- output folders

def _tag(out: Path) -> str:
    return ".gonio-" + hashlib.sha256(out.name.encode("utf-8", "surrogatepass")).hexdigest()[:10]


def _note(msg: str) -> None:
    sys.stderr.write(f"gonio: note: {msg}\n")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def clean_stale(out: Path) -> list[Path]:
    """Remove staging folders a killed run left beside ``out``; returns what was removed."""
    removed = []
    tag = _tag(out)
    try:
        names = os.listdir(out.parent)
    except OSError:
        return removed
    for name in names:
        if not name.startswith(tag + "-"):
            continue
        try:
            pid = int(name[len(tag) + 1:].split("-")[1])
        except (IndexError, ValueError):
            pid = -1
        if pid > 0 and _alive(pid):
            continue
        p = out.parent / name
        shutil.rmtree(p, ignore_errors=True)
        if not p.exists():
            removed.append(p)
            _note(f"removed {p}, a staging folder left by an interrupted run into {out}")
    return removed


def _check_dir_place(out, what: str) -> Path:
    out = _nonempty(out, what)
    absolute = Path(os.path.abspath(out))
    if not absolute.name:
        raise GonioError(f"{what} is a filesystem root; give a folder inside it", file=out)
    cwd = os.path.abspath(os.getcwd())
    if cwd == str(absolute) or cwd.startswith(str(absolute) + os.sep):
        raise GonioError(f"{what} is the current folder or holds it; a run replaces its whole "
                         "output folder, so give a folder below", file=out)
    out = absolute
    _check_parent(out, what)
    st = _lstat(out)
    if st is not None and not stat.S_ISDIR(st.st_mode):
        raise GonioError(f"{what} is {_kind(st.st_mode)}, not a folder", file=out)
    return out


def _lock(out: Path, what: str):
    """Create ``out`` if needed and take an exclusive lock on it; returns (fd, created)."""
    created = False
    for _ in range(5):
        if not out.exists():
            try:
                out.mkdir(parents=True)
                created = True
            except FileExistsError:
                pass
            except OSError as exc:
                raise _oserror(exc, out, f"create the {what} folder") from None
        try:
            fd = os.open(out, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        except OSError as exc:
            raise _oserror(exc, out, f"open the {what} folder") from None
        import fcntl
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise GonioError(f"another gonio run is writing into this {what} folder; "
                             "wait for it or choose another folder", file=out) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(out).st_ino
        except OSError:
            same = False
        if same:
            return fd, created
        os.close(fd)                  # swapped under us by a finishing run: lock the new one
    raise GonioError(f"the {what} folder keeps changing; another program is writing into it",
                     file=out)


def _stage(out: Path) -> Path:
    try:
        stage = Path(tempfile.mkdtemp(prefix=f"{_tag(out)}-stage-{os.getpid()}-",
                                      dir=out.parent))
        os.chmod(stage, 0o777 & ~_umask())
    except OSError as exc:
        raise _oserror(exc, out.parent, "create a staging folder") from None
    return stage


def _exchange(a: Path, b: Path) -> None:
    """Swap two folders atomically (Linux renameat2 RENAME_EXCHANGE), else by two renames."""
    libc = ctypes.CDLL(None, use_errno=True)
    fn = getattr(libc, "renameat2", None)
    if fn is not None:
        at_fdcwd, rename_exchange = -100, 2
        if fn(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
            return
        err = ctypes.get_errno()
        if err not in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP):
            raise OSError(err, os.strerror(err), str(b))
    tmp = a.with_name(a.name + "-old")
    os.rename(b, tmp)
    os.rename(a, b)
    os.rename(tmp, a)


def _manifest(stage: Path, source_sha256, extra: dict | None, exclude=()) -> None:
    from gonio import __version__

    files = {}
    skip = set(exclude)                     # files kept for the user: not gonio's to list
    for p in sorted(stage.rglob("*")):
        if p.is_file() and p.name != MANIFEST and p.relative_to(stage).as_posix() not in skip:
            files[p.relative_to(stage).as_posix()] = sha256_file(p)
    d = {"gonio_version": __version__, "source_sha256": source_sha256, **(extra or {}),
         "files": files}
    if current_command() is not None:
        d["command"] = current_command()
    write_text(stage / MANIFEST, json.dumps(d, indent=2, ensure_ascii=False, sort_keys=True)
               + "\n")


def read_manifest(out: str | Path) -> dict | None:
    """The manifest of an output set, or None when ``out`` holds none (or a damaged one)."""
    try:
        d = json.loads((Path(out) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return d if isinstance(d, dict) and isinstance(d.get("files"), dict) else None


def carried_inputs(out: Path, inputs: Iterable) -> dict[str, Path]:
    """Inputs that lie inside ``out``: relative path -> path (kept across the swap).

    A run into the folder that holds its input (``calibrate lab/readings.csv --out lab``)
    keeps that input: it is linked into the new set, never replaced. A folder or a
    symlink given as input inside ``out`` is refused.
    """
    real_out = os.path.realpath(out)
    out_rel: dict[str, Path] = {}
    inputs = list(inputs)
    inputs += source_set_files(out, inputs)
    for inp in inputs:
        if inp is None or not str(inp).strip():
            continue
        ri = os.path.realpath(inp)
        if ri == real_out:
            raise GonioError(f"the output folder is also an input ({inp})", file=out)
        if ri.startswith(real_out + os.sep):
            if not os.path.isfile(ri):
                raise GonioError(f"the output folder holds the input {inp}, which is not a "
                                 "regular file", file=out)
            out_rel[Path(os.path.relpath(ri, real_out)).as_posix()] = Path(ri)
    return out_rel


def _is_source_set(man: dict) -> bool:
    """Whether a manifest is that of data a run reads (``gonio simulate``: readings,
    stream, thermal programme, truth), not of results."""
    cmd = man.get("command")
    if cmd is not None:
        return cmd == "simulate"
    files = man["files"]
    return not any(n in files for n in ("results.json", "validation.json")) and \
        any(Path(n).name in PROTECTED_NAMES or Path(n).name.startswith("stream.") for n in files)


def source_set_files(out, inputs: Iterable) -> list[Path]:
    """Files of ``out`` that are a run's inputs beyond those named: when one input lies in
    ``out`` and ``out`` holds the simulated set it came from, every file of that set
    (readings, the thermal file the readings name, truth.json); and the inputs a previous
    run into ``out`` kept (its manifest's ``inputs_kept``). They are kept, never deleted."""
    out = Path(out)
    man = read_manifest(out)
    if man is None:
        return []
    kept = [n for n in man.get("inputs_kept") or () if isinstance(n, str)]
    inside = _reads_from(out, inputs)
    names = list(kept)
    if inside and _is_source_set(man):
        names += list(man["files"])
    found = []
    for n in dict.fromkeys(names):
        p = out / n
        if ".." not in Path(n).parts and not Path(n).is_absolute() and p.is_file() \
                and not p.is_symlink():
            found.append(p)
    return found


def holds_study(out: Path, man: dict | None = None) -> bool:
    """Whether ``out`` holds a coverage study of ``gonio validate`` (its JSON, its partial
    batches, or a manifest that says so)."""
    if man is None:
        man = read_manifest(out)
    if man is not None and man.get("command") == "validate":
        return True
    return any(os.path.lexists(Path(out) / n) for n in STUDY_NAMES)


def _refuse_mixing(out: Path, what: str, inputs: Iterable = ()) -> None:
    """A folder holds the outputs of one run of one command: a coverage study and a
    calibration (or a simulation) never share one, whichever comes second; a folder another
    command wrote (``gonio demo``'s set, a calibration) is not replaced by a different
    command — the one exception is the documented workflow, a run whose input lies in the
    folder ``gonio simulate`` wrote, which keeps that whole set (:func:`source_set_files`).
    Nothing of the other run is deleted."""
    if _lstat(out) is None:
        return
    man = read_manifest(out)
    cmd = current_command()
    other = None if man is None else man.get("command")
    if cmd is not None and other is not None and other != cmd and cmd != "validate" \
            and not (other == "simulate" and _reads_from(out, inputs)):
        raise GonioError(f"{what} holds the outputs of gonio {other}; a folder holds one "
                         f"command's outputs and gonio {cmd} would replace them: choose "
                         "another folder", file=out)
    if cmd == "validate":
        other = None if man is None else man.get("command")
        if other not in (None, "validate") or (other is None and man is not None
                                                and not holds_study(out, man)):
            name = f"gonio {other}" if other else "another gonio run"
            raise GonioError(f"{what} holds the outputs of {name}; a folder holds one "
                             "command's outputs: choose another folder for the study",
                             file=out)
    elif holds_study(out, man):
        raise GonioError(f"{what} holds a coverage study of gonio validate (validation.json "
                         "or .validate-partial); a folder holds one command's outputs: "
                         "choose another folder", file=out)


def _folder_files(out: Path, what: str) -> list[str]:
    """Relative paths of every file (and symlink) in ``out``, the manifest excepted."""
    try:
        names = sorted(os.listdir(out))
    except OSError as exc:
        raise _oserror(exc, out, f"list the {what} folder") from None
    files = []
    for n in names:
        p = out / n
        if n == MANIFEST:
            continue
        if p.is_dir() and not p.is_symlink():
            files += sorted(f.relative_to(out).as_posix() for f in p.rglob("*")
                            if not f.is_dir() or f.is_symlink())
        else:
            files.append(n)
    return files


def foreign_files(out: Path, inputs: Iterable = (), what: str = "--out") -> list[str]:
    """Files in ``out`` that gonio did not write (not in its manifest) and that are not
    the run's inputs: they are kept, unchanged, in the new set (a log the user
    redirected there, notes); a run that would write one of their names is refused."""
    if _lstat(out) is None:
        return []
    carried = carried_inputs(out, inputs)
    man = read_manifest(out)
    listed = man["files"] if man is not None else {}
    return [f for f in _folder_files(out, what) if f not in carried and f not in listed]


def _reads_from(out: Path, inputs: Iterable) -> bool:
    """Whether one of ``inputs`` lies inside the folder ``out``."""
    real_out = os.path.realpath(out)
    return any(inp is not None and str(inp).strip() and
               os.path.realpath(inp).startswith(real_out + os.sep) for inp in inputs)


def _check_replaceable(out: Path, inputs: Iterable, force: bool, what: str) -> None:
    inputs = list(inputs)
    _refuse_mixing(out, what, inputs)
    man = read_manifest(out)
    if man is None:
        return                            # nothing gonio wrote; foreign files are kept
    carried = carried_inputs(out, inputs)
    listed = man["files"]
    for rel in _folder_files(out, what):
        if rel in carried or rel not in listed:
            continue                      # inputs and foreign files are kept, never replaced
        q = out / rel
        if not q.is_file() or q.is_symlink() or sha256_file(q) != listed[rel]:
            if not force:
                raise GonioError(f"{what} holds {rel!r}, changed since gonio wrote the "
                                 "folder; give --force to replace the folder", file=out)
        elif Path(rel).name in PROTECTED_NAMES and not force:
            raise GonioError(f"{what} holds {rel!r}; give --force to replace it", file=out)


def active_stage(out: str | Path) -> Path | None:
    """The staging folder of the :func:`output_set` open for ``out``, if any."""
    if not str(out):
        return None
    return _ACTIVE.get(os.path.realpath(out))


@contextlib.contextmanager
def output_set(out: str | Path, *, inputs: Iterable = (), force: bool = False,
               source_sha256: str | None = None, what: str = "--out",
               extra: dict | None = None,
               before_swap: Callable[[Path], None] | None = None,
               writes: Iterable[str] = ()) -> Iterator[Path]:
    """Stage one run's whole output set and swap it into ``out`` when all parts are written.

    Refused before any work: an empty name, a place that is not a folder, a folder
    holding one of ``inputs``, gonio's files changed since gonio wrote them, and an
    existing readings/stream file — the last two unless ``force``. Files gonio did
    not write (and inputs inside ``out``) are kept in the new set, linked unchanged;
    a run that would write one of their names is refused at the swap, or before any work
    where the name is one of ``writes`` (the names the run writes whatever happens: a
    simulation's readings.csv). Another run into the same folder is refused while
    this one holds the lock. ``before_swap(stage)``: called with the finished set (its
    manifest written) just before the swap, to accept it (``calibrate --record``: the
    records take it first); whatever it raises refuses the set. On any exception (or
    SIGINT/SIGTERM raised as one) the staging folder is removed and ``out`` is as before.
    """
    out = _check_dir_place(out, what)
    parent = out.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _oserror(exc, parent, f"create the folder of {what}") from None
    fd, created = _lock(out, what)
    key = os.path.realpath(out)
    stage = None
    try:
        clean_stale(out)
        _check_replaceable(out, inputs, force, what)
        stage = _stage(out)
        _ACTIVE[key] = stage
        carried = carried_inputs(out, inputs)
        foreign = foreign_files(out, inputs, what)
        kept = [(rel, src, "its input") for rel, src in carried.items()] + \
            [(rel, out / rel, "a file gonio did not write") for rel in foreign]
        writes = set(writes)
        for rel, _src, kind in kept:                  # known now: refused before the work
            if rel in writes:
                raise GonioError(f"the run would replace {kind}, {rel}; move it or choose "
                                 f"another {what}", file=out)
        yield stage
        for rel, src, kind in kept:                   # inputs and the user's files stay
            dst = stage / rel
            if os.path.lexists(dst):
                raise GonioError(f"the run would replace {kind}, {rel}; move it or choose "
                                 f"another {what}", file=out)
            try:
                dst.parent.mkdir(parents=True, exist_ok=True)
                try:                                  # same inode: an open log keeps writing
                    os.link(src, dst, follow_symlinks=False)
                except OSError:
                    shutil.copy2(src, dst, follow_symlinks=False)
            except OSError as exc:
                raise _oserror(exc, dst, "keep the file in the new set") from None
        info = dict(extra or {})
        if carried:
            info["inputs_kept"] = sorted(carried)
        if foreign:
            info["foreign_files_kept"] = sorted(foreign)
        _manifest(stage, source_sha256, info or extra, exclude=foreign)
        if before_swap is not None:         # refused: nothing of this set reaches ``out``
            before_swap(stage)
        sigs = {signal.SIGINT, signal.SIGTERM}
        old = signal.pthread_sigmask(signal.SIG_BLOCK, sigs)
        try:
            try:
                _exchange(stage, out)
            except OSError as exc:
                raise _oserror(exc, out, f"move the finished set into {what}") from None
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                os.rmdir(out)
        raise
    finally:
        _ACTIVE.pop(key, None)
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)     # the old set after a swap
        os.close(fd)


@contextlib.contextmanager
def output_dir(out: str | Path) -> Iterator[Path]:
    """Stage outputs and move them into ``out`` together (the API's per-part writer).

    Inside an open :func:`output_set` for ``out`` this yields that set's staging
    folder (the set is swapped in as a whole later). Alone, it locks ``out``, stages
    the files beside it and moves each into place only when all are written; other
    files already in ``out`` stay (an existing manifest is updated).

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp()) / "run"
    >>> try:
    ...     with output_dir(d) as stage:
    ...         _ = (stage / "a.txt").write_text("half")
    ...         raise RuntimeError("failed mid-run")
    ... except RuntimeError:
    ...     pass
    >>> (d / "a.txt").exists()
    False
    """
    st = active_stage(out)
    if st is not None:
        yield st
        return
    out = _check_dir_place(out, "output folder")
    fd, created = _lock(out, "output")
    stage = None
    try:
        clean_stale(out)
        _refuse_mixing(out, "output folder")
        stage = _stage(out)
        yield stage
        items = [p for p in sorted(stage.rglob("*")) if p.is_file()]
        for item in items:                       # refuse special targets before moving any
            target = out / item.relative_to(stage)
            s = _lstat(target)
            if s is not None and not stat.S_ISREG(s.st_mode):
                raise GonioError(f"output place is {_kind(s.st_mode)}; only a regular file is "
                                 "replaced", file=target)
        man = read_manifest(out)
        if man is None and current_command() is not None:     # the folder says who wrote it
            man = {"gonio_version": _version(), "command": current_command(), "files": {}}
        try:
            for item in items:
                target = out / item.relative_to(stage)
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(item, target)
                if man is not None:
                    man["files"][target.relative_to(out).as_posix()] = sha256_file(target)
        except OSError as exc:
            raise _oserror(exc, out, "move the outputs into place") from None
        if man is not None:
            write_text(out / MANIFEST, json.dumps(man, indent=2, ensure_ascii=False,
                                                  sort_keys=True) + "\n")
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                os.rmdir(out)
        raise
    finally:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
        os.close(fd)


def check_output_folder_place(out, what: str = "--out") -> Path:
    """The place checks alone (not empty, not a root or the current folder, a real folder
    or nothing yet, its parent a folder) for a command that adds to its folder instead of
    replacing it (``gonio validate`` keeps resumable batches there), and no other
    command's outputs there (:func:`_refuse_mixing`)."""
    out = _check_dir_place(out, what)
    _refuse_mixing(out, what)
    return out


def _version() -> str:
    from gonio import __version__
    return __version__


def check_output_dir(out, *, inputs: Iterable = (), force: bool = False,
                     what: str = "--out") -> Path:
    """The checks :func:`output_set` makes, run before any work (no lock, nothing created)."""
    out = _check_dir_place(out, what)
    if _lstat(out) is not None:
        _check_replaceable(out, inputs, force, what)
    return out
