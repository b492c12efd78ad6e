"""The Lua API reference (docs/LUA.md, made from services/scripting/api.py's declarations)
lists exactly what the sandbox exposes to a script (issue 34)."""

from __future__ import annotations

import re
from pathlib import Path

from app.reference import documented_lua_api, live_lua_api, lua_markdown

ROOT = Path(__file__).resolve().parents[2]


def test_the_declarations_name_every_function_the_sandbox_exposes_and_no_other() -> None:
    documented, live = documented_lua_api(), live_lua_api()
    for kind in ("globals", "methods", "fields", "input"):
        assert documented[kind] == live[kind], (
            f"{kind}: declared but not in the sandbox: {sorted(documented[kind] - live[kind])}; "
            f"in the sandbox but not declared: {sorted(live[kind] - documented[kind])}")
    # the colosseum table holds the same functions (print is a global only: colosseum.log)
    assert live["colosseum"] == live["globals"] - {"print"}


def test_the_declared_callbacks_are_the_ones_the_engine_calls() -> None:
    called = set()
    for folder in ("engine", "services", "systems"):
        for path in (ROOT / folder).rglob("*.py"):
            called |= set(re.findall(r'"(on[A-Z][A-Za-z]+)"', path.read_text(encoding="utf-8")))
    assert documented_lua_api()["callbacks"] == called


def test_the_page_lists_every_name() -> None:
    page = lua_markdown()
    names = documented_lua_api()
    for name in names["globals"]:
        assert f"`{name}`" in page
    for name in names["methods"]:
        assert f"`obj:{name}`" in page
    for name in names["input"]:
        assert f"`input.{name}`" in page
