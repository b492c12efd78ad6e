"""Run statistics: what ``--stats FILE.json`` writes and the progress line shows."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from engine.files import write_atomic

if TYPE_CHECKING:
    from engine.app import Engine


def collect(engine: Engine) -> dict[str, Any]:
    """Frames, simulated and wall seconds, real-time factor, per-step and per-frame costs."""
    physics = engine.physics
    steps = physics.controller.step_costs
    wall = engine.controller.wall_time
    stats: dict[str, Any] = {
        "mode": engine.config.mode,
        "backend": physics.backend_name,
        "frames": engine.frame,
        "steps": physics.steps,
        "sim_seconds": physics.time,
        "wall_seconds": wall,
        "real_time_factor": engine.real_time_factor,
        "physics_ms_mean": steps.mean() * 1e3,
        "physics_ms_p99": steps.percentile(99) * 1e3,
        "frame_ms_mean": engine.frame_costs.mean() * 1e3,
        "frame_ms_p99": engine.frame_costs.percentile(99) * 1e3,
        "bodies": len(physics.snapshot.bodies.keys),
        "entities": len(engine.world),
        "contacts": physics.contacts_total,
        "dt": engine.controller.dt,
        "substeps": engine.controller.substeps,
        "slept_seconds": engine.controller.slept,
    }
    for name, source in engine.stat_sources.items():
        stats[name] = source()
    return stats


def status_line(engine: Engine) -> str:
    s = collect(engine)
    return (f"t={s['sim_seconds']:7.2f}s frame {s['frames']:6d}  rtf {s['real_time_factor']:5.2f}  "
            f"physics {s['physics_ms_mean']:6.2f} ms  frame {s['frame_ms_mean']:6.2f} ms  "
            f"bodies {s['bodies']}")


def write_json(path: Path, data: dict[str, Any]) -> None:
    write_atomic(path, json.dumps(data, indent=2, sort_keys=True) + "\n")
