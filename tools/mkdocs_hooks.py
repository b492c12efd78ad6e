"""MkDocs hooks of the manual (mkdocs.yml ``hooks:``): the build stops when a generated
reference page (the scene keys, the Lua API, the command line, the --stats keys, the GLSL
contract) differs from what the code makes now, so the site never shows a stale one."""

from __future__ import annotations

from typing import Any

from mkdocs.exceptions import PluginError


def on_pre_build(config: Any) -> None:
    from tools.docs import stale_pages

    stale = stale_pages()
    if stale:
        raise PluginError(f"docs/: {', '.join(stale)} differ from the code; "
                          "run .venv/bin/python -m tools.docs")


def on_post_build(config: Any) -> None:
    """The manual's pictures, drawn by the engine now, over the committed copies: the demo
    (README's picture) and the tutorial's grasp, from the tutorial's own commands."""
    from pathlib import Path

    from tools.docs import screenshots

    screenshots(Path(config["site_dir"]) / "images")
