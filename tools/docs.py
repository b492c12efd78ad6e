"""``python -m tools.docs``: write the generated pages of docs/ (the GLSL contract, the scene
key reference, the --stats keys and schema, the command line, the Lua API); ``--check``
only says which differ; ``--figures`` draws every figure of docs/figures/ again from the
benchmark JSON committed beside it (``colosseum bench WHAT --json docs/figures/NAME.json``).
Tests and the manual's build (tools/mkdocs_hooks.py) keep the pages equal to what this
writes, so they cannot drift from the code."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from app.reference import cli_markdown, lua_markdown
from engine.scene.keys import reference_markdown
from engine.stats import STATS_SCHEMA, stats_markdown
from services.render.glsl import contract_markdown

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"

#: page -> the function that makes its text
PAGES: dict[str, Callable[[], str]] = {
    "GLSL.md": contract_markdown,
    "KEYS.md": reference_markdown,
    "STATS.md": stats_markdown,
    "stats.schema.json": lambda: json.dumps(STATS_SCHEMA, indent=2) + "\n",
    "CLI.md": cli_markdown,
    "LUA.md": lua_markdown,
}


def manual_pages() -> set[str]:
    """The pages of the manual's navigation (mkdocs.yml), as paths relative to docs/."""
    import yaml

    config = yaml.safe_load((DOCS.parent / "mkdocs.yml").read_text(encoding="utf-8"))
    pages: set[str] = set()

    def walk(node: object) -> None:
        if isinstance(node, str):
            pages.add(node)
        elif isinstance(node, list):
            for item in node:
                walk(item)
        elif isinstance(node, dict):
            for item in node.values():
                walk(item)

    walk(config["nav"])
    return pages


def stale_pages() -> list[str]:
    """The generated pages whose text in docs/ differs from what the code makes now."""
    return [name for name, make in PAGES.items()
            if not (DOCS / name).is_file()
            or (DOCS / name).read_text(encoding="utf-8") != make()]


FIGURES = DOCS / "figures"


def plot_figures() -> list[Path]:
    """Each docs/figures/NAME.json (a benchmark's --json, with its date and machine) drawn
    into NAME.png beside it, as ``colosseum bench --plot`` draws it."""
    from app.bench import plot

    return [plot(json.loads(source.read_text(encoding="utf-8")), source.with_suffix(".png"))
            for source in sorted(FIGURES.glob("*.json"))]


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if "--figures" in args:
        for figure in plot_figures():
            print(f"{figure.relative_to(DOCS.parent)} drawn from {figure.stem}.json")
        return 0
    check = "--check" in args
    stale = []
    for name, make in PAGES.items():
        path, text = DOCS / name, make()
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            stale.append(name)
            if not check:
                path.write_text(text, encoding="utf-8")
    verb = "differ from the code" if check else "written"
    print(f"docs/: {', '.join(stale) or 'none'} {verb}")
    return 1 if check and stale else 0


if __name__ == "__main__":
    sys.exit(main())


TUTORIAL = ROOT / "docs" / "getting-started" / "tutorial.md"


def shell_blocks(markdown: str) -> list[str]:
    """A page's ``sh`` code blocks, as written."""
    import re

    return re.findall(r"^```sh\n(.*?)^```$", markdown, flags=re.S | re.M)


def run_tutorial(folder: Path, timeout: float = 240.0) -> subprocess.CompletedProcess[str]:
    """Every ``sh`` block of the tutorial, in order, in one shell in ``folder`` (empty),
    with this Python's bin folder on PATH and no display (as CI runs it)."""
    import os

    script = "set -euo pipefail\n" + "\n".join(shell_blocks(TUTORIAL.read_text("utf-8")))
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
           f"{os.environ.get('PATH', '')}"}
    env.pop("DISPLAY", None)
    return subprocess.run(["bash", "-c", script], cwd=folder, env=env, capture_output=True,
                          text=True, timeout=timeout)


def screenshots(images: Path) -> None:
    """Draw the manual's pictures into ``images`` with the engine: the demo, and the
    tutorial's grasp (its commands run in a scratch folder). Raises RuntimeError when a
    run fails, so a build never shows a picture the engine no longer draws."""
    import shutil
    import tempfile

    images.mkdir(parents=True, exist_ok=True)
    demo = subprocess.run([sys.executable, "-m", "app.cli", "run", str(ROOT / "content" /
                           "demo"), "--headless", "--seconds", "2", "--screenshot",
                           str(images / "demo.png")], capture_output=True, text=True,
                          timeout=120)
    if demo.returncode != 0:
        raise RuntimeError(f"the demo's screenshot failed:\n{demo.stderr[-2000:]}")
    with tempfile.TemporaryDirectory() as scratch:
        result = run_tutorial(Path(scratch))
        if result.returncode != 0:
            raise RuntimeError(f"the tutorial failed:\n{(result.stdout + result.stderr)[-2000:]}")
        shutil.copyfile(Path(scratch) / "grasp.png", images / "tutorial-grasp.png")
