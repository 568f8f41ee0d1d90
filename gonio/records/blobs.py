"""The content-addressed file store: every readings file, results.json and certificate is
kept once, under its SHA-256, and never modified.

Layout: ``<data>/blobs/<first two hex digits>/<sha256>``, files read-only (0444). A file is
written to a temporary name in the same folder, flushed, fsynced and renamed into place,
so a crash leaves either no file or the whole file; a file whose name exists already is
not written again (same name, same bytes). Reading checks the hash: a file changed on disk
behind gonio's back is refused, never served. An uploaded file's own name never becomes a
path: only the hex digest does.

>>> import tempfile, pathlib
>>> root = pathlib.Path(tempfile.mkdtemp())
>>> h = put_bytes(root, b"abc")
>>> h
'ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad'
>>> get_bytes(root, h)
b'abc'
"""

from __future__ import annotations

import hashlib
import os
import re
import tempfile
from pathlib import Path
from typing import BinaryIO

from gonio.errors import GonioError

_HEX = re.compile(r"[0-9a-f]{64}")


def size_text(n_bytes: float) -> str:
    """A size for a person: binary units with the exact bytes.

    >>> size_text(256 * 2**20), size_text(1000)
    ('256 MiB (268,435,456 bytes)', '1,000 bytes')
    """
    n = int(n_bytes)
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= scale:
            return f"{n / scale:.4g} {unit} ({n:,} bytes)"
    return f"{n:,} bytes"


def blob_path(root: str | os.PathLike, sha256: str) -> Path:
    """Where the file with this digest lives (the digest is checked to be 64 hex digits)."""
    if not isinstance(sha256, str) or not _HEX.fullmatch(sha256):
        raise GonioError("not a SHA-256 digest", key="sha256")
    return Path(root) / sha256[:2] / sha256


def put_stream(root: str | os.PathLike, stream: BinaryIO, *,
               limit_bytes: float | None = None) -> tuple[str, int]:
    """Store the bytes read from ``stream``; returns (sha256, size). Over ``limit_bytes``
    is a GonioError and nothing is stored."""
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    h = hashlib.sha256()
    size = 0
    fd, tmp = tempfile.mkstemp(prefix=".incoming-", dir=root)
    try:
        with os.fdopen(fd, "wb") as fh:
            while True:
                piece = stream.read(1 << 20)
                if not piece:
                    break
                size += len(piece)
                if limit_bytes is not None and size > limit_bytes:
                    raise GonioError(f"the file is larger than the limit of "
                                     f"{size_text(limit_bytes)}", key="upload")
                h.update(piece)
                fh.write(piece)
            fh.flush()
            os.fsync(fh.fileno())
        digest = h.hexdigest()
        final = blob_path(root, digest)
        final.parent.mkdir(exist_ok=True)
        if final.exists():
            os.unlink(tmp)
        else:
            os.chmod(tmp, 0o444)
            os.replace(tmp, final)
        return digest, size
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def put_bytes(root: str | os.PathLike, data: bytes) -> str:
    """Store ``data``; returns its SHA-256."""
    import io
    return put_stream(root, io.BytesIO(data))[0]


def put_file(root: str | os.PathLike, path: str | os.PathLike) -> tuple[str, int]:
    """Store a copy of the file at ``path``; returns (sha256, size)."""
    with open(path, "rb") as fh:
        return put_stream(root, fh)


def get_bytes(root: str | os.PathLike, sha256: str) -> bytes:
    """The stored bytes, checked against their digest."""
    path = blob_path(root, sha256)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise GonioError("stored file missing from the blob store", file=path) from None
    if hashlib.sha256(data).hexdigest() != sha256:
        raise GonioError("stored file does not match its SHA-256 (changed on disk)", file=path)
    return data


def verify(root: str | os.PathLike, sha256: str) -> bool:
    """True when the stored file exists and matches its digest."""
    try:
        get_bytes(root, sha256)
    except GonioError:
        return False
    return True


def readings_content(root: str | os.PathLike, sha256: str) -> str | None:
    """The content digest (:func:`gonio.formats.content.content_sha256`) of the stored file
    ``sha256``; None where the file is not in the store or holds no readable table."""
    from gonio.formats.content import content_sha256

    src = blob_path(root, sha256)
    if not src.is_file():
        return None
    try:
        return content_sha256(src)
    except (OSError, ValueError):
        return None


def readings_facts(root: str | os.PathLike, sha256: str) -> tuple[str | None, str | None]:
    """(content digest, the SHA-256 of the stream it was reduced from) of the stored
    readings file ``sha256`` (:func:`readings_content`,
    :func:`gonio.formats.content.source_sha256`); (None, None) where it is not stored."""
    from gonio.formats.content import source_sha256

    src = blob_path(root, sha256)
    if not src.is_file():
        return None, None
    return readings_content(root, sha256), source_sha256(src)


def content_rows(root: str | os.PathLike, shas) -> list[dict]:
    """The ``readings_contents`` rows of the stored readings files ``shas`` that hold a
    table (:func:`readings_facts`): ``{"sha256", "content_sha256", "source_sha256"}``, in the
    order given (a migration's backfill, a restore)."""
    rows = []
    for sha in shas:
        digest, source = readings_facts(root, sha)
        if digest is not None:
            rows.append({"sha256": sha, "content_sha256": digest, "source_sha256": source})
    return rows
