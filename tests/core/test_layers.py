"""Dependencies run one way and nothing imports in a circle (tools/layers.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

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
        "services/render/__init__.py": "from services.render import gl\n",
        "services/render/gl.py": "",
        "engine/scene.py": "from services.render.gl import draw\n",
        "systems/__init__.py": "", "systems/x.py": "", "tools/__init__.py": "",
        "app/__init__.py": "", "app/cli.py": "import systems.x\nimport tools\n",
    })
    problems = check(tmp_path)
    assert problems == [
        "app/cli.py:2: app.cli (application) imports tools (developer tools), a higher layer",
        "components/bad.py:2: components.bad (components) imports engine.app (engine core), "
        "a higher layer",
        "engine/scene.py:1: engine.scene (engine core) imports services.render.gl "
        "(services), a higher layer",
        "import cycle: engine.app -> engine.world",
    ]


def test_the_layer_map_is_one_top_level_folder_per_layer_and_every_folder_has_one():
    from tools.layers import LAYERS, PACKAGES, ROOT, layer_of

    assert [layer.rank for layer in LAYERS] == list(range(len(LAYERS)))
    assert len(set(PACKAGES)) == len(PACKAGES) and all("." not in f for f in PACKAGES)
    packages = {p.parent.name for p in ROOT.glob("*/__init__.py")}
    assert packages == set(PACKAGES)  # a new top-level package must be given its layer
    assert layer_of("app.cli").name == "application"
    with pytest.raises(ValueError, match="belongs to no layer"):
        layer_of("tests.conftest")


def test_the_layout_page_names_every_source_folder():
    """docs/explanation/layout.md is the map a new maintainer reads: a folder missing from
    it is a folder nobody finds."""
    from tools.layers import PACKAGES, ROOT

    page = (ROOT / "docs" / "explanation" / "layout.md").read_text(encoding="utf-8")
    folders = sorted({p.parent.relative_to(ROOT) for package in PACKAGES
                      for p in (ROOT / package).rglob("*.py")})
    missing = [str(f) for f in folders if f"{f.name}/" not in page]
    assert not missing, f"folders the layout page does not name: {missing}"
