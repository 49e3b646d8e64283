"""Atomic file writes: a reader sees the old file or the new one, never half.

The text goes to a temporary file in the target's folder, is flushed and
fsynced, then renamed over the target (``os.replace`` is atomic on POSIX and
Windows). A writer killed midway leaves the old file intact and at most a
stray ``.<name>.*.tmp`` file behind.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..exceptions import FtkinError


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path.

    Raises:
        FtkinError: the folder does not exist or is not writable.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise FtkinError(f"cannot write {path}: folder {folder} does not exist")
    try:
        import tempfile  # here, not at import: it pulls in shutil, random, bz2, lzma

        handle, temporary = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as error:
        raise FtkinError(f"cannot write {path}: {error}") from None
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        if path.exists():
            os.chmod(temporary, path.stat().st_mode & 0o777)
        else:
            os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException as error:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        if isinstance(error, OSError):
            raise FtkinError(f"cannot write {path}: {error}") from None
        raise
    return path


def atomic_write_text(path, text: str) -> Path:
    """Write UTF-8 text to ``path`` atomically; returns the path."""
    return atomic_write_bytes(path, text.encode("utf-8"))
