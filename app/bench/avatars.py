"""Avatar benchmark: 100 hounds, each blending Walk and Run by its own weight, headless.

The hound (content/avatars/models/hound.glb, made by tools/gltf_samples.py) has 32 joints
and about 1,800 textured vertices in one primitive, drawn at Scale 0.01 (it is modelled in
centimetres).

Three measurements, each beside a reference timed in the same run (alternating rounds, so
load from other processes falls on both alike):

* animation — the batched mixer (advance every fade and phase, sample every channel,
  blend, compose the hierarchies, make the joint matrices) against the channel-by-channel
  reference (:mod:`engine.animation.sampling`) run avatar by avatar. Goal: at most 2 ms.
  Timed twice: wall clock, and this process's CPU time (``cpu_ms``: what a frame costs;
  on a machine shared with other work the wall clock also counts the waits for a core,
  so the goal is judged on it, with the load average beside it).
* skinning — what skinning adds to a frame on the GPU (transform feedback, palettes
  uploaded) against linear-blend skinning of the same meshes with numpy on the CPU.
* frames — frames per second of the whole scene drawn by the software renderer, skinned,
  against the same hounds drawn unskinned (in their bind pose).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from components import Shape, Visual
from engine.animation import Mixer
from engine.animation.sampling import clip_pose, joint_matrices
from engine.animation.skinning import skin
from engine.assets import Assets, SkinnedModel
from engine.rotation import compose, slerp
from services.render.camera import CameraView
from services.render.context import HeadlessTarget
from services.render.lights import LightInfo
from services.render.renderer import Renderer

MODELS = Path(__file__).resolve().parents[2] / "content" / "avatars" / "models"
DT = 1.0 / 60.0
GOAL_MS = 2.0


def _weights(count: int, frame: int) -> np.ndarray:
    """Each hound's Run weight this frame (its speed rising and falling)."""
    return 0.5 + 0.5 * np.sin(0.05 * frame + np.arange(count))


class _Batched:
    def __init__(self, hound: SkinnedModel, count: int) -> None:
        self.mixer = Mixer()
        rig = self.mixer.library.rig_for(hound)
        for key in range(count):
            self.mixer.add(key, rig)
            self.mixer.blend(key, {"Walk": 0.5, "Run": 0.5})
        self.hound, self.count, self.frame = hound, count, 0
        self.palettes = np.zeros((0, 3, 4))

    def step(self) -> None:
        run = _weights(self.count, self.frame)
        for key in range(0, self.count, 10):  # a tenth of them change gait each frame
            self.mixer.blend(key, {"Walk": 1.0 - float(run[key]), "Run": float(run[key])})
        self.mixer.advance(DT)
        world, plan = self.mixer.evaluate()
        self.palettes = np.ascontiguousarray(plan.palettes(world)[:, :3, :], np.float32)
        self.frame += 1


class _Reference:
    """The same work avatar by avatar: two clips sampled channel by channel, blended node
    by node with slerp, composed into joint matrices."""

    def __init__(self, hound: SkinnedModel, count: int) -> None:
        self.hound, self.count, self.frame = hound, count, 0
        self.walk, self.run = hound.clip("Walk"), hound.clip("Run")
        self.phase = np.zeros(count)

    def step(self) -> None:
        hound = self.hound
        run_w = _weights(self.count, self.frame)
        for key in range(self.count):
            w = float(run_w[key])
            rate = (1 - w) / self.walk.duration + w / self.run.duration
            self.phase[key] = (self.phase[key] + DT * rate) % 1.0
            t1, r1, s1 = clip_pose(hound, "Walk", self.phase[key] * self.walk.duration)
            t2, r2, s2 = clip_pose(hound, "Run", self.phase[key] * self.run.duration)
            local = compose(t1 + w * (t2 - t1), slerp(r1, r2, w), s1 + w * (s2 - s1))
            joint_matrices(hound, local)
        self.frame += 1


def _timed(cases: list[Callable[[], None]], rounds: int, frames: int,
           clock: Callable[[], float] = time.perf_counter) -> list[float]:
    """Median ms per frame of each case on ``clock``, rounds alternating between them."""
    times: list[list[float]] = [[] for _ in cases]
    for _ in range(rounds):
        for i, case in enumerate(cases):
            start = clock()
            for _ in range(frames):
                case()
            times[i].append(1000.0 * (clock() - start) / frames)
    return [float(np.median(t)) for t in times]


def _scene(target: HeadlessTarget, hound: SkinnedModel, assets: Assets, count: int,
           skinned: bool) -> Renderer:
    renderer = Renderer(target, root=MODELS, assets=assets)
    renderer.add(10_000, Visual(shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))]))
    side = int(np.ceil(np.sqrt(count)))
    for key in range(count):
        at = ((key % side - side / 2) * 1.6, (key // side - side / 2) * 1.6, 0.0)
        renderer.add(key, Visual(model="hound.glb", scale=(0.01,) * 3), at,
                     skin=hound if skinned else None)
    renderer.lights = [LightInfo("directional", direction=(-0.4, -0.3, -1.0), shadows=True)]
    renderer.camera = CameraView.looking_at((0.0, -16.0, 10.0), (0.0, 0.0, 0.0))
    return renderer


def run_bench(count: int = 100, rounds: int = 5, frames: int = 20, quick: bool = False
              ) -> list[dict]:
    if quick:
        rounds, frames = 3, 5
    assets = Assets(MODELS)
    hound = assets.skinned("hound.glb")
    batched, reference = _Batched(hound, count), _Reference(hound, count)
    batched.step()
    load = os.getloadavg()[0]
    anim_ms, ref_ms = _timed([batched.step, reference.step], rounds, frames)
    anim_cpu_ms, ref_cpu_ms = _timed([batched.step, reference.step], rounds, frames,
                                     time.process_time)
    part = hound.parts[0]

    def cpu_skinning() -> None:
        palettes = batched.palettes.reshape(count, -1, 3, 4)
        full = np.zeros((len(hound.palette_nodes), 4, 4))
        full[:, 3, 3] = 1.0
        for key in range(count):
            full[:, :3, :] = palettes[key]
            skin(part.vertices, part.normals, part.joints, part.weights, full)

    target = HeadlessTarget((640, 480))
    skinned = _scene(target, hound, assets, count, skinned=True)
    static = _scene(target, hound, assets, count, skinned=False)
    offsets = {key: key * len(hound.palette_nodes) for key in range(count)}

    def draw_skinned() -> None:
        batched.step()
        skinned.set_palettes(batched.palettes, offsets)
        skinned.render(DT)
        target.ctx.finish()

    def draw_static() -> None:
        batched.step()
        static.render(DT)
        target.ctx.finish()

    try:
        draw_skinned(), draw_static()
        skinned_ms, static_ms, cpu_ms = _timed([draw_skinned, draw_static, cpu_skinning],
                                               rounds, max(frames // 2, 3))
        gl = target.renderer_name
    finally:
        skinned.release()
        static.release()
        target.close()
    gpu_ms = max(skinned_ms - static_ms, 0.0)
    return [
        {"case": "animation: batched mixer", "avatars": count, "ms_per_frame": anim_ms,
         "cpu_ms": anim_cpu_ms, "reference": "avatar by avatar", "reference_ms": ref_ms,
         "reference_cpu_ms": ref_cpu_ms, "speedup": ref_ms / anim_ms, "goal_ms": GOAL_MS,
         "ok": "yes" if anim_cpu_ms <= GOAL_MS else "NO", "load": load},
        {"case": "skinning: GPU transform feedback", "avatars": count, "ms_per_frame": gpu_ms,
         "reference": "numpy on the CPU", "reference_ms": cpu_ms,
         "speedup": cpu_ms / gpu_ms if gpu_ms > 0 else float("inf")},
        {"case": "frame: skinned, 640x480", "avatars": count, "ms_per_frame": skinned_ms,
         "fps": 1000.0 / skinned_ms, "reference": "unskinned hounds", "reference_ms": static_ms,
         "reference_fps": 1000.0 / static_ms, "gl_renderer": gl},
    ]
