"""Run statistics: what ``--stats FILE.json`` writes and the progress line shows.

:data:`STATS_SCHEMA` is the file's JSON Schema, every key with its unit; docs/STATS.md
and docs/stats.schema.json are generated from it, and the tests check a real run's file
against it, so the three cannot drift apart.
"""

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
    stats.update(sections(engine))
    return stats


def sections(engine: Engine) -> dict[str, Any]:
    """The plugins' sections (``render``, ``sound``); read again after ``engine.close()``
    to count what systems did as they shut down (the frame a --screenshot draws)."""
    return {name: source() for name, source in engine.stat_sources.items()}


def status_line(engine: Engine) -> str:
    s = collect(engine)
    return (f"t={s['sim_seconds']:7.2f}s frame {s['frames']:6d}  rtf {s['real_time_factor']:5.2f}  "
            f"physics {s['physics_ms_mean']:6.2f} ms  frame {s['frame_ms_mean']:6.2f} ms  "
            f"bodies {s['bodies']}")


def write_json(path: Path, data: dict[str, Any]) -> None:
    write_atomic(path, json.dumps(data, indent=2, sort_keys=True) + "\n")


def _key(kind: str, unit: str, meaning: str) -> dict[str, Any]:
    return {"type": kind, "description": f"{meaning} ({unit})" if unit else meaning,
            "x-unit": unit}


def _section(meaning: str, keys: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return {"type": "object", "description": meaning, "properties": keys,
            "required": list(keys), "additionalProperties": False}


#: The ``--stats`` file (JSON Schema draft 2020-12); "x-unit" is each number's unit.
STATS_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "colosseum run --stats",
    "type": "object",
    "properties": {
        "mode": {"enum": ["serial", "threaded"], "description": "where physics ran",
                 "x-unit": ""},
        "backend": _key("string", "", "dynamics backend (ode, pymunk, ballistic)"),
        "frames": _key("integer", "", "frames run"),
        "steps": _key("integer", "", "physics steps taken (frames times substeps, in serial)"),
        "sim_seconds": _key("number", "s", "simulated time at the end"),
        "wall_seconds": _key("number", "s", "wall-clock time the frames took"),
        "real_time_factor": _key("number", "", "simulated seconds per wall second"),
        "physics_ms_mean": _key("number", "ms", "mean wall time of one physics step"),
        "physics_ms_p99": _key("number", "ms", "99th percentile of a physics step"),
        "frame_ms_mean": _key("number", "ms", "mean wall time of a frame, every phase"),
        "frame_ms_p99": _key("number", "ms", "99th percentile of a frame"),
        "bodies": _key("integer", "", "bodies in the physics world at the end"),
        "entities": _key("integer", "", "entities in the ECS world at the end"),
        "contacts": _key("integer", "", "contact points reported over the run"),
        "dt": _key("number", "s", "physics time step at the end (it may grow with --late grow)"),
        "substeps": _key("integer", "", "physics steps per frame at the end"),
        "slept_seconds": _key("number", "s", "wall time spent waiting to stay real-time"),
        "render": _section("drawing (present when the render plugin ran)", {
            "backend": _key("string", "", "render target: headless or window"),
            "gl_renderer": _key("string", "", "the OpenGL driver"),
            "frames_drawn": _key("integer", "", "frames drawn, a --screenshot one included"),
            "frames_written": _key("integer", "", "frames written by --record-frames"),
            "render_ms_mean": _key("number", "ms", "mean CPU time to draw a frame"),
            "render_ms_p99": _key("number", "ms", "99th percentile of drawing a frame"),
            "render_ms_last": _key("number", "ms", "CPU time of the last frame drawn"),
            "draw_calls": _key("integer", "", "draw calls of the last frame"),
            "instances": _key("integer", "", "objects drawn in the last frame"),
            "fps": _key("number", "1/s", "frames drawn per wall second (smoothed; 0 for one)"),
            "errors": {"type": "array", "items": {"type": "string"},
                       "description": "shader and asset problems told while drawing",
                       "x-unit": ""},
        }),
        "xr": _section("the headset display (present when --xr or a scene's Display { Kind "
                       "\"openxr\" } opened it)", {
            "runtime": _key("string", "", "the OpenXR runtime's name and version"),
            "system": _key("string", "", "the headset, as the runtime names it"),
            "reference_space": _key("string", "", "stage, local_floor or local"),
            "eye_size": {"type": "array", "items": {"type": "integer"},
                         "description": "pixels drawn per eye (width, height)", "x-unit": "px"},
            "color_format": {"type": ["string", "null"], "x-unit": "",
                             "description": "the eyes' swapchain format"},
            "depth_submitted": _key("boolean", "", "each eye's depth handed to the runtime"),
            "refresh_rate": {"type": ["number", "null"], "x-unit": "Hz",
                             "description": "the display's rate, where the runtime says (Hz)"},
            "frames_submitted": _key("integer", "", "frames drawn and handed to the runtime"),
            "frames_skipped": _key("integer", "", "frames the runtime said not to draw "
                                   "(shouldRender false), ended empty"),
            "frames_late": _key("integer", "", "frames handed over after their predicted "
                                "display time"),
            "frames_with_hud": _key("integer", "", "frames submitted with the HUD as a "
                                    "head-locked layer (--hud)"),
            "session_state_max": _key("string", "", "the furthest session state reached "
                                      "(IDLE, READY, SYNCHRONIZED, VISIBLE, FOCUSED)"),
            "session_end": {"type": ["string", "null"], "x-unit": "",
                            "description": "how the session ended: exiting, lost, or null "
                                           "(the run ended it)"},
            "render_ms": _key("number", "ms", "mean time from locating the eyes to handing "
                              "the stereo frame over"),
            "render_ms_p99": _key("number", "ms", "99th percentile of the same"),
            "wait_ms": _key("number", "ms", "mean time blocked in xrWaitFrame (the runtime "
                            "pacing the loop)"),
        }),
        "sound": _section("sound (present when the sound plugin ran)", {
            "backend": _key("string", "", "openal, wave or null"),
            "pool_size": _key("integer", "", "voices that can play at once"),
            "requests": _key("integer", "", "sounds asked for"),
            "played": _key("integer", "", "requests that started playing"),
            "queued": _key("integer", "", "requests that waited for a voice"),
            "dropped": _key("integer", "", "requests given up (no voice, low priority)"),
            "stolen": _key("integer", "", "voices taken from a lower-priority sound"),
            "failed": _key("integer", "", "requests whose file could not be played"),
            "cancelled": _key("integer", "", "requests stopped before they played"),
            "waiting": _key("integer", "", "requests still waiting at the end"),
            "active": _key("integer", "", "voices playing at the end"),
            "streamed": _key("integer", "", "sounds played by streaming"),
            "underruns": _key("integer", "", "times a stream ran dry"),
            "contact_sounds": _key("integer", "", "sounds started by contacts"),
        }),
        "measures": {"type": "object", "description": "the run's final values: Measure "
                     "blocks and measure(name, value) in scripts, by name", "x-unit":
                     "as measured", "properties": {}, "additionalProperties": {
                         "type": "number"}},
        "net": {"type": "object", "description": "network (colosseum serve and join)",
                "x-unit": "", "additionalProperties": False, "properties": {
                    "nodes": {"type": "array", "items": {"type": "string"}, "x-unit": "",
                              "description": "server: users joined at the end"},
                    "replicated": _key("integer", "", "server: objects sent to nodes"),
                    "custom_dropped": _key("integer", "", "server: custom events the nodes "
                                           "were not told (over 64 in a frame)"),
                    "frames_sent": _key("integer", "", "server: frames published"),
                    "bytes_sent": _key("integer", "B", "server: bytes published (each "
                                       "node receives them all)"),
                    "publish_ms_mean": _key("number", "ms", "server: mean time its frame "
                                            "spent gathering a frame for the sender"),
                    "publish_ms_p99": _key("number", "ms", "server: 99th percentile of it"),
                    "send_ms_mean": _key("number", "ms", "server: mean time its sender "
                                         "thread took to encode and send a frame"),
                    "send_ms_p99": _key("number", "ms", "server: 99th percentile of it"),
                    "send_cpu_ms_mean": _key("number", "ms", "server: mean CPU time of "
                                             "it (less its waits for the GIL or a core)"),
                    "frames_merged": _key("integer", "", "server: frames that took the "
                                          "place of one the sender had not sent yet"),
                    "inputs": _key("integer", "", "server: input messages from nodes"),
                    "refused": _key("integer", "", "server: nodes refused at hello"),
                    "oversized": _key("integer", "", "server: messages over the size "
                                      "limit, dropped"),
                    "malformed": _key("integer", "", "messages that were not the "
                                      "protocol's, dropped"),
                    "barrier_timeouts": _key("integer", "", "server: swap barriers let go "
                                             "before every display was ready"),
                    "frames_received": _key("integer", "", "node: frames received"),
                    "bytes_received": _key("integer", "B", "node: bytes received"),
                    "dropped": _key("integer", "", "node: frames that never arrived"),
                    "gaps": _key("integer", "", "node: frames it could not decode for a "
                                 "missed one before them (until a keyframe)"),
                    "stale": _key("integer", "", "node (display): frames newer than the "
                                  "one drawn, when the barrier chose an older one"),
                    "resyncs": _key("integer", "", "node: full states taken again (a "
                                    "restarted server)"),
                    "barrier_misses": _key("integer", "", "node: swap barriers that ran "
                                           "out"),
                    "shown_frame": _key("integer", "", "node: the newest server frame "
                                        "shown"),
                    "shown_time": _key("number", "s", "node: the server time shown last"),
                    "shown_frames": {"type": "array", "items": {"type": "integer"},
                                     "x-unit": "", "description": "node (display): the "
                                     "server frames drawn, newest last (at most 3600)"},
                    "latency_ms_p50": _key("number", "ms", "node: median of a frame's age "
                                           "when taken (wall clocks of both machines)"),
                    "latency_ms_p99": _key("number", "ms", "node: 99th percentile of it"),
                }},
    },
    "required": ["mode", "backend", "frames", "steps", "sim_seconds", "wall_seconds",
                 "real_time_factor", "physics_ms_mean", "physics_ms_p99", "frame_ms_mean",
                 "frame_ms_p99", "bodies", "entities", "contacts", "dt", "substeps",
                 "slept_seconds"],
    "additionalProperties": {"type": "object", "description": "a content plugin's section"},
}


def stats_markdown() -> str:
    """docs/STATS.md: every key of the --stats file, its type and unit."""
    def rows(props: dict[str, Any], prefix: str = "") -> list[str]:
        out = []
        for name, spec in props.items():
            if spec.get("type") == "object":
                out.append(f"| `{prefix}{name}` | object | {spec.get('x-unit', '')} | "
                           f"{spec['description']} |")
                out += rows(spec["properties"], f"{prefix}{name}.")
            else:
                kind = spec.get("type", "string")
                meaning = spec["description"].removesuffix(f" ({spec['x-unit']})")
                out.append(f"| `{prefix}{name}` | {kind} | {spec['x-unit']} | {meaning} |")
        return out

    return "\n".join([
        "# Run statistics (`--stats FILE.json`)", "",
        "<!-- generated from engine/stats.py by `python -m tools.docs`; "
        "tests/core/test_stats_schema.py keeps it equal and checks a real run's file -->", "",
        "`colosseum run --stats FILE.json` writes one JSON object when the run ends. Its JSON",
        "Schema is [stats.schema.json](stats.schema.json). Times are wall-clock unless they",
        "say simulated; a content folder's own plugin may add a section of its own.", "",
        "| key | type | unit | meaning |", "|---|---|---|---|",
        *rows(STATS_SCHEMA["properties"]), ""])
