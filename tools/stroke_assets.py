"""Makes the stroke simulator's models and sounds (content/stroke/models, sounds).

Models are built with trimesh from primitives and written as small OBJ files: a
wheelchair wheel (tyre, rim, spokes, hub and push rim), a bowl, a cup with a handle, a
plate, a fork, a knife, a spoon, a broom and a dust pan. Physics uses primitives and
convex hulls of some of these (the scene says which), so the meshes stay light.

Sounds are synthesised (decaying partials and filtered noise, 22 050 Hz mono, 16-bit)
and short: a ceramic knock, a cutlery clink, a glass ting, a broom's brush, a cardboard
tap and the chair's bump. Everything is deterministic (fixed seeds), so running this
again writes the same files. Run: ``python -m tools.stroke_assets [--out FOLDER]``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import soundfile
import trimesh

from tools.stroke_scene import write_cli

RATE = 22050


# -- models -----------------------------------------------------------------------
def _cylinder(radius: float, height: float, centre: tuple[float, float, float],
              axis: str = "z", sections: int = 24) -> trimesh.Trimesh:
    mesh = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
    if axis == "x":
        mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0)))
    elif axis == "y":
        mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    mesh.apply_translation(centre)
    return mesh


def _box(size: tuple[float, float, float], centre: tuple[float, float, float]
         ) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=size)
    mesh.apply_translation(centre)
    return mesh


def wheel() -> trimesh.Trimesh:
    """A rear wheel about X, Ø 0.61 m: tyre, rim, 12 spokes, hub, and the push rim."""
    turn = trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0))
    tyre = trimesh.creation.torus(0.29, 0.015, major_sections=48, minor_sections=8)
    push_rim = trimesh.creation.torus(0.26, 0.008, major_sections=48, minor_sections=6)
    push_rim.apply_translation((0, 0, 0.045))
    parts = [tyre, push_rim, trimesh.creation.annulus(0.26, 0.28, 0.02, sections=48),
             _cylinder(0.03, 0.07, (0, 0, 0))]
    for k in range(12):
        spoke = _cylinder(0.002, 0.25, (0, 0, 0), "x", sections=5)
        spoke.apply_translation((0.14, 0, 0))
        spoke.apply_transform(trimesh.transformations.rotation_matrix(k * np.pi / 6, (0, 0, 1)))
        parts.append(spoke)
    mesh = trimesh.util.concatenate(parts)
    mesh.apply_transform(turn)
    return mesh


def _lathe(profile: list[tuple[float, float]], sections: int = 32) -> trimesh.Trimesh:
    """A solid of revolution about Z from (radius, height) points (a closed outline)."""
    return trimesh.creation.revolve(np.array(profile, float), sections=sections)


def bowl() -> trimesh.Trimesh:
    """Ø 0.15 m, 0.065 m tall, walls 5 mm; base at z = -0.0325 (centred)."""
    h = 0.0325
    return _lathe([(0.0, -h), (0.04, -h), (0.075, h), (0.07, h), (0.036, -h + 0.005),
                   (0.0, -h + 0.005)])


def plate() -> trimesh.Trimesh:
    """Ø 0.26 m, 0.02 m tall, centred."""
    return _lathe([(0.0, -0.01), (0.09, -0.01), (0.13, 0.01), (0.125, 0.01), (0.09, -0.004),
                   (0.0, -0.004)], sections=40)


def cup() -> trimesh.Trimesh:
    """Ø 0.08 m, 0.095 m tall, with a handle on +X; centred on the body."""
    h = 0.0475
    body = _lathe([(0.0, -h), (0.038, -h), (0.04, h), (0.035, h), (0.034, -h + 0.006),
                   (0.0, -h + 0.006)])
    handle = trimesh.creation.torus(0.022, 0.005, major_sections=16, minor_sections=6)
    handle.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    handle.apply_translation((0.045, 0, 0.005))
    return trimesh.util.concatenate([body, handle])


def _utensil(head: trimesh.Trimesh) -> trimesh.Trimesh:
    """A 0.19 m handle along Y with ``head`` at its +Y end, centred."""
    handle = _box((0.012, 0.11, 0.004), (0, -0.03, 0))
    return trimesh.util.concatenate([handle, head])


def fork() -> trimesh.Trimesh:
    tines = [_box((0.003, 0.04, 0.003), (x, 0.065, 0)) for x in (-0.0075, -0.0025, 0.0025,
                                                                 0.0075)]
    return _utensil(trimesh.util.concatenate([_box((0.02, 0.02, 0.003), (0, 0.035, 0)),
                                              *tines]))


def knife() -> trimesh.Trimesh:
    return _utensil(_box((0.018, 0.08, 0.002), (0, 0.065, 0)))


def spoon() -> trimesh.Trimesh:
    head = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    head.apply_scale((0.02, 0.03, 0.006))
    head.apply_translation((0, 0.06, 0))
    return _utensil(head)


def broom() -> trimesh.Trimesh:
    """A 1.2 m handle along Z with a 0.3 m head at its lower end; origin at its middle."""
    handle = _cylinder(0.012, 1.2, (0, 0, 0.0))
    head = _box((0.3, 0.06, 0.05), (0, 0, -0.6))
    bristles = _box((0.28, 0.05, 0.06), (0, 0, -0.655))
    return trimesh.util.concatenate([handle, head, bristles])


def dust_pan() -> trimesh.Trimesh:
    """A 0.25 m wide pan (its floor at z = -0.02), its open lip toward -Y, a short handle."""
    parts = [_box((0.25, 0.22, 0.004), (0, 0.0, -0.02)),
             _box((0.004, 0.22, 0.05), (-0.125, 0.0, 0.003)),
             _box((0.004, 0.22, 0.05), (0.125, 0.0, 0.003)),
             _box((0.25, 0.004, 0.05), (0, 0.11, 0.003)),
             _box((0.03, 0.12, 0.02), (0, 0.17, 0.0))]
    return trimesh.util.concatenate(parts)


MODELS = {"wheel.obj": wheel, "bowl.obj": bowl, "plate.obj": plate, "cup.obj": cup,
          "fork.obj": fork, "knife.obj": knife, "spoon.obj": spoon, "broom.obj": broom,
          "dust_pan.obj": dust_pan}


# -- sounds -------------------------------------------------------------------------
def _envelope(seconds: float, decay: float) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(int(seconds * RATE)) / RATE
    attack = np.minimum(t / 0.002, 1.0)
    return t, attack * np.exp(-t / decay)


def _partials(seconds: float, decay: float, partials: list[tuple[float, float, float]]
              ) -> np.ndarray:
    """Sum of (frequency Hz, amplitude, decay factor) partials under one envelope."""
    t, env = _envelope(seconds, decay)
    out = np.zeros_like(t)
    for freq, amp, factor in partials:
        out += amp * np.sin(2 * np.pi * freq * t) * np.exp(-t / (decay * factor))
    return out * env


def _noise(seconds: float, decay: float, seed: int, smooth: int) -> np.ndarray:
    t, env = _envelope(seconds, decay)
    noise = np.random.default_rng(seed).standard_normal(len(t))
    if smooth > 1:
        noise = np.convolve(noise, np.ones(smooth) / smooth, mode="same")
    return noise * env


def sounds() -> dict[str, np.ndarray]:
    return {
        "ceramic.wav": _partials(0.35, 0.06, [(1250, 1.0, 1.0), (2710, 0.5, 0.6),
                                              (4400, 0.25, 0.4)])
        + 0.3 * _noise(0.35, 0.01, 1, 2),
        "clink.wav": _partials(0.4, 0.09, [(3200, 1.0, 1.0), (5100, 0.6, 0.7),
                                           (7900, 0.3, 0.5)]),
        "glass.wav": _partials(0.6, 0.15, [(2100, 1.0, 1.0), (4950, 0.4, 0.6)]),
        "brush.wav": _noise(0.3, 0.12, 2, 6),
        "cardboard.wav": _noise(0.2, 0.03, 3, 12) + _partials(0.2, 0.03, [(180, 0.6, 1.0)]),
        "bump.wav": _partials(0.3, 0.05, [(90, 1.0, 1.0), (210, 0.5, 0.6)])
        + 0.4 * _noise(0.3, 0.02, 4, 20),
    }


def write(out: Path) -> list[Path]:
    written = []
    models, noises = out / "models", out / "sounds"
    models.mkdir(parents=True, exist_ok=True)
    noises.mkdir(parents=True, exist_ok=True)
    for name, make in MODELS.items():
        path = models / name
        path.write_text(trimesh.exchange.obj.export_obj(make(), include_normals=False,
                                                        include_texture=False, digits=4))
        written.append(path)
    for name, samples in sounds().items():
        path = noises / name
        peak = float(np.abs(samples).max()) or 1.0
        soundfile.write(path, (0.8 * samples / peak).astype(np.float32), RATE,
                        subtype="PCM_16")
        written.append(path)
    return written


def main() -> None:
    write_cli(__doc__.splitlines()[0], write)


if __name__ == "__main__":
    main()
