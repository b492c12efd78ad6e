"""``python -m tools.docs``: write the generated pages of docs/ (the GLSL contract, the scene
key reference, the --stats keys and schema); ``--check`` only says which differ. Tests keep
the pages equal to what this writes, so they cannot drift from the code."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path

from engine.render.glsl import contract_markdown
from engine.scene.keys import reference_markdown
from engine.stats import STATS_SCHEMA, stats_markdown

DOCS = Path(__file__).resolve().parent.parent / "docs"

#: page -> the function that makes its text
PAGES: dict[str, Callable[[], str]] = {
    "GLSL.md": contract_markdown,
    "KEYS.md": reference_markdown,
    "STATS.md": stats_markdown,
    "stats.schema.json": lambda: json.dumps(STATS_SCHEMA, indent=2) + "\n",
}


def main(argv: list[str] | None = None) -> int:
    check = "--check" in (sys.argv[1:] if argv is None else argv)
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
