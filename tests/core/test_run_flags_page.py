"""The README names every ``colosseum run`` flag argparse knows, and no other (issue 20)."""

from __future__ import annotations

import re
from pathlib import Path

from engine.cli import build_parser

README = Path(__file__).resolve().parents[2] / "README.md"


def run_options() -> set[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    run = sub.choices["run"]  # type: ignore[attr-defined]
    return {opt for action in run._actions for opt in action.option_strings
            if opt.startswith("--") and opt != "--help"}


def test_every_run_flag_is_in_the_readme_table() -> None:
    text = README.read_text(encoding="utf-8")
    section = text.split("### `colosseum run` flags", 1)[1].split("\n#", 1)[0]
    table = "\n".join(line for line in section.splitlines() if line.startswith("| `"))
    documented = set(re.findall(r"`(--[a-z][a-z-]*)", table))
    assert documented == run_options(), (
        f"missing from the README: {sorted(run_options() - documented)}; "
        f"not flags: {sorted(documented - run_options())}")
