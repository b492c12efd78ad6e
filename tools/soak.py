"""``python -m tools.soak``: a long run under churn whose memory must stay flat.

A content folder made for the purpose runs through ``colosseum run`` (threaded by
default, paced in real time, as an installation would run) for ``--minutes``; a
scene script spawns boxes that fall onto the ground and onto each other (contacts and
collision callbacks), deletes the oldest so about ``--keep`` stay alive, keeps
``after`` and ``every`` timers going and sends itself custom events every frame. The
process's resident memory is read from outside (``/proc/PID/statm``) every
``--every`` seconds.

Reported: the memory at the start, after the warm-up (the first fifth of the run, at
least a minute), at the end and at its highest; the slope after the warm-up (least
squares, MB per hour) and the growth per object churned. Flat means the growth after
warm-up stays within what a few allocator arenas make (a fraction of a MB), however
long the run.

    python -m tools.soak --minutes 60 --json soak.json
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

SCENE = """// soak: churn, contacts, timers and events for as long as it runs
World { TimeStep 0.01 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Script "scripts/churn.lua"
"""

CHURN = """-- keeps about KEEP boxes alive: PER new ones a frame fall on the pile, the oldest go
live, head, tail = {}, 1, 0
spawned, hits, ticks, heard = 0, 0, 0, 0

local function tick() ticks = ticks + 1 end
every(0.5, tick)
on("soak", function(data) heard = heard + data.n end)

function onUpdate(dt)
  local rows = {}
  for i = 1, PER do
    local n = tail + i
    rows[i] = 'Object { ID "box' .. i .. '" Position [' .. (n % 10) - 5 .. ' '
              .. (n // 10 % 10) - 5 .. ' 3] Size [0.4 0.4 0.4] PhysicalAttributes { } }'
  end
  for _, obj in ipairs(spawn(table.concat(rows, '\\n'))) do
    tail = tail + 1
    live[tail] = obj
  end
  spawned = spawned + PER
  while tail - head + 1 > KEEP do
    live[head]:delete()
    live[head] = nil
    head = head + 1
  end
  after(0.1, tick)
  emit("soak", {n = 1})
end

function onCollision(a, b, impulse) hits = hits + 1 end
"""


def make_content(folder: Path, per: int, keep: int) -> Path:
    (folder / "scripts").mkdir(parents=True, exist_ok=True)
    (folder / "main.scene").write_text(SCENE)
    (folder / "scripts" / "churn.lua").write_text(
        CHURN.replace("PER", str(per)).replace("KEEP", str(keep)))
    return folder


def resident_mb(pid: int) -> float | None:
    try:
        with open(f"/proc/{pid}/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6
    except (OSError, ValueError):
        return None


def slope_per_hour(samples: list[tuple[float, float]]) -> float:
    """Least-squares slope of (seconds, MB) samples, in MB per hour."""
    n = len(samples)
    if n < 2:
        return 0.0
    mt = sum(t for t, _ in samples) / n
    mm = sum(m for _, m in samples) / n
    var = sum((t - mt) ** 2 for t, _ in samples)
    cov = sum((t - mt) * (m - mm) for t, m in samples)
    return cov / var * 3600.0 if var else 0.0


def soak(minutes: float, mode: str, backend: str, per: int, keep: int,
         every: float) -> dict[str, Any]:
    """Run the soak; its figures."""
    seconds = minutes * 60.0
    with tempfile.TemporaryDirectory(prefix="colosseum-soak-") as tmp:
        content = make_content(Path(tmp) / "soak", per, keep)
        stats = Path(tmp) / "stats.json"
        command = [sys.executable, "-m", "app.cli", "--log-level", "warning", "run",
                   str(content), "--headless", "--mode", mode, "--backend", backend,
                   "--seconds", str(seconds), "--stats", str(stats)]
        start = time.monotonic()
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                   text=True)
        samples: list[tuple[float, float]] = []
        try:
            while process.poll() is None:
                mb = resident_mb(process.pid)
                if mb is not None:
                    samples.append((time.monotonic() - start, mb))
                time.sleep(every)
        finally:
            if process.poll() is None:
                process.terminate()
            _, errors = process.communicate(timeout=60)
        run = json.loads(stats.read_text()) if stats.exists() else {}
    if process.returncode != 0 or not samples:
        raise SystemExit(f"the soak run failed (exit {process.returncode}):\n{errors[-4000:]}")
    warm = max(60.0, 0.2 * samples[-1][0])
    after = [s for s in samples if s[0] >= warm] or samples[-1:]
    churned = run.get("frames", 0) * per
    growth = after[-1][1] - after[0][1]
    return {"minutes": minutes, "mode": mode, "backend": backend, "frames": run.get("frames"),
            "objects churned": churned, "contacts": run.get("contacts"),
            "start MB": samples[0][1], "after warm-up MB": after[0][1],
            "end MB": samples[-1][1], "peak MB": max(m for _, m in samples),
            "growth after warm-up MB": growth,
            "slope after warm-up MB/h": slope_per_hour(after),
            "bytes per object after warm-up": growth * 1e6 / max(
                1.0, churned * (samples[-1][0] - after[0][0]) / samples[-1][0]),
            "warnings": [line for line in errors.splitlines() if line.strip()][:20]}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tools.soak", description=__doc__.split(
        "\n")[0])
    parser.add_argument("--minutes", type=float, default=60.0, help="how long (default 60)")
    parser.add_argument("--mode", choices=["serial", "threaded"], default="threaded")
    parser.add_argument("--backend", default="ode", help="ode or pymunk (default ode)")
    parser.add_argument("--per", type=int, default=2, help="boxes spawned a frame")
    parser.add_argument("--keep", type=int, default=200, help="boxes kept alive")
    parser.add_argument("--every", type=float, default=5.0, help="seconds between samples")
    parser.add_argument("--json", type=Path, help="write the figures as JSON")
    args = parser.parse_args(argv)
    # stopped from outside: leave through the finally that ends the run it started
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    figures = soak(args.minutes, args.mode, args.backend, args.per, args.keep, args.every)
    for key, value in figures.items():
        if key != "warnings":
            print(f"{key:>32}: {value:.4g}" if isinstance(value, float) else
                  f"{key:>32}: {value}")
    for line in figures["warnings"]:
        print(f"  {line}")
    if args.json is not None:
        args.json.write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
