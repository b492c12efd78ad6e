"""Dependencies run one way and nothing imports in a circle (tools/layers.py)."""

from __future__ import annotations

from pathlib import Path

from tools.layers import check


def test_the_project_has_no_upward_import_and_no_cycle():
    assert check() == []


def write(root: Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_the_checker_finds_upward_imports_and_cycles_but_not_type_hints(tmp_path: Path):
    write(tmp_path, {
        "components/__init__.py": "",
        "components/bad.py": "def f():\n    from engine import app\n",  # lazy: still counts
        "engine/__init__.py": "",
        "engine/app.py": "from engine import world\n",
        "engine/world.py": "import engine.app\n",
        "engine/hints.py": ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                            "    from systems import x\n"),
        "engine/render/__init__.py": "from engine.render import gl\n",
        "engine/render/gl.py": "",
        "engine/scene.py": "from engine.render.gl import draw\n",
        "systems/__init__.py": "", "systems/x.py": "", "tools/__init__.py": "",
    })
    problems = check(tmp_path)
    assert problems == [
        "components/bad.py:2: components.bad (components) imports engine.app (engine core), "
        "a higher layer",
        "engine/scene.py:1: engine.scene (engine core) imports engine.render.gl "
        "(engine services), a higher layer",
        "import cycle: engine.app -> engine.world",
    ]
