"""Render benchmark: 1,000 boxes with one shadowed light, headless at 640x480.

Instanced drawing (one draw call per mesh/material) against the same boxes drawn one draw call
per box, in the same run, so the ratio says what instancing buys on this machine's GL
(Mesa llvmpipe on CPU-only machines).
"""

from __future__ import annotations

import time

import numpy as np

from components import Shape, Visual
from services.render.camera import CameraView
from services.render.context import HeadlessTarget
from services.render.lights import LightInfo
from services.render.renderer import Renderer


def _scene(renderer: Renderer, count: int, rng: np.random.Generator) -> np.ndarray:
    """A floor and ``count`` coloured boxes on a grid; returns the boxes' positions."""
    renderer.add(0, Visual(shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))]))
    side = int(np.ceil(np.sqrt(count)))
    positions = np.zeros((count, 3))
    for i in range(count):
        x, y = (i % side - side / 2) * 0.6, (i // side - side / 2) * 0.6
        positions[i] = (x, y, 0.2 + rng.uniform(0.0, 2.0))
        colour = (*rng.uniform(0.2, 1.0, 3), 1.0)
        renderer.add(i + 1, Visual(shapes=[Shape("box", (0.4, 0.4, 0.4))], color=colour),
                     position=positions[i])
    renderer.lights = [LightInfo("directional", direction=(-0.4, -0.3, -1.0), shadows=True)]
    renderer.camera = CameraView.looking_at((0.0, -14.0, 9.0), (0.0, 0.0, 0.0))
    return positions


class _Case:
    """One way of drawing the scene, timed in rounds interleaved with the other case."""

    def __init__(self, target: HeadlessTarget, instancing: bool, count: int) -> None:
        self.target = target
        self.renderer = Renderer(target, instancing=instancing)
        self.base = _scene(self.renderer, count, np.random.default_rng(1))
        self.keys = np.arange(1, count + 1)
        self.quats = np.tile([1.0, 0.0, 0.0, 0.0], (count, 1))
        self.frame = 0
        self.round_ms: list[float] = []

    def run(self, frames: int, timed: bool = True) -> None:
        self.target.ctx.finish()
        start = time.perf_counter()
        for _ in range(frames):  # boxes move every frame, like a simulation
            pos = self.base.copy()
            pos[:, 2] += 0.1 * np.sin(self.frame * 0.1 + self.keys * 0.01)
            self.renderer.set_poses(self.keys, pos, self.quats)
            self.renderer.render(1 / 60)
            self.frame += 1
        self.target.ctx.finish()
        if timed:
            self.round_ms.append(1000.0 * (time.perf_counter() - start) / frames)

    def row(self, name: str) -> dict:
        ms = float(np.median(self.round_ms))
        stats = self.renderer.stats
        return {
            "case": name,
            "boxes": len(self.keys),
            "size": f"{self.target.size[0]}x{self.target.size[1]}",
            "frames": self.frame,
            "fps": 1000.0 / ms,
            "ms_per_frame": ms,
            "ms_best_round": min(self.round_ms),
            "draw_calls": stats.draw_calls,
            "shadow_draw_calls": stats.shadow_draw_calls,
            "gl_renderer": self.target.renderer_name,
        }


def run_bench(count: int = 1000, rounds: int = 6, frames_per_round: int = 10, warmup: int = 5,
              size: tuple[int, int] = (640, 480), quick: bool = False) -> list[dict]:
    """fps and ms per frame (median over rounds), instanced and one draw per box.

    The two cases alternate round by round so that load from other processes affects both
    alike; the instanced row carries ``speedup`` (its fps over the reference's).
    """
    if quick:
        rounds, frames_per_round, warmup = 3, 5, 2
    target = HeadlessTarget(size)
    cases = [_Case(target, True, count), _Case(target, False, count)]
    try:
        for case in cases:
            case.run(warmup, timed=False)
        for _ in range(rounds):
            for case in cases:
                case.run(frames_per_round)
        instanced, reference = cases[0].row("instanced"), cases[1].row("one draw per box")
    finally:
        for case in cases:
            case.renderer.release()
        target.close()
    instanced["speedup"] = instanced["fps"] / reference["fps"]
    reference["speedup"] = 1.0
    instanced["target_30fps_met"] = instanced["fps"] >= 30.0
    return [instanced, reference]


def _headset_camera(distance: float = 14.0) -> CameraView:
    """Two eyes 63 mm apart with a headset's asymmetric fields of view (Monado's simulated
    HMD's angles), looking over the boxes."""
    from services.render import math3d
    from services.render.camera import HeadsetEye
    from services.xr.projection import Fov, fov_projection

    centre = np.array([0.0, -distance, 9.0])
    look = math3d.look_at_orientation(centre, (0.0, 0.0, 0.0))
    right = math3d.compose(centre, look)[:3, 0]
    eyes = [HeadsetEye(centre + side * 0.0315 * right, look,
                       fov_projection(Fov(left, right_angle, 0.78, -0.78), 0.05, 500.0))
            for side, left, right_angle in ((-1, -0.74, 0.70), (1, -0.70, 0.74))]
    return CameraView(centre, look, near=0.05, far=500.0, headset=eyes)


class _StereoCase(_Case):
    """Mono at one eye's size, or both eyes side by side (one pass, or one pass an eye);
    timed by the CPU time of the thread that draws (what a headset's frame costs the
    engine; a GPU, or llvmpipe's own threads, rasterise beside it)."""

    def __init__(self, eye: tuple[int, int], count: int, eyes: int, single: bool) -> None:
        target = HeadlessTarget((eye[0] * eyes, eye[1]))
        super().__init__(target, True, count)
        self.renderer.single_pass = single
        if eyes == 2:
            self.renderer.camera = _headset_camera()
        self.cpu_ms: list[float] = []
        self.engine_ms: list[float] = []

    def run(self, frames: int, timed: bool = True) -> None:
        self.target.ctx.finish()
        start, driver = time.thread_time(), 0.0
        renderer = self.renderer
        for _ in range(frames):
            super().run(1, timed=False)
            driver += renderer.stats.driver_ms
        if timed:
            cpu = 1000.0 * (time.thread_time() - start) / frames
            self.cpu_ms.append(cpu)
            self.engine_ms.append(cpu - driver / frames)
            self.round_ms.append(cpu)


def run_stereo_bench(quick: bool = False, backend: str | None = None, count: int = 2000,
                     eye: tuple[int, int] = (320, 240)) -> list[dict]:
    """``colosseum bench render --stereo``: the CPU time of a stereo frame, both eyes in
    one pass and one pass an eye, beside a mono frame at the same per-eye resolution
    (rounds interleaved; median, and the spread over rounds). ``engine_cpu_ms`` is the
    drawing thread's CPU time less what it spent inside the GL driver's draws and clears
    (on llvmpipe the vertex stage runs there, where a GPU would run it); ``cpu_ms`` is all
    of it."""
    rounds, frames, warmup = (3, 5, 2) if quick else (8, 10, 4)
    cases = {"mono": _StereoCase(eye, count, 1, True),
             "stereo, one pass": _StereoCase(eye, count, 2, True),
             "stereo, one pass an eye": _StereoCase(eye, count, 2, False)}
    try:
        for case in cases.values():
            case.run(warmup, timed=False)
        for _ in range(rounds):
            for case in cases.values():
                case.run(frames)
        rows = []
        mono = cases["mono"]
        for name, case in cases.items():
            row = case.row(name)
            ratios = np.array(case.engine_ms) / np.array(mono.engine_ms)
            row.update({"cpu_ms": float(np.median(case.cpu_ms)),
                        "engine_cpu_ms": float(np.median(case.engine_ms)),
                        "engine_vs_mono": float(np.median(ratios)),
                        "engine_vs_mono_min": float(ratios.min()),
                        "engine_vs_mono_max": float(ratios.max()),
                        "cpu_vs_mono": float(np.median(np.array(case.cpu_ms)
                                                       / np.array(mono.cpu_ms)))})
            rows.append(row)
    finally:
        for case in cases.values():
            case.renderer.release()
            case.target.close()
    rows[1]["goal_1.2x_met"] = rows[1]["engine_vs_mono"] <= 1.2
    return rows
