"""The manual's "Run content" page names every ``colosseum run`` flag argparse knows, and no
other (issue 20; the table moved there from the README in issue 34)."""

from __future__ import annotations

import re
from pathlib import Path

from app.cli import build_parser

RUNNING = Path(__file__).resolve().parents[2] / "docs" / "howto" / "running.md"


def run_options() -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    run = sub.choices["run"]  # type: ignore[attr-defined]
    return {opt for action in run._actions for opt in action.option_strings
            if opt.startswith("--") and opt != "--help"}


def test_every_run_flag_is_in_the_manuals_table() -> None:
    text = RUNNING.read_text(encoding="utf-8")
    section = text.split("## `colosseum run` flags", 1)[1].split("\n#", 1)[0]
    table = "\n".join(line for line in section.splitlines() if line.startswith("| `"))
    documented = set(re.findall(r"`(--[a-z][a-z-]*)", table))
    assert documented == run_options(), (
        f"missing from docs/howto/running.md: {sorted(run_options() - documented)}; "
        f"not flags: {sorted(documented - run_options())}")
