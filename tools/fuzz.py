"""Fuzz every kind of author input: generated and mutated scenes, models, images, sounds,
Lua scripts and input streams, each through the code that reads it in a run.

Each kind is a target (:mod:`tools.fuzz_scene`, :mod:`tools.fuzz_assets`,
:mod:`tools.fuzz_lua`, :mod:`tools.fuzz_input`) run by the machinery of
:mod:`tools.fuzz_core`: every input must end in success or a message, never a
traceback, within 10 s and 1 GiB of new memory; the first failure is shrunk and written
out as a reproducer. Hypothesis drives the run from ``--seed``, so it repeats::

    .venv/bin/python -m tools.fuzz --seconds 3600                    # every kind, an hour
    .venv/bin/python -m tools.fuzz --inputs 100000 --seed 3          # shared evenly
    .venv/bin/python -m tools.fuzz --kind lua --kind osc --seconds 60

The test suite runs a short fixed-seed run of each target (tests/*/test_fuzz*.py).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tools import fuzz_assets, fuzz_input, fuzz_lua, fuzz_scene
from tools.fuzz_core import Result, Target, run

TARGETS: dict[str, Target] = {t.name: t for t in (
    fuzz_scene.TARGET, fuzz_assets.MODELS, fuzz_assets.IMAGES, fuzz_assets.SOUNDS,
    fuzz_lua.TARGET, fuzz_input.OSC, fuzz_input.SERIAL, fuzz_input.RECORDING)}


def summary(result: Result) -> str:
    """One line per kind (inputs, how they ended, the slowest), then the totals."""
    lines = []
    for name, kind in result.kinds.items():
        endings = ", ".join(f"{n} {what}" for what, n in sorted(kind.outcomes.items()))
        lines.append(f"  {name:<10} {kind.inputs:>7} inputs ({endings or 'none'}); slowest "
                     f"{kind.slowest_s:.2f} s")
    verdict = "FAILED" if result.failure else "0 tracebacks, 0 hangs"
    lines.append(f"{result.inputs} inputs in {result.seconds:.0f} s: {verdict}; slowest input "
                 f"{result.slowest_s:.2f} s; peak memory of the process "
                 f"{result.peak_rss / 2**20:.0f} MiB")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", action="append", choices=list(TARGETS),
                        help="a kind to fuzz (repeat for more; default: all)")
    parser.add_argument("--seconds", type=float, default=60.0, help="how long to run")
    parser.add_argument("--inputs", type=int, default=None,
                        help="stop after this many, shared evenly between the kinds")
    parser.add_argument("--seed", type=int, default=0, help="seed of the whole run")
    parser.add_argument("--out", type=Path, default=Path.cwd(),
                        help="folder for a failing input's reproducer")
    args = parser.parse_args(argv)
    targets = [TARGETS[k] for k in args.kind or TARGETS]
    shown = [0.0]

    def progress(r: Result) -> None:
        if r.seconds - shown[0] >= 30:
            shown[0] = r.seconds
            print(f"{r.inputs} inputs, {r.seconds:.0f} s, slowest {r.slowest_s:.2f} s",
                  file=sys.stderr, flush=True)

    result = run(targets, args.seconds if args.inputs is None else float("inf"), args.seed,
                 args.inputs, args.out, progress)
    print(f"seed {args.seed}:\n{summary(result)}")
    if result.failure:
        print(f"{result.failed_kind}: {result.failure}", file=sys.stderr)
        print("reproducer: " + ", ".join(map(str, result.reproducer)), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
