"""Writing output files without ever leaving a half-written one behind."""

from __future__ import annotations

import os
import stat
from pathlib import Path


def file_mode(path: Path) -> int | None:
    """The permission bits of ``path``, or None when there is no such file."""
    try:
        return stat.S_IMODE(path.stat().st_mode)
    except FileNotFoundError:
        return None


def _default_mode() -> int:
    """The mode a new file gets (0o666 less the umask), as ``open`` would give it."""
    umask = os.umask(0o022)
    os.umask(umask)
    return 0o666 & ~umask


def write_atomic(path: Path, text: str, mode: int | None = None) -> None:
    """Write to a temporary file beside ``path``, then rename it into place.

    The file ends with ``mode``, else the mode of the file it replaces, else the
    default mode of a new file (not the temporary file's private 0600).
    """
    path = Path(path)
    if mode is None:
        mode = file_mode(path)
    import tempfile  # (and random) for a command that writes, not for every check

    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        os.fchmod(fd, mode if mode is not None else _default_mode())
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            out.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
