"""The fuzzing machinery every target shares: seeded inputs driven by hypothesis, time and
memory limits, shrinking and reproducers (``python -m tools.fuzz`` runs the targets).

A :class:`Target` is one kind of author input: ``make`` builds one input from a seeded
``random.Random`` (cheap, so a run reaches 100,000 inputs), ``exercise`` runs it through
the engine exactly as a run or a command would and says how it ended (an
:data:`Outcome`: success or a message the author is shown). Anything else it raises is a
failure: a traceback that would reach the author, an input past :data:`TIME_LIMIT_S`
(:class:`Hang`) or one needing more than :data:`MEMORY_LIMIT` bytes of new memory. A
failing input is shrunk (chunks of each of its text or byte fields removed while it
still fails the same way) and written out as a reproducer.
"""

from __future__ import annotations

import contextlib
import io
import logging
import random
import resource
import signal
import time
import traceback
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import FrameType
from typing import Any

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import seed as hypothesis_seed
from hypothesis import strategies as st
from hypothesis.errors import FlakyFailure

TIME_LIMIT_S = 10.0
MEMORY_LIMIT = 1 << 30
#: Hypothesis examples per seeded batch (a run stops between batches when time is up).
BATCH = 100
#: How an input ended: "ok" (read, loaded or run) or "message" (the author is told why
#: not); a target may use finer names, all of them endings an author sees as text.
Outcome = str


@dataclass(frozen=True, slots=True)
class Target:
    """One kind of input: how to make one, how to run one, and how to write one out.

    ``prepare`` fills the run's scratch folder once (seed files, assets); ``exercise``
    runs an input in that folder; ``files`` names the files of a reproducer (``stem`` is
    its name without extension)."""

    name: str
    make: Callable[[random.Random], Any]
    exercise: Callable[[Any, Path], Outcome]
    files: Callable[[Any, str], dict[str, str | bytes]]
    prepare: Callable[[Path], object] | None = None


class Hang(Exception):
    """An input ran past :data:`TIME_LIMIT_S`."""


class TooMuchMemory(Exception):
    """An input made the process's peak memory grow past :data:`MEMORY_LIMIT`."""


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


def peak_rss() -> int:
    """The process's peak resident memory so far, bytes."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


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


@contextmanager
def quiet() -> Iterator[None]:
    """What the engine tells the author (log records, stderr, warnings) kept off the
    fuzzer's terminal: those are the messages an input is allowed to end in."""
    sink = io.StringIO()
    logging.disable(logging.CRITICAL)
    try:
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        logging.disable(logging.NOTSET)


def fails_like(target: Target, folder: Path, kind: type[BaseException]
               ) -> Callable[[Any], bool]:
    """Whether an input of ``target`` still fails in ``folder`` with a ``kind`` error."""

    def fails(inp: Any) -> bool:
        try:
            with time_limit(TIME_LIMIT_S), quiet():
                target.exercise(inp, folder)
        except kind:
            return True
        except Exception:
            return False
        return False

    return fails


def shrink(inp: Any, fails: Callable[[Any], bool], budget_s: float = 120.0) -> Any:
    """A smaller input that still ``fails``: chunks of each text or bytes field (but those
    marked ``field(metadata={"keep": True})``) removed, halving the chunk size down to one
    character, while it does."""
    stop = time.monotonic() + budget_s
    for f in fields(inp):
        data = getattr(inp, f.name)
        if not isinstance(data, (str, bytes)) or f.metadata.get("keep"):
            continue
        size = max(len(data) // 2, 1)
        while time.monotonic() < stop:
            i = 0
            while i < len(data) and time.monotonic() < stop:
                candidate = replace(inp, **{f.name: data[:i] + data[i + size:]})
                if fails(candidate):
                    inp, data = candidate, getattr(candidate, f.name)
                else:
                    i += size
            if size == 1:
                break
            size //= 2
    return inp


# -- byte mutations ----------------------------------------------------------------

#: Bytes that have broken binary parsers: boundaries of integer fields, magic numbers.
BYTE_FRAGMENTS = [b"\x00", b"\xff", b"\x00\x00\x00\x00", b"\xff\xff\xff\xff", b"\x7f\xff\xff\xff",
                  b"\x80\x00\x00\x00", b"\xff\xff", b"\x00\x80", b"\x01", b"\x10\x00",
                  b"nan", b"inf", b"-1", b"1e999", b"\n", b"\r\n", b" ", b"{", b"}", b"[",
                  b"]", b'"', b"\xc3(", b"\xef\xbb\xbf", b"RIFF", b"\x89PNG", b"glTF"]


def mutate_bytes(rng: random.Random, data: bytes, edits: int) -> bytes:
    """``data`` after ``edits`` deletions, insertions, overwrites, copies, bit flips and
    truncations (the mutations that break length fields and checksums)."""
    for _ in range(edits):
        i = rng.randrange(len(data) + 1)
        j = min(len(data), i + rng.randrange(1, 17))
        op = rng.randrange(7)
        if op == 0:
            data = data[:i] + data[j:]
        elif op == 1:
            data = data[:i] + rng.choice(BYTE_FRAGMENTS) + data[i:]
        elif op == 2:
            piece = rng.choice(BYTE_FRAGMENTS)
            data = data[:i] + piece + data[i + len(piece):]
        elif op == 3:
            data = data[:j] + data[i:j] * rng.choice([1, 2, 100]) + data[j:]
        elif op == 4 and i < len(data):
            data = data[:i] + bytes([data[i] ^ (1 << rng.randrange(8))]) + data[i + 1:]
        elif op == 5:
            data = data[:i]
        else:
            data = data[:i] + bytes(rng.randrange(256) for _ in range(j - i)) + data[j:]
    return data


# -- the run -----------------------------------------------------------------------


@dataclass(slots=True)
class KindResult:
    """One target's share of a run: inputs, how they ended, the slowest."""

    inputs: int = 0
    outcomes: Counter[str] = field(default_factory=Counter)
    slowest_s: float = 0.0


@dataclass(slots=True)
class Result:
    """What a run did: per target, its inputs and their endings; the peak memory of the
    process; the first failure if any, with its reproducer."""

    kinds: dict[str, KindResult] = field(default_factory=dict)
    seconds: float = 0.0
    peak_rss: int = 0
    failure: str | None = None
    failed_kind: str | None = None
    reproducer: list[Path] = field(default_factory=list)

    @property
    def inputs(self) -> int:
        return sum(k.inputs for k in self.kinds.values())

    @property
    def slowest_s(self) -> float:
        return max((k.slowest_s for k in self.kinds.values()), default=0.0)


class _Failed(Exception):
    """Stops hypothesis at the first failing input (already shrunk and written out)."""


def run(targets: list[Target], seconds: float, seed: int = 0, max_inputs: int | None = None,
        out_dir: Path | None = None, progress: Callable[[Result], None] | None = None,
        scratch: Path | None = None) -> Result:
    """Fuzz ``targets`` in turn, a batch each, for ``seconds`` (or until ``max_inputs``
    inputs, shared evenly); stops at the first failure. Each target gets its own folder
    under ``scratch`` (a temporary one by default)."""
    import tempfile

    result = Result(kinds={t.name: KindResult() for t in targets})
    start = time.monotonic()
    deadline = start + seconds
    share = None if max_inputs is None else -(-max_inputs // len(targets))
    with tempfile.TemporaryDirectory(prefix="fuzz.", dir=scratch) as tmp:
        folders = {}
        for target in targets:
            folders[target.name] = Path(tmp) / target.name
            folders[target.name].mkdir()
            if target.prepare is not None:
                target.prepare(folders[target.name])
        baseline = peak_rss()
        with memory_limit(MEMORY_LIMIT):
            batch = 0
            while time.monotonic() < deadline and result.failure is None:
                left = [t for t in targets if share is None or result.kinds[t.name].inputs < share]
                if not left:
                    break
                for target in left:
                    done = result.kinds[target.name].inputs
                    examples = BATCH if share is None else min(BATCH, share - done)
                    try:
                        _batch(target, seed, batch, examples, deadline, folders[target.name],
                               baseline, result, out_dir)
                    except _Failed:
                        break
                    except FlakyFailure:  # hypothesis retried the input and it passed
                        result.failure = (result.failure or "") + (
                            "(it did not fail again when retried: a time limit missed on a "
                            "loaded machine, or state one input left for the next)\n")
                        break
                    if time.monotonic() >= deadline:
                        break
                batch += 1
                if progress is not None:
                    result.seconds = time.monotonic() - start
                    result.peak_rss = peak_rss()
                    progress(result)
    result.seconds = time.monotonic() - start
    result.peak_rss = peak_rss()
    return result


def _batch(target: Target, seed: int, batch: int, examples: int, deadline: float,
           folder: Path, baseline: int, result: Result, out_dir: Path | None) -> None:
    tally = result.kinds[target.name]

    @hypothesis_seed(seed * 1_000_003 + batch)
    @settings(max_examples=examples, database=None, deadline=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(st.integers(0, 2**63 - 1))
    def one(example: int) -> None:
        if time.monotonic() >= deadline:
            return
        with quiet():  # libraries a target makes inputs with may log too
            inp = target.make(random.Random(f"{target.name}/{seed}/{batch}/{example}"))
        t0 = time.perf_counter()
        try:
            with time_limit(TIME_LIMIT_S), quiet():
                outcome = target.exercise(inp, folder)
            if peak_rss() - baseline > MEMORY_LIMIT:
                raise TooMuchMemory(f"peak memory grew by {(peak_rss() - baseline) >> 20} MiB")
        except Exception as exc:
            result.failure = "".join(traceback.format_exception(exc))
            result.failed_kind = target.name
            small = shrink(inp, fails_like(target, folder, type(exc)))
            result.reproducer = write_reproducer(target, small, out_dir or Path.cwd(),
                                                 f"fuzz-failure-{target.name}-{example}")
            raise _Failed from exc
        tally.slowest_s = max(tally.slowest_s, time.perf_counter() - t0)
        tally.inputs += 1
        tally.outcomes[outcome] += 1

    one()


def write_reproducer(target: Target, inp: Any, out_dir: Path, stem: str) -> list[Path]:
    """The files of ``inp`` written to ``out_dir``, named after ``stem``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, content in target.files(inp, stem).items():
        path = out_dir / name
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")
        paths.append(path)
    return paths
