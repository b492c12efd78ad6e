"""Content stays in its folder: the files a scene or a script may name.

Content folders are shared, downloaded and served to other machines, so what one
names must not reach the machine it runs on: every file a scene file (``Include``,
every ``File``, ``Script``, ``Texture``, ``Model`` key), a spawned snippet or a
script names has to resolve inside the content folder, or inside a folder the
author allowed (``colosseum run --allow-path DIR``, which ``check`` honours too).
An absolute path, a ``..`` that climbs out and a symlink that points out are
refused alike, by where the name resolves to. The refusal names the line and the
name as written, never what the file holds.

>>> import tempfile
>>> root = Path(tempfile.mkdtemp())
>>> scope = Confinement.of(root)
>>> scope.problem(root / "models" / "cow.obj") is None
True
>>> scope.problem(root / ".." / "secret.txt") == OUTSIDE
True
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

#: The reason a name leading out of the content folder is refused.
OUTSIDE = ("it is outside the content folder (absolute paths, '..' and symlinks may not "
           "lead out of it; colosseum run --allow-path DIR allows a folder)")


def resolved(path: Path) -> Path:
    """``path`` absolute with symlinks resolved where they can be (a loop, a NUL or an
    over-long name leave it as written: :func:`engine.scene.paths.file_problem` then says
    why)."""
    try:
        return path.resolve()
    except (OSError, RuntimeError, ValueError):
        return Path(os.path.abspath(path))


@lru_cache(maxsize=64)
def _roots(folder: Path, allow: tuple[Path, ...]) -> tuple[Path, ...]:
    """The folders resolved once (every spawn of a run names the same ones)."""
    return tuple(dict.fromkeys(resolved(p) for p in (folder, *allow)))


@lru_cache(maxsize=4096)
def _inside(path: str, roots: tuple[Path, ...]) -> bool:
    """Whether ``path`` resolves inside one of ``roots``; remembered, as an imported
    model's 10,000 nodes name one file 10,000 times (resolving walks the file system)."""
    target = resolved(Path(path))
    return any(target.is_relative_to(root) for root in roots)


@dataclass(frozen=True, slots=True)
class Confinement:
    """The folders files may be read from: the content folder and those allowed."""

    roots: tuple[Path, ...]

    @staticmethod
    def of(folder: str | Path, allow: Iterable[str | Path] = ()) -> Confinement:
        """Files inside ``folder`` (the content folder) and inside each of ``allow``."""
        return Confinement(_roots(Path(folder), tuple(map(Path, allow))))

    def allows(self, path: str | Path) -> bool:
        """Whether ``path`` (symlinks followed) lies inside one of the roots."""
        return _inside(os.path.abspath(path), self.roots)  # absolute: a key for any cwd

    def problem(self, path: str | Path) -> str | None:
        """Why ``path`` may not be read (:data:`OUTSIDE`), or None when it may."""
        return None if self.allows(path) else OUTSIDE
