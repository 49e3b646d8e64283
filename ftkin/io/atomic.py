"""Atomic file writes that never destroy a file: a reader sees the old file or the new one, never
half.

The text goes to a temporary file in the target's folder, is flushed and
fsynced, then renamed over the target (``os.replace`` is atomic on POSIX and
Windows). A writer killed midway leaves the old file intact and at most a
stray ``.<name>.*.tmp`` file behind.

:func:`check_output_path` is the one check every output goes through (the
CLI calls it for every ``-o``, ``--html``, ``--png``, ``--plot`` before
anything is read or written): an empty name, an existing output that is not a
regular file (a folder, a device such as ``/dev/null``, a FIFO, a socket) and
an output that is one of the command's inputs (``os.path.samefile``: also
through symlinks and hard links) are refused. An output that is a symlink is
written through to its target, atomically in the target's folder, so the link
survives.
"""

import contextlib
import os
import stat
import tempfile
from pathlib import Path

from ..exceptions import FtkinError, InvalidInput

_KINDS = {
    stat.S_IFDIR: "a folder",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFSOCK: "a socket",
}  # what an existing output that is not a regular file is, by its ``stat`` file type


def check_output_path(path, inputs=(), what: str = "output") -> Path:
    """Refuse an output path that would destroy something; returns it as a :class:`~pathlib.Path`.

    Args:
        path: The file about to be written.
        inputs: Paths the same command reads (files or folders); names that do
            not exist are skipped.
        what: How the output is named in messages (e.g. ``"-o/--output"``).

    Raises:
        InvalidInput: an empty name, a folder that does not exist, an existing output that is
            not a regular file, or an output that is the same file as one of ``inputs``.
    """
    if path is None or not str(path).strip():
        raise InvalidInput(f"{what}: the file name is empty; expected a path to write")
    path = Path(path)
    try:
        status = os.stat(path)  # follows symlinks: the file that would be written
    except FileNotFoundError:
        folder = path.parent if str(path.parent) else Path(".")
        if not folder.is_dir():  # said before the work, not after it
            raise InvalidInput(
                f"{what} {path}: the folder {folder} does not exist; create it or name another"
            ) from None
        return path
    except OSError as error:
        raise InvalidInput(f"{what} {path}: cannot check the output: {error}") from None
    if not stat.S_ISREG(status.st_mode):
        raise InvalidInput(
            f"{what} {path} exists and is "
            f"{_KINDS.get(stat.S_IFMT(status.st_mode), 'not a regular file')}; "
            "refusing to replace it: expected a regular file or a new name"
        )
    for source in inputs:
        with contextlib.suppress(OSError):  # an input that does not exist is skipped
            if source is not None and str(source) and os.path.samefile(path, source):
                raise InvalidInput(
                    f"{what} {path} is the input {source} of this command (same file); refusing to "
                    "overwrite an input: "
                    "write to another file"
                )
    return path


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path.

    A symlink is written through: its target is replaced (atomically, in the
    target's folder) and the link kept.

    Raises:
        InvalidInput: empty name, or an existing path that is not a regular file.
        FtkinError: the folder does not exist or is not writable.
    """
    path = check_output_path(path)
    # a symlink is written through: the final target is replaced
    target = Path(os.path.realpath(path)) if path.is_symlink() else path
    if not target.parent.is_dir():
        raise FtkinError(f"cannot write {path}: folder {target.parent} does not exist")
    try:
        handle, temporary = tempfile.mkstemp(
            dir=target.parent, prefix=f".{target.name}.", suffix=".tmp"
        )
    except OSError as error:
        raise FtkinError(f"cannot write {path}: {error}") from None
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, target.stat().st_mode & 0o777 if target.exists() else 0o644)
        os.replace(temporary, target)
    except BaseException as error:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        if isinstance(error, OSError):
            raise FtkinError(f"cannot write {path}: {error}") from None
        raise
    return path


def atomic_write_text(path, text: str) -> Path:
    """Write UTF-8 text to ``path`` atomically; returns the path."""
    return atomic_write_bytes(path, text.encode("utf-8"))
