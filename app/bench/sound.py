"""``colosseum bench sound``: SoundManager throughput and per-frame cost, beside raw OpenAL.

Rows:

* ``requests`` — one-shot requests per second the SoundManager handles while
  its pool is saturated (the contact-burst path: decide, queue or drop);
* ``frame`` — median per-frame cost of the sound system in a running Engine with 32
  looping sources attached to 32 moving bodies (follow poses and velocities,
  listener on a moving camera, reclaim, serve); target < 0.5 ms;
* reference, in the same run, on the same device, interleaved in chunks of 50
  frames so both see the same machine load: the raw AL calls alone that such a
  frame needs (position and velocity of 32 sources, the listener), unchecked
  ctypes calls straight into libopenal; ``ratio`` = ours / raw.

The default device is OpenAL Soft's wave writer on a temporary file (so the
mixer really runs beside the benchmark); ``backend`` names another
(``openal``, ``null``; no raw reference with ``null``).
"""

from __future__ import annotations

import ctypes
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import soundfile as sf

from systems import create_engine

SOURCES = 32


def _tone(path: Path, seconds: float) -> Path:
    t = np.arange(int(44100 * seconds)) / 44100
    sf.write(str(path), 0.3 * np.sin(2 * np.pi * 440 * t), 44100)
    return path


def run_bench(quick: bool = False, backend: str | None = None) -> list[dict[str, Any]]:
    """Table rows; ``backend`` is a sound backend spec (default: a temporary wave file)."""
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-sound-") as tmp:
        return _bench(Path(tmp), backend, quick)


def _bench(folder: Path, backend: str | None, quick: bool) -> list[dict[str, Any]]:
    from components import Camera, Physical, Sound, Transform
    from engine import EngineConfig
    from engine.physics.backend import WorldSettings
    from services.audio import SoundManager
    from systems.sound import SoundPlugin, SoundSystem

    spec = backend or f"wave:{folder / 'bench.wav'}"
    knock = _tone(folder / "knock.wav", 0.2)
    hum = _tone(folder / "hum.wav", 0.5)
    frames = 300 if quick else 2000
    rows: list[dict[str, Any]] = []

    cfg = EngineConfig(backend="ballistic", fast=True, sound=spec,
                       world=WorldSettings(gravity=(0.0, 0.0, 0.0)))
    with create_engine(cfg) as engine:
        engine.add_plugin(SoundPlugin(pool_size=SOURCES))
        rng = np.random.default_rng(0)
        engine.spawn(Transform(linear_velocity=(0.5, 0.2, 0.0)), Physical(gravity=False),
                     Camera())
        for _ in range(SOURCES):
            engine.spawn(Transform(position=rng.uniform(-10, 10, 3),
                                   linear_velocity=rng.uniform(-3, 3, 3)),
                         Physical(gravity=False), Sound(file=str(hum), loop=True, auto_play=True))
        system = engine.resource(SoundSystem)
        manager = engine.resource(SoundManager)
        costs = _costs(system)
        engine.run(frames=10)  # warm up: sources started, caches built
        costs.clear()
        raw = _RawFrame(manager) if manager.backend.name != "null" else None
        raw_costs: list[float] = []
        for _ in range(frames // 50):  # interleaved, so both see the same machine load
            engine.run(frames=50)
            if raw is not None:
                raw_costs += raw.run(50)
        assert manager.stats()["active"] == SOURCES, manager.stats()
        frame_ms = float(np.median(costs) * 1e3)
        raw_ms = float(np.median(raw_costs) * 1e3) if raw_costs else None
        rows.append({"case": f"frame, {SOURCES} sources on moving bodies",
                     "backend": manager.backend.name.split(":")[0], "ours_ms": frame_ms,
                     "p99_ms": float(np.percentile(costs, 99) * 1e3), "raw_al_ms": raw_ms,
                     "ratio": None if raw_ms is None else frame_ms / raw_ms,
                     "target_ms": 0.5})

        rows.append(_burst(manager, knock, rng, rows[0]["backend"], quick))
    with create_engine(cfg) as engine:
        engine.add_plugin(SoundPlugin(pool_size=SOURCES))
        rows.append(_free(engine.resource(SoundManager), knock, rng, rows[0]["backend"], quick))
    return rows


def _costs(system: Any) -> list[float]:
    """Wrap ``system.run`` to append each call's wall seconds to the list returned."""
    costs: list[float] = []
    run = system.run

    def timed(eng: Any, dt: float) -> None:
        t0 = time.perf_counter()
        run(eng, dt)
        costs.append(time.perf_counter() - t0)

    system.run = timed
    return costs


def _burst(manager: Any, knock: Path, rng: Any, backend: str, quick: bool) -> dict[str, Any]:
    """The burst path: every source busy with loops, so each request is decided (queued,
    then dropped at its deadline) rather than played."""
    n = 5_000 if quick else 50_000
    positions = rng.uniform(-5, 5, (n, 3))
    t0 = time.perf_counter()
    for i in range(n):
        manager.play(knock, position=positions[i], priority=-1)
        if i % 50 == 49:
            manager.update()
    busy = time.perf_counter() - t0
    return {"case": "requests, pool saturated", "backend": backend,
            "requests_per_s": n / busy, "us_per_request": busy / n * 1e6}


def _free(manager: Any, knock: Path, rng: Any, backend: str, quick: bool) -> dict[str, Any]:
    """Free sources: every request starts a source (configure, attach, play)."""
    n = 2_000 if quick else 10_000
    positions = rng.uniform(-5, 5, (n, 3))
    t0 = time.perf_counter()
    for i in range(n):
        voice = manager.play(knock, position=positions[i])
        manager.stop(voice)
    busy = time.perf_counter() - t0
    return {"case": "requests, free source (start+stop)", "backend": backend,
            "requests_per_s": n / busy, "us_per_request": busy / n * 1e6}


class _RawFrame:
    """The same AL work as one frame with no engine, numpy or manager: unchecked
    ``alSource3f`` position + velocity for every source, then the listener."""

    def __init__(self, manager: Any) -> None:
        from openal import al

        self.sources = [v.source for v in manager.voices]
        rng = np.random.default_rng(1)
        self.pos = rng.uniform(-10, 10, (len(self.sources), 3)).tolist()
        self.vel = rng.uniform(-3, 3, (len(self.sources), 3)).tolist()
        f3 = [ctypes.c_uint, ctypes.c_int, ctypes.c_float, ctypes.c_float, ctypes.c_float]
        self.source3f = al.lib["alSource3f"]
        self.source3f.argtypes, self.source3f.restype = f3, None
        self.listener3f = al.lib["alListener3f"]
        self.listener3f.argtypes, self.listener3f.restype = f3[1:], None
        self.listenerfv = al.lib["alListenerfv"]
        self.listenerfv.argtypes = [ctypes.c_int, ctypes.POINTER(ctypes.c_float)]
        self.listenerfv.restype = None
        self.get_error = al.alGetError
        self.orientation = (ctypes.c_float * 6)(0.0, 0.0, -1.0, 0.0, 1.0, 0.0)

    def run(self, frames: int) -> list[float]:
        set3f, listener3f, p_enum, v_enum = self.source3f, self.listener3f, 0x1004, 0x1006
        costs = []
        for k in range(frames):
            t0 = time.perf_counter()
            dx = 0.01 * k
            for s, p, v in zip(self.sources, self.pos, self.vel, strict=True):
                set3f(s, p_enum, p[0] + dx, p[1], p[2])
                set3f(s, v_enum, v[0], v[1], v[2])
            listener3f(p_enum, dx, 0.0, 0.0)
            listener3f(v_enum, 0.5, 0.0, 0.0)
            self.listenerfv(0x100F, self.orientation)
            self.get_error()
            costs.append(time.perf_counter() - t0)
        return costs


if __name__ == "__main__":
    from app.bench import print_table

    print_table(run_bench(quick=True))
