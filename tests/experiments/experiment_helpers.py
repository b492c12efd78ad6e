"""Content folders with an Experiment block, and the experiment command run in-process."""

from __future__ import annotations

import csv
from pathlib import Path

from app.cli import main

BALL = """Object { ID "ball" Position [0 0 1]
  VisualAttributes { Geometry { Primitive "sphere" Size [0.2] } }
  PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.2] } } }
"""


def write_content(folder: Path, experiment: str, lua: str | None = None, top: str = "",
                  files: dict[str, str] | None = None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    script = 'Script "scripts/exp.lua"\n' if lua is not None else ""
    (folder / "main.scene").write_text(f"{top}\n{BALL}{script}Experiment {{\n{experiment}\n}}\n",
                                       encoding="utf-8")
    if lua is not None:
        (folder / "scripts").mkdir(exist_ok=True)
        (folder / "scripts" / "exp.lua").write_text(lua, encoding="utf-8")
    for name, text in (files or {}).items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text, encoding="utf-8")
    return folder


def experiment(*args: str) -> int:
    return main(["--log-level", "warning", "experiment", *args])


def rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))
