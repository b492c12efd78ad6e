"""File names a scene gives (``Include``, assets), checked without ever raising.

A name in a scene file is author text: it may hold a NUL, a component longer than
the OS allows, or lead through a symlink loop. These helpers turn each of those
into a reason to report, where ``Path.resolve`` or ``Path.is_file`` would raise.
"""

from __future__ import annotations

import errno
import stat
from pathlib import Path

#: What :func:`file_problem` says of a name that names nothing, and of a folder.
NOT_FOUND = "not found"
FOLDER = "it is a folder, not a file"


def file_problem(path: Path) -> str | None:
    """Why ``path`` cannot be read as a file, or None when it can."""
    if "\0" in str(path):
        return "the file name contains a NUL character"
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return NOT_FOUND
        return exc.strerror or str(exc)
    if stat.S_ISDIR(mode):
        return FOLDER
    return None if stat.S_ISREG(mode) else "it is not a regular file"


def shown(path: Path | str, limit: int = 160) -> str:
    """A path for a message, its middle elided past ``limit`` characters."""
    text = str(path)
    if len(text) <= limit:
        return text
    half = (limit - 3) // 2
    return text[:half] + "..." + text[-half:]
