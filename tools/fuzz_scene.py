"""Fuzz the scene format: generated and mutated scene text, expressions and includes.

Every input is written as a content folder and goes through what ``colosseum check``
and ``colosseum fmt --write`` do: parse with its includes, validate, build specs,
render the report as text and as JSON, and, when it has no errors, format it, check
the format is stable and reads back to the same scene. Each input must end in a
report, never a traceback, within :data:`TIME_LIMIT_S` seconds and
:data:`MEMORY_LIMIT` bytes of new memory, and every diagnostic must point inside a
file that was read (``path:line:col``). A failing input is shrunk (chunks removed
while it still fails the same way) and written out as a reproducer.

Hypothesis drives the run: each example is a seed from which one input is made
with a seeded ``random.Random`` (cheap enough for 100,000 inputs in well under an
hour on two cores), and batches of examples are seeded in turn, so a run is
reproducible from ``--seed``::

    .venv/bin/python -m tools.fuzz_scene --seconds 3600          # an hour
    .venv/bin/python -m tools.fuzz_scene --seed 3 --inputs 100000

The test suite runs a short fixed-seed run (tests/scene/test_fuzz.py); the fast
path's property test (tests/scene/test_fast_path.py) uses :func:`scene_text` and
:func:`mutate` for its scenes.
"""

from __future__ import annotations

import argparse
import random
import resource
import shutil
import signal
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import FrameType

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import seed as hypothesis_seed
from hypothesis import strategies as st

import engine.scene.expr as ex
import engine.scene.schema as sc
from engine.scene import Report, SceneError, check, format_scene, parse_file
from engine.scene.diagnostics import MAX_PER_FILE

ROOT = Path(__file__).resolve().parent.parent
TIME_LIMIT_S = 10.0
MEMORY_LIMIT = 1 << 30
#: Hypothesis examples per seeded batch (a run stops between batches when time is up).
BATCH = 100
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
#: Names an ``Include`` gives: files of the fuzz folder (see :func:`_prepare`), and names
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


def mutate(rng: random.Random, text: str, edits: int) -> str:
    """``text`` after ``edits`` random deletions, insertions, replacements and copies."""
    for _ in range(edits):
        i = rng.randrange(len(text) + 1)
        j = min(len(text), i + rng.randrange(13))
        op = rng.randrange(4)
        if op == 0:
            text = text[:i] + text[j:]
        elif op == 1:
            text = text[:i] + rng.choice(FRAGMENTS) + text[i:]
        elif op == 2:
            text = text[:i] + rng.choice(FRAGMENTS) + text[j:]
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


def make_input(rng: random.Random, hostile_rate: float = 0.002) -> Input:
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


class Hang(Exception):
    """An input ran past :data:`TIME_LIMIT_S`."""


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


def exercise(inp: Input, folder: Path) -> tuple[int, bool]:
    """Run one input through check and fmt; returns the diagnostics found and whether it
    parsed (and so was formatted)."""
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
        return len(report), False
    formatted = format_scene(folder)
    main.write_text(formatted, encoding="utf-8")
    if format_scene(folder) != formatted:
        raise BadReport("fmt is not stable: formatting its output changes it")
    if parse_file(main) != before:
        raise BadReport("fmt changed the scene: its output reads differently")
    return len(report), True


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


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raise :class:`Hang` in the main thread if the block runs past ``seconds``."""

    def expired(signum: int, frame: FrameType | None) -> None:
        raise Hang(f"no result within {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _data_in_use() -> int:
    """Bytes of this process's data segment now (VmData)."""
    with open("/proc/self/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("VmData:"):
                return int(line.split()[1]) * 1024
    return 0


@contextmanager
def memory_limit(extra: int) -> Iterator[None]:
    """Cap new memory (RLIMIT_DATA) at ``extra`` bytes over what is in use now: past it
    an input gets a MemoryError, which counts as a failure."""
    soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
    cap = _data_in_use() + extra
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_DATA, (cap, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_DATA, (soft, hard))


def fails_like(folder: Path, kind: type[BaseException]) -> Callable[[Input], bool]:
    """Whether an input still fails in ``folder`` with an exception of ``kind``."""

    def fails(inp: Input) -> bool:
        try:
            with time_limit(TIME_LIMIT_S):
                exercise(inp, folder)
        except kind:
            return True
        except Exception:
            return False
        return False

    return fails


def shrink(inp: Input, fails: Callable[[Input], bool], budget_s: float = 120.0) -> Input:
    """A smaller input that still ``fails``: chunks of each file removed, halving the
    chunk size down to one character, while it does."""
    stop = time.monotonic() + budget_s
    for name in ("main", "part"):
        text = getattr(inp, name)
        size = max(len(text) // 2, 1)
        while time.monotonic() < stop:
            i = 0
            while i < len(text) and time.monotonic() < stop:
                candidate = replace(inp, **{name: text[:i] + text[i + size:]})
                if fails(candidate):
                    inp, text = candidate, getattr(candidate, name)
                else:
                    i += size
            if size == 1:
                break
            size //= 2
    return inp


# -- the run -------------------------------------------------------------------------


@dataclass(slots=True)
class Result:
    """What a run did: inputs run, how many parsed (and went through fmt), the
    diagnostics reported, the slowest input, and the first failure if any."""

    inputs: int = 0
    formatted: int = 0
    diagnostics: int = 0
    slowest_s: float = 0.0
    seconds: float = 0.0
    failure: str | None = None
    reproducer: list[Path] = field(default_factory=list)


class _Failed(Exception):
    """Stops hypothesis at the first failing input (already shrunk and written out)."""


def run(seconds: float, seed: int = 0, max_inputs: int | None = None,
        hostile_rate: float = 0.002, out_dir: Path | None = None,
        progress: Callable[[Result], None] | None = None) -> Result:
    """Fuzz for ``seconds`` (or ``max_inputs`` inputs); stops at the first failure."""
    result = Result()
    start = time.monotonic()
    deadline = start + seconds
    with tempfile.TemporaryDirectory(prefix="fuzz_scene.") as tmp, memory_limit(MEMORY_LIMIT):
        folder = prepare(Path(tmp))
        batch = 0
        while time.monotonic() < deadline and result.failure is None and (
                max_inputs is None or result.inputs < max_inputs):
            examples = BATCH if max_inputs is None else min(BATCH, max_inputs - result.inputs)
            try:
                _batch(seed, batch, examples, deadline, folder, hostile_rate, result, out_dir)
            except _Failed:
                break
            batch += 1
            if progress is not None:
                result.seconds = time.monotonic() - start
                progress(result)
    result.seconds = time.monotonic() - start
    return result


def _batch(seed: int, batch: int, examples: int, deadline: float, folder: Path,
           hostile_rate: float, result: Result, out_dir: Path | None) -> None:
    @hypothesis_seed(seed * 1_000_003 + batch)
    @settings(max_examples=examples, database=None, deadline=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(st.integers(0, 2**63 - 1))
    def one(example: int) -> None:
        if time.monotonic() >= deadline:
            return
        inp = make_input(random.Random(f"{seed}/{batch}/{example}"), hostile_rate)
        t0 = time.perf_counter()
        try:
            with time_limit(TIME_LIMIT_S):
                found, parsed = exercise(inp, folder)
        except Exception as exc:
            result.failure = "".join(traceback.format_exception(exc))
            small = shrink(inp, fails_like(folder, type(exc)))
            result.reproducer = _write_reproducer(small, out_dir or Path.cwd(), example)
            raise _Failed from exc
        result.slowest_s = max(result.slowest_s, time.perf_counter() - t0)
        result.inputs += 1
        result.formatted += parsed
        result.diagnostics += found

    one()


def _write_reproducer(inp: Input, out_dir: Path, example: int) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    main = out_dir / f"fuzz-failure-{example}.scene"
    main.write_text(inp.main, encoding="utf-8")
    paths = [main]
    if inp.part:
        part = out_dir / f"fuzz-failure-{example}.part.scene"
        part.write_text(inp.part, encoding="utf-8")
        paths.append(part)
    return paths


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="how long to run")
    parser.add_argument("--inputs", type=int, default=None, help="stop after this many")
    parser.add_argument("--seed", type=int, default=0, help="seed of the whole run")
    parser.add_argument("--hostile-rate", type=float, default=0.002,
                        help="share of inputs that are large hostile files")
    parser.add_argument("--out", type=Path, default=Path.cwd(),
                        help="folder for a failing input's reproducer")
    args = parser.parse_args(argv)

    shown = [0.0]

    def progress(r: Result) -> None:
        if r.seconds - shown[0] >= 10:
            shown[0] = r.seconds
            print(f"{r.inputs} inputs, {r.seconds:.0f} s, slowest {r.slowest_s:.2f} s",
                  file=sys.stderr, flush=True)

    result = run(args.seconds if args.inputs is None else float("inf"), args.seed,
                 args.inputs, args.hostile_rate, args.out, progress)
    print(f"{result.inputs} inputs in {result.seconds:.0f} s (seed {args.seed}): "
          f"{'FAILED' if result.failure else 'no tracebacks, no hangs'}; slowest input "
          f"{result.slowest_s:.2f} s; {result.formatted} parsed and were formatted; "
          f"{result.diagnostics} diagnostics reported")
    if result.failure:
        print(result.failure, file=sys.stderr)
        print("reproducer: " + ", ".join(map(str, result.reproducer)), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
