"""The scene target of the fuzzer (``python -m tools.fuzz --kind scene``): generated and
mutated scene text, expressions and includes.

Every input is written as a content folder and goes through what ``colosseum check``
and ``colosseum fmt --write`` do: parse with its includes, validate, build specs,
render the report as text and as JSON, and, when it has no errors, format it, check
the format is stable and reads back to the same scene. Each input must end in a
report, never a traceback, within the fuzzer's time and memory limits
(:mod:`tools.fuzz_core`), and every diagnostic must point inside a file that was read
(``path:line:col``).

The fast path's property test (tests/scene/test_fast_path.py) uses :func:`scene_text`
and :func:`mutate` for its scenes.
"""

from __future__ import annotations

import random
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import engine.scene.expr as ex
import engine.scene.schema as sc
from engine.scene import Report, SceneError, check, format_scene, parse_file
from engine.scene.diagnostics import MAX_PER_FILE
from tools.fuzz_core import Outcome, Target

ROOT = Path(__file__).resolve().parent.parent
#: Share of inputs that are one of the large :data:`HOSTILE` files.
HOSTILE_RATE = 0.002
#: Real files whose text is mutated; assets the fuzz folder holds, so models load.
SEED_FILES = [ROOT / "content/demo/main.scene", *sorted(
    (ROOT / "tests/scene/data").glob("**/*.scene"))]
ASSETS = {"models": ROOT / "tests/scene/data/representative/models",
          "scripts": ROOT / "tests/scene/data/representative/scripts",
          "sounds": ROOT / "tests/scene/data/representative/sounds",
          "shaders": ROOT / "tests/scene/data/paper/shaders"}

# -- text generation -----------------------------------------------------------------

_KEYS = sorted({k for fields in sc.SCHEMAS.values() for k in fields})
_VARIABLES = ["s", "a", "b", "spacing", "height", "x_1"]
_VARIABLES_SET = "".join(f"{v} {i + 1}\n" for i, v in enumerate(_VARIABLES))
_ALIENS = ["Radius", "Scale", "Colour", "Rotation", "Mas", "positon", "Translation", "_x",
           "Q" * 80]
_FUNCTIONS = sorted(ex.FUNCTIONS)
_WORDS = ["sphere", "box", "capsule", "cylinder", "plane", "rubber", "wood", "ball", "door",
          "hinge", "Hinge", "ode", "pymunk", "models/cube.obj", "sounds/knock.wav",
          "scripts/door.lua", "shaders/toon.vert", "key:Up/Down", "motor:hinge", "toon",
          "TriangleMesh", "ConvexHull", "", "a b", "x" * 50]
#: Names an ``Include`` gives: files of the fuzz folder (see :func:`prepare`), and names
#: no file system likes.
INCLUDE_NAMES = ["part.scene", "loop_a.scene", "link_a.scene", "folder.scene", "bad.scene",
                 "main.scene", "missing.scene", "a\x00b.scene", "x" * 300 + ".scene",
                 "../" * 40 + "etc/hostname", "/dev/zero", "/proc/self/cmdline", "", ".",
                 "part.scene/x", "models/cube.obj"]
_KEY_GAPS = [" ", " ", "  ", "\t"]
_SEPARATORS = [" ", " ", "\n", "\n", "\n\n", "\n  ", "\t", "\r\n", " // note\n",
               " /* c */ ", "\n/* two\n\nlines */\n", "\n\n\n"]
#: Bits of text mutations insert: the grammar's lexemes and what has broken parsers.
FRAGMENTS = list('{}[]()",/*+-^ \n\t\u201c\u201d\\.e0123456789aZ_#$@\x00\ufeff\r') + [
    "Object", "ID", "Include", "Size", "//", "/*", "*/", "Geometry", "Primitive", "sphere",
    "1e999", "99999999999999999999", "randInterval(", "Joint", "min(1)", "max(2)",
    "randInt(1e300, 1e301)", "sqrt(-1)", "2^1e10", "0/0", '"a\x00b"', "\u00e9", "\U0001f600",
    "-", "--", "+-", "[1 -2]", "[a*2 -a/2]", "pi", "e", "x" * 200]


def _number(rng: random.Random) -> str:
    kind = rng.randrange(9)
    if kind == 0:
        return str(rng.randrange(1000))
    if kind == 1:
        return repr(rng.uniform(-1e3, 1e3))
    if kind == 2:
        return rng.choice(["1.", ".5", "1e3", "2E-2", "0", "0.0", "1e-300", "4.e5", "007"])
    if kind == 3:
        return str(rng.randrange(10 ** rng.randrange(1, 22)))
    if kind == 4:
        return rng.choice(["1e999", "9223372036854775807", "9223372036854775808", "1e308"])
    return str(rng.randrange(10))


def _string(rng: random.Random) -> str:
    body = rng.choice(_WORDS)
    kind = rng.randrange(12)
    if kind == 0:
        body += '\\"q\\"'
    elif kind == 1:
        body += "\\\\"
    elif kind == 2:
        return f"\u201c{body}\u201d"
    elif kind == 3 and rng.random() < 0.3:
        return f'"{body}'  # not closed
    elif kind == 4:
        body += "\\n"
    return f'"{body}"'


def expression(rng: random.Random, depth: int = 0) -> str:
    """A float expression: numbers, variables, constants, operators, calls of any arity."""
    kind = rng.randrange(10 if depth < 4 else 3)
    if kind == 0:
        return _number(rng)
    if kind == 1:
        return rng.choice(_VARIABLES + ["pi", "e", "unknown" if rng.random() < 0.1 else "pi"])
    if kind == 2:
        return f"{rng.choice(['', '-', '+'])}{_number(rng)}"
    if kind in (3, 4, 5):
        op = rng.choice(["+", "-", "*", "/", "^", " + ", " - ", " * "])
        return f"{expression(rng, depth + 1)}{op}{expression(rng, depth + 1)}"
    if kind == 6:
        return f"({expression(rng, depth + 1)})"
    if kind == 7:
        return f"-{expression(rng, depth + 1)}"
    name = rng.choice(_FUNCTIONS)
    fewest = ex.FUNCTIONS[name][0]
    count = fewest if rng.random() < 0.8 else rng.choice([0, 1, 2, 3, 4])
    return f"{name}({', '.join(expression(rng, depth + 1) for _ in range(count))})"


def _vector(rng: random.Random) -> str:
    kind = rng.randrange(6)
    n = rng.choice([0, 1, 2, 3, 3, 3, 4, 7])
    if kind == 0:
        items = [_string(rng) for _ in range(n)]
    elif kind == 1:
        items = [rng.choice(["a*2", "-a/2", "+a+1", "s-1", "pi", "-e", "spacing*3", "2/a",
                             "a-b", "-0", "q", "1e400*2"]) for _ in range(n)]
    elif kind == 2:
        items = [expression(rng, 2) for _ in range(n)]
    else:
        items = [rng.choice(["", "-", "+"]) + _number(rng) for _ in range(n)]
    sep = rng.choice([" ", " ", " ", "  ", "\t", "\n"])
    return f"[{rng.choice(['', ' '])}{sep.join(items)}{rng.choice(['', ' '])}]"


def _value(rng: random.Random, depth: int) -> str:
    kind = rng.randrange(10)
    if kind < 2:
        return _number(rng)
    if kind < 4:
        return _string(rng)
    if kind < 6:
        return _vector(rng)
    if kind == 6:
        return expression(rng)
    return _block(rng, depth + 1) if depth < 5 else _number(rng)


def _key(rng: random.Random) -> str:
    kind = rng.randrange(12)
    if kind < 7:
        return rng.choice(_KEYS)
    if kind < 10:
        return rng.choice(_VARIABLES)
    if kind == 10:
        return "Include"
    return rng.choice(_ALIENS)


def _entries(rng: random.Random, depth: int, count: int) -> list[str]:
    out = []
    for _ in range(count):
        key = _key(rng)
        value = f'"{rng.choice(INCLUDE_NAMES)}"' if key == "Include" else _value(rng, depth)
        out.append(f"{key}{rng.choice(_KEY_GAPS)}{value}")
    return out


def _block(rng: random.Random, depth: int) -> str:
    entries = _entries(rng, depth, rng.randrange(5))
    if rng.random() < 0.5:
        return "{ " + " ".join(entries) + " }" if entries else "{}"
    pad = "  " * depth
    body = "".join(f"{pad}  {e}{rng.choice(_SEPARATORS) if rng.random() < 0.2 else ''}\n"
                   for e in entries)
    return "{\n" + body + pad + "}"


def scene_text(rng: random.Random) -> str:
    """A scene from the grammar: entries of every kind, blocks on one line or many,
    comments and blank lines between, now and then a BOM or CRLF line ends."""
    entries = _entries(rng, 0, rng.randrange(1, 9))
    parts = [_VARIABLES_SET] if rng.random() < 0.7 else []
    for e in entries:
        parts.append(e)
        parts.append(rng.choice(_SEPARATORS))
    text = "".join(parts)
    if rng.random() < 0.05:
        text = "\ufeff" + text
    if rng.random() < 0.05:
        text = text.replace("\n", "\r\n")
    return text


def mutate(rng: random.Random, text: str, edits: int, fragments: list[str] = FRAGMENTS) -> str:
    """``text`` after ``edits`` random deletions, insertions and replacements (of pieces
    of ``fragments``), and copies."""
    for _ in range(edits):
        i = rng.randrange(len(text) + 1)
        j = min(len(text), i + rng.randrange(13))
        op = rng.randrange(4)
        if op == 0:
            text = text[:i] + text[j:]
        elif op == 1:
            text = text[:i] + rng.choice(fragments) + text[i:]
        elif op == 2:
            text = text[:i] + rng.choice(fragments) + text[j:]
        else:
            text = text[:j] + text[i:j] + text[j:]
    return text


def _seed_text(rng: random.Random) -> str:
    path = rng.choice(SEED_FILES)
    text = path.read_text(encoding="utf-8")
    if len(text) > 1500:  # a window of a long file, from a line start
        start = text.rfind("\n", 0, rng.randrange(len(text) - 1000)) + 1
        text = text[start:start + 1500]
    return text


#: Inputs that broke earlier versions by size: each must give a short report quickly.
HOSTILE: list[Callable[[random.Random], str]] = [
    lambda rng: "\x00" * 1_000_000,
    lambda rng: "@" * 30_000,
    lambda rng: "a $\n" * 100_000,
    lambda rng: "".join(f"Object {{ Qq{i}x 1 }}\n" for i in range(5_000)),
    lambda rng: "".join(f"v{i} 1\n" for i in range(5_000)) + "x u1*2\n" * 5_000,
    lambda rng: rng.choice("{[(") * 100_000,
    lambda rng: "x " + "1+" * 50_000 + "1\n",
    lambda rng: "x " + "-" * 100_000 + "1\n",
    lambda rng: "S " + '"' + "a" * 1_000_000 + '"\nObject { ID 1 Primitive S }\n',
    lambda rng: "".join(f'Object {{ ID "o{i}" PhysicalAttributes {{ Material "m{i}" }} }}\n'
                        for i in range(5_000)),
]


@dataclass(slots=True)
class Input:
    """One fuzz input: the main scene file and the file it may include as ``part.scene``."""

    main: str
    part: str = ""


def make_input(rng: random.Random, hostile_rate: float = HOSTILE_RATE) -> Input:
    """A scene (generated, a real file, an expression list or text soup), mutated or not,
    with an included part; now and then one of :data:`HOSTILE`."""
    if rng.random() < hostile_rate:
        return Input(rng.choice(HOSTILE)(rng))
    kind = rng.randrange(10)
    if kind < 4:
        main = scene_text(rng)
    elif kind < 7:
        main = _seed_text(rng)
    elif kind == 7:
        main = "".join(f"{rng.choice(_VARIABLES)} {expression(rng)}\n"
                       for _ in range(rng.randrange(1, 6)))
    elif kind == 8:
        main = " ".join(rng.choice(FRAGMENTS + _KEYS) for _ in range(rng.randrange(60)))
    else:
        main = "".join(chr(rng.choice([rng.randrange(32, 127), rng.randrange(0x10000)]))
                       for _ in range(rng.randrange(200)))
    if rng.random() < 0.6:
        main = mutate(rng, main, rng.randrange(1, 7))
    part = scene_text(rng) if rng.random() < 0.5 else ""
    return Input(_no_surrogates(main), _no_surrogates(part))


def _no_surrogates(text: str) -> str:
    """Text a file can hold (lone surrogates cannot be written as UTF-8)."""
    return text.encode("utf-8", "replace").decode("utf-8")


# -- running an input --------------------------------------------------------------


class BadReport(AssertionError):
    """A report that points outside the files read, or a format that does not hold."""


def prepare(folder: Path) -> Path:
    """The fuzz content folder: assets, and the files :data:`INCLUDE_NAMES` name."""
    for name, source in ASSETS.items():
        if source.is_dir():
            shutil.copytree(source, folder / name, dirs_exist_ok=True)
    (folder / "loop_a.scene").write_text('Include "loop_b.scene"\nk 1\n')
    (folder / "loop_b.scene").write_text('Include "loop_a.scene"\n')
    for a, b in (("link_a.scene", "link_b.scene"), ("link_b.scene", "link_a.scene")):
        (folder / a).unlink(missing_ok=True)
        (folder / a).symlink_to(folder / b)
    (folder / "folder.scene").mkdir(exist_ok=True)
    (folder / "bad.scene").write_bytes(b"k 1\nObject { ID \"\xff\xfe\" }\n\xc3(")
    return folder


def exercise(inp: Input, folder: Path) -> Outcome:
    """Run one input through check and fmt: "formatted" when it parsed, else "message"
    (its report)."""
    main = folder / "main.scene"
    main.write_text(inp.main, encoding="utf-8")
    (folder / "part.scene").write_text(inp.part, encoding="utf-8")
    report = check(folder)
    _check_places(report)
    report.render()
    report.to_json()
    try:
        before = parse_file(main)
    except SceneError:
        return "message"
    formatted = format_scene(folder)
    main.write_text(formatted, encoding="utf-8")
    if format_scene(folder) != formatted:
        raise BadReport("fmt is not stable: formatting its output changes it")
    if parse_file(main) != before:
        raise BadReport("fmt changed the scene: its output reads differently")
    return "formatted"


def _check_places(report: Report) -> None:
    per_file: dict[str, int] = {}
    lines_of: dict[str, list[str]] = {}
    for d in report.diagnostics:
        per_file[d.path] = per_file.get(d.path, 0) + 1
        if d.path not in report.sources:
            raise BadReport(f"diagnostic in a file that was not read: {d.head()}")
        lines = lines_of.get(d.path)
        if lines is None:
            lines = lines_of[d.path] = report.sources[d.path].split("\n")
        if not (1 <= d.line <= len(lines) and 1 <= d.col <= len(lines[d.line - 1]) + 1):
            raise BadReport(f"diagnostic outside its file: {d.head()}")
    if any(n > MAX_PER_FILE + 1 for n in per_file.values()):
        raise BadReport(f"more than {MAX_PER_FILE} diagnostics shown for one file")


def _files(inp: Input, stem: str) -> dict[str, str]:
    return {f"{stem}.scene": inp.main, **({f"{stem}.part.scene": inp.part} if inp.part else {})}


#: The scene target of :mod:`tools.fuzz`.
TARGET = Target("scene", make_input, exercise, _files, prepare)
