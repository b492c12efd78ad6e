"""Scene variables set from outside: ``colosseum run --param mass=2`` and sweeps.

A scene variable is a lower-case key at the top of the scene file (``mass 1.5``); later
expressions use it (``Mass mass * 2``). :func:`with_params` returns the scene text with
each named variable's definition replaced, so everything that uses it — expressions,
``randInterval`` bounds — sees the new value, exactly as if the author had typed it.

>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> scene = folder / "main.scene"
>>> _ = scene.write_text("mass 1.5   // kg\\nlength mass * 2\\n")
>>> print(with_params(scene, {"mass": "3"}), end="")
mass 3   // kg
length mass * 2
>>> with_params(scene, {"mas": "3"})
Traceback (most recent call last):
...
engine.scene.params.ParamError: no scene variable 'mas' in .../main.scene; did you mean 'mass'? ...
"""

from __future__ import annotations

import difflib
from pathlib import Path

import numpy as np

from engine.scene.db import Entry
from engine.scene.diagnostics import SceneError
from engine.scene.parser import parse_file, parse_text


class ParamError(ValueError):
    """A parameter that names no variable of the scene, or one that cannot be set."""


def _variables(path: Path) -> tuple[dict[str, Entry], set[int]]:
    """The scene file's own top-level variables (the last definition of each), and the
    lines holding more than one top-level entry."""
    db = parse_file(path, np.random.default_rng(0))
    own = [e for e in db.root.entries if e.loc.path == str(path)]
    lines = [e.loc.line for e in own]
    return ({e.key: e for e in own if e.key[:1].islower()},
            {line for line in lines if lines.count(line) > 1})


def with_params(path: Path, params: dict[str, str]) -> str:
    """The text of scene file ``path`` with each variable in ``params`` defined as its value
    (text: a number or an expression). Raises ParamError naming a variable the file does
    not define (with the closest ones), SceneError when the file does not parse."""
    path = Path(path)
    variables, shared = _variables(path)
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    for key, value in params.items():
        entry = variables.get(key)
        if entry is None:
            close = difflib.get_close_matches(key, list(variables), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            known = ", ".join(sorted(variables)) or "none"
            raise ParamError(f"no scene variable {key!r} in {path.as_posix()}{hint} "
                             f"(variables: {known})")
        if entry.loc.line in shared:
            raise ParamError(f"cannot set {key} in {path.as_posix()}:{entry.loc.line}: the "
                             "line holds more than the variable; put it on a line of its own")
        line = lines[entry.loc.line - 1]
        start = entry.loc.col - 1
        comment = line.find("//", start)
        tail = line[comment:] if comment >= 0 else line[len(line.rstrip("\r\n")):]
        gap = "   " if comment >= 0 else ""
        lines[entry.loc.line - 1] = f"{line[:start]}{key} {value}{gap}{tail}"
    text = "".join(lines)
    try:
        parse_text(text, str(path), np.random.default_rng(0))
    except SceneError as exc:
        bad = ", ".join(f"{k}={v}" for k, v in params.items())
        raise ParamError(f"{path.as_posix()} does not parse with {bad}: "
                         f"{exc.diagnostics[0].message}") from None
    return text
