"""The reference pages made from the code itself: the CLI (from the argparse parser) and the
Lua API (from the declarations in :mod:`services.scripting.api`'s docstring, with the
standard library the sandbox keeps read from a live sandbox). ``python -m tools.docs``
writes them into docs/ beside the others; tests keep them equal to what this makes."""

from __future__ import annotations

import argparse
import re
from typing import Any

# -- the command line ------------------------------------------------------------------------


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def _help_of(parser: argparse.ArgumentParser, name: str) -> str:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return next((c.help or "" for c in action._choices_actions if c.dest == name), "")


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _argument_rows(parser: argparse.ArgumentParser) -> list[str]:
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        if action.option_strings:
            meta = ""
            if action.nargs != 0:
                meta = " " + (action.metavar or ("{" + ",".join(map(str, action.choices)) + "}"
                                                 if action.choices else action.dest.upper()))
            name = ", ".join(f"`{o}{meta}`" for o in action.option_strings)
        else:
            name = f"`{action.metavar or action.dest}`"
        helptext = action.help or ""
        if "%(default)" in helptext:
            helptext = helptext % {"default": action.default}
        extra = []
        if action.choices and action.option_strings:
            extra.append("one of " + ", ".join(f"`{c}`" for c in action.choices))
        if action.nargs == "?" and not action.option_strings:
            extra.append("optional")
        if action.required and action.option_strings:
            extra.append("required")
        if isinstance(action, argparse._AppendAction) and "repeatable" not in helptext:
            extra.append("repeatable")
        default = action.default
        if default not in (None, False, [], argparse.SUPPRESS) and action.nargs != 0 \
                and "default" not in helptext:
            extra.append(f"default `{default}`")
        text = _cell(helptext) + (f" ({'; '.join(extra)})" if extra else "")
        rows.append(f"| {name} | {text} |")
    return rows


def cli_markdown() -> str:
    """Every ``colosseum`` command and its arguments, from :func:`app.cli.build_parser`."""
    from app.cli import build_parser

    parser = build_parser()
    about = (parser.description or "").removeprefix("colosseum: ").rstrip(".")
    out = ["# Command line", "",
           "<!-- Generated from app/cli.py's argument parser by `python -m tools.docs`; "
           "do not edit. -->", "",
           f"`colosseum [--log-level LEVEL] COMMAND ...`: {about}.", "",
           "Exit codes: 0 success, 1 errors in the content or a failing system, 2 usage "
           "errors (unknown flags, missing paths). `colosseum COMMAND --help` prints the "
           "same as this page in a terminal.", "",
           "| global option | meaning |", "|---|---|",
           *[row for row in _argument_rows(parser) if "COMMAND" not in row
             and "`command`" not in row], ""]
    for name, sub in _subparsers(parser).items():
        about = _cell(_help_of(parser, name))
        out += [f"## {name}", "", about[:1].upper() + about[1:] + ".", "",
                "```", " ".join(sub.format_usage().split()).replace("usage: ", ""), "```", "",
                "| argument | meaning |", "|---|---|", *_argument_rows(sub), ""]
        if sub.epilog:
            out += [_cell(sub.epilog) + ".", ""]
    return "\n".join(out).rstrip() + "\n"


# -- the Lua API -----------------------------------------------------------------------------

#: a method call on a handle: obj:getPosition(, hand:grasp(, avatar:play(, avatar:blend{
_METHOD = re.compile(r"\b(?:obj|hand|avatar):([A-Za-z_]\w*)\s*[({]")
#: a field read on a handle: obj.id, hand.state, hand.held
_FIELD = re.compile(r"\b(?:obj|hand)\.([A-Za-z_]\w*)")
#: input.tracker(...)
_INPUT = re.compile(r"\binput\.([A-Za-z_]\w*)\s*\(")
#: a name called at the top level of a declaration: find(, every(, createJoint{
_CALL = re.compile(r"(?<![\w.:])([a-z][A-Za-z]*)[({]")
#: a callback a script defines: ``onStart()``
_CALLBACK = re.compile(r"``(on[A-Z]\w*)\(")


def _top_level_calls(text: str) -> set[str]:
    """Names called outside any bracket: ``after(sec, fn)`` names ``after``, not ``fn``."""
    names, depth, at = set(), 0, 0
    for match in _CALL.finditer(text):
        for ch in text[at:match.start()]:
            depth += (ch in "({[") - (ch in ")}]")
        at = match.start()
        if depth == 0:
            names.add(match.group(1))
    return names


def _declaration_blocks(doc: str) -> dict[str, str]:
    """The docstring's ``Title::`` literal blocks by title."""
    blocks: dict[str, str] = {}
    lines = doc.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.endswith("::") and line.strip() != "::":
            title = line[:-2].strip()
            body = []
            i += 1
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith("    ")):
                body.append(lines[i][4:])
                i += 1
            blocks[title] = "\n".join(body).strip("\n")
            continue
        i += 1
    return blocks


def documented_lua_api() -> dict[str, set[str]]:
    """The names :mod:`services.scripting.api` declares: ``globals`` (also fields of the
    ``colosseum`` table), ``methods`` (on object, hand and avatar handles), ``fields``
    (read on a handle), ``input`` (the ``input`` table's functions) and ``callbacks``."""
    from services.scripting import api

    doc = api.__doc__ or ""
    blocks = _declaration_blocks(doc)
    handles = blocks["Objects (``obj:method(...)``)"] + "\n" + \
        blocks["Avatars (``Avatar`` blocks; the avatars plugin)"]
    scene = blocks["Scene and engine"]
    names = _top_level_calls(scene)
    names |= set(re.findall(r"``(\w+)``", scene))  # the paper's ``requrestPlugin``
    return {
        "globals": names,
        "methods": set(_METHOD.findall(handles)),
        "fields": set(_FIELD.findall(handles)),
        "input": set(_INPUT.findall(blocks["Input state, any time (nil before a device has "
                                          "said anything)"])),
        "callbacks": set(_CALLBACK.findall(doc)),
    }


def live_lua_api() -> dict[str, Any]:
    """What a script's environment really holds, read from a fresh sandbox with the
    scripting API installed: the engine's globals, the handle methods and fields, the
    ``input`` functions, and the standard Lua the sandbox keeps (base functions, and each
    library with its functions)."""
    from services.scripting.api import ScriptAPI
    from services.scripting.runtime import ScriptRuntime

    api = ScriptAPI.__new__(ScriptAPI)  # install() needs only bound methods, no engine
    runtime = ScriptRuntime(api=api.install)
    env = runtime._make_globals(0, None)
    k = runtime.kernel
    keys = runtime.lua.eval("function(t) local out = {} for key in pairs(t) do "
                            "out[#out + 1] = key end return out end")
    names = set(keys(env).values())
    libraries = {"string", "table", "math", "utf8", "coroutine", "os"}
    standard = {"load", "require", "_G"}
    engine_globals = names - libraries - standard - {"self", "colosseum", "input"}
    return {
        "globals": engine_globals,
        "colosseum": set(keys(env.colosseum).values()) - {"input"},
        "methods": set(keys(k.Object).values()),
        "fields": set(keys(k.Fields).values()) | {"id"},
        "input": set(keys(env.input).values()),
        "base": sorted(set(keys(k.SAFE).values()) | (standard - {"_G"})),
        "libraries": {lib: sorted(keys(env[lib]).values()) for lib in sorted(libraries)},
    }


def _rst_to_markdown(text: str) -> str:
    text = re.sub(r":(?:mod|func|class|data|meth):`~?([^`]+)`", r"`\1`", text)
    return text.replace("``", "`")


def lua_markdown() -> str:
    """The Lua API page: the declarations of :mod:`services.scripting.api` as they are
    written there, then every name in one list, then the standard Lua a script has."""
    from services.scripting import api

    doc = api.__doc__ or ""
    out = ["# Lua API", "",
           "<!-- Generated from services/scripting/api.py (its declarations) and a live "
           "sandbox (the standard library) by `python -m tools.docs`; do not edit. -->", ""]
    lines = doc.splitlines()
    i = 0
    prose: list[str] = []
    while i < len(lines):
        line = lines[i]
        if line.endswith("::") and line.strip() != "::":
            prose.append(_rst_to_markdown(line[:-2].rstrip()) + ":")
            out += [" ".join(prose).strip(), ""] if prose else []
            prose = []
            body = []
            i += 1
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith("    ")):
                body.append(lines[i][4:])
                i += 1
            out += ["```lua", "\n".join(body).strip("\n"), "```", ""]
            continue
        if not line.strip():
            if prose:
                out += [_rst_to_markdown(" ".join(prose).strip()), ""]
                prose = []
        else:
            prose.append(line.strip())
        i += 1
    if prose:
        out += [_rst_to_markdown(" ".join(prose).strip()), ""]
    names = documented_lua_api()
    out += ["## Every name", "",
            "Globals (each also a field of the `colosseum` table): "
            + ", ".join(f"`{n}`" for n in sorted(names["globals"], key=str.lower)) + ".", "",
            "Methods of object, hand and avatar handles: "
            + ", ".join(f"`obj:{n}`" for n in sorted(names["methods"], key=str.lower)) + ".",
            "",
            "Fields of handles: " + ", ".join(f"`obj.{n}`" for n in sorted(names["fields"]))
            + ".", "",
            "The `input` table: " + ", ".join(f"`input.{n}`" for n in sorted(names["input"]))
            + ".", "",
            "Callbacks a script may define: "
            + ", ".join(f"`{n}`" for n in sorted(names["callbacks"])) + ".", "",
            "## Standard Lua in the sandbox", "",
            "Lua 5.4 with no files, no OS and no debug library. What a script has of the "
            "standard library (read from a live sandbox):", ""]
    live = live_lua_api()
    out += ["- base: " + ", ".join(f"`{n}`" for n in live["base"])]
    for lib, fns in live["libraries"].items():
        out += [f"- `{lib}`: " + ", ".join(f"`{n}`" for n in fns)]
    return "\n".join(out).rstrip() + "\n"
