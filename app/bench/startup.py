"""``colosseum bench startup``: how long a command takes from the shell to its end, beside
a bare Python program that imports exactly the libraries that command needs.

Rows: ``check`` and ``run --frames 1 --headless`` of the demo scene (models, Lua, sound)
and of a plain scene (boxes on a ground: no model, no script, no sound), and ``keys``.
Each command and its reference run as fresh processes, alternately, ``repeats`` times;
the table shows the median seconds of each, wall and CPU (user + system of the process),
the median of the per-pair CPU ratios and their spread (lowest-highest). Goals: ``check``
and ``keys`` under 0.5 s on a plain scene; elsewhere (the demo's check loads its model,
and so trimesh) within 1.2x of the bare imports. They are judged on CPU seconds, which
other work on a shared machine stretches far less than wall seconds (as ``bench import``
does).

Byte-code is cached as on any installed machine (one untimed run of each first, into a
cache folder of the benchmark's own), whatever ``PYTHONDONTWRITEBYTECODE`` says.
Third-party modules a command loaded beyond its reference are named in the row: a library
loaded before the scene asks for it shows there.
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
CHECK_GOAL_S = 0.5
RUN_GOAL_RATIO = 1.2

#: A scene without models, scripts or sound: what any run needs and no more.
PLAIN_SCENE = """World { Gravity [0 0 -9.81] TimeStep 0.01 }
Object { ID "ground" Dynamic 0
  VisualAttributes { Geometry { Primitive "plane" } }
  PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "box" Position [0 0 1] Size [1 1 1]
  VisualAttributes { Geometry { Primitive "box" } Color [0.7 0.5 0.3] }
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" } } }
"""

#: What every scene needs: arrays, the ECS, the scene's physics library (libode).
CORE = ("numpy",)
RUN_CORE = (*CORE, "esper", "ctypes:ode")
#: What the demo's blocks add: models (trimesh), a Lua script, a shader drawn headless.
DEMO_CHECK = (*CORE, "trimesh", "soundfile")
DEMO_RUN = (*RUN_CORE, "trimesh", "soundfile", "lupa.lua54", "moderngl")

#: Loads libode as the engine's extension does, without the extension's Python side.
_IMPORT_ODE = ("import ctypes, ctypes.util\n"
               "ctypes.CDLL(ctypes.util.find_library('ode') or 'libode.so.8')\n")

#: What the installed ``colosseum`` script runs.
ENTRY_POINT = "import sys\nfrom app.cli import main\nsys.exit(main())"

#: Prints the third-party top-level modules loaded, when the process ends.
_REPORT_MODULES = ("import atexit, json, sys\n"
                   "atexit.register(lambda: print('\\nMODULES ' + json.dumps(sorted("
                   "{m.split('.')[0] for m in sys.modules} - set(sys.stdlib_module_names))),"
                   " file=sys.stderr))\n")


@dataclass(frozen=True, slots=True)
class Case:
    """One command line of ``colosseum`` and the libraries its bare reference imports."""

    name: str
    argv: tuple[str, ...]
    needs: tuple[str, ...]
    goal: str  # "s": under CHECK_GOAL_S seconds; "x": within RUN_GOAL_RATIO of the reference

    def reference_code(self) -> str:
        """The bare program: the imports alone."""
        lines = [_IMPORT_ODE if n == "ctypes:ode" else f"import {n}\n" for n in self.needs]
        return "".join(lines) or "pass\n"


def cases(plain: Path) -> list[Case]:
    demo = str(ROOT / "content" / "demo")
    frame = ("--frames", "1", "--headless", "--fast")
    return [Case("keys", ("keys",), CORE, "s"),
            Case("check, plain scene", ("check", str(plain)), CORE, "s"),
            Case("check, demo", ("check", demo), DEMO_CHECK, "x"),
            Case("run to first frame, plain scene", ("run", str(plain), *frame), RUN_CORE,
                 "x"),
            Case("run to first frame, demo", ("run", demo, *frame), DEMO_RUN, "x")]


def run_bench(quick: bool = False, repeats: int = 7) -> list[dict[str, Any]]:
    """Every case, ours and its reference alternating, ``repeats`` pairs each."""
    repeats = 3 if quick else repeats
    with tempfile.TemporaryDirectory(prefix="colosseum-startup-") as tmp:
        folder = Path(tmp)
        (folder / "plain").mkdir()
        (folder / "plain" / "main.scene").write_text(PLAIN_SCENE, encoding="utf-8")
        env = _environment(folder / "pycache")
        rows = []
        for case in cases(folder / "plain"):
            ours_cmd = [sys.executable, "-c", ENTRY_POINT, *case.argv]
            ref_cmd = [sys.executable, "-c", case.reference_code()]
            extra = _extra_modules(case, env, folder)  # also warms the byte-code cache
            _timed(ref_cmd, env, folder)
            pairs = [(_timed(ours_cmd, env, folder), _timed(ref_cmd, env, folder))
                     for _ in range(repeats)]
            rows.append(_row(case, pairs, extra))
    return rows


def _environment(pycache: Path) -> dict[str, str]:
    """This checkout's code first, byte-code cached in ``pycache``."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env["PYTHONPYCACHEPREFIX"] = str(pycache)
    return env


def _timed(cmd: list[str], env: dict[str, str], cwd: Path) -> tuple[float, float]:
    """Wall and CPU seconds of one process from start to exit; it must succeed."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, timeout=120,
                          check=False)
    elapsed = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        shown = " ".join(cmd[3:]) or cmd[2]  # colosseum's arguments, else the bare program
        raise RuntimeError(f"bench startup: {shown!r} failed "
                           f"({done.returncode}): {done.stderr.strip()[-400:]}")
    return elapsed, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _extra_modules(case: Case, env: dict[str, str], cwd: Path) -> list[str]:
    """Third-party top-level modules the command loaded that its reference did not."""
    def loaded(code: str) -> set[str]:
        done = subprocess.run([sys.executable, "-c", _REPORT_MODULES + code], env=env,
                              cwd=cwd, capture_output=True, text=True, timeout=120,
                              check=False)
        line = next((s for s in done.stderr.splitlines() if s.startswith("MODULES ")), None)
        if done.returncode != 0 or line is None:
            raise RuntimeError(f"bench startup: {case.name} failed: {done.stderr[-400:]}")
        return {m for m in json.loads(line[8:])  # cython_runtime: made by any Cython module
                if not m.startswith("_") and m != "cython_runtime"}

    ours = loaded(f"import sys\nfrom app.cli import main\nsys.exit(main({list(case.argv)!r}))")
    ours -= {"engine", "components", "systems", "tools"}
    ours = {m for m in ours if not m.startswith("colosseum_content_")}  # the folder's code
    return sorted(ours - loaded(case.reference_code()))


def _row(case: Case, pairs: list[tuple[tuple[float, float], tuple[float, float]]],
         extra: list[str]) -> dict[str, Any]:
    """The medians of ``pairs`` ((wall, cpu) of ours, of the reference), the CPU ratio's
    median and spread, the goal judged on CPU seconds."""
    def median(side: int, what: int) -> float:
        return statistics.median(p[side][what] for p in pairs)

    ours_cpu = median(0, 1)
    ratios = sorted(o[1] / r[1] for o, r in pairs)
    ratio = statistics.median(ratios)
    row: dict[str, Any] = {
        "command": case.name, "reference: bare imports of": ", ".join(
            "libode" if n == "ctypes:ode" else n for n in case.needs),
        "ours wall s": median(0, 0), "reference wall s": median(1, 0),
        "ours cpu s": ours_cpu, "reference cpu s": median(1, 1),
        "cpu ratio": ratio, "spread": f"{ratios[0]:.2f}-{ratios[-1]:.2f}", "runs": len(pairs)}
    if case.goal == "s":
        row["goal"] = f"< {CHECK_GOAL_S:g} cpu s"
        row["ok"] = "yes" if ours_cpu < CHECK_GOAL_S else "NO"
    else:
        row["goal"] = f"<= {RUN_GOAL_RATIO:g}x"
        row["ok"] = "yes" if ratio <= RUN_GOAL_RATIO else "NO"
    row["loaded beyond the reference"] = ", ".join(extra) or "-"
    return row
