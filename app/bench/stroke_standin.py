"""A stand-in for the stroke simulator's apartment, for ``colosseum bench stroke`` until
content/stroke exists: rooms, furniture and shelves of everyday things (about 2,000 objects
in view, of boxes, cylinders, spheres and capsules in many sizes and colours), a hall behind
the viewer holding 600 more, and about 300 small dynamic bodies (crumbs, cups, plates,
cutlery) that fall, settle and sleep. The view pans slowly, as a seated user looks around.

``python -m app.bench.stroke_standin DIR`` writes it (``main.scene`` and a camera script) into
DIR; the bench writes it into a temporary folder.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

#: Eye height of a seated wheelchair user (m).
EYE_HEIGHT = 1.2

_CAMERA_SCRIPT = """-- look around slowly, as a seated user does: 40 degrees each way over 12 s
local eye = {0, -3.2, 1.2}
function onUpdate(dt)
  local a = math.rad(40) * math.sin(2 * math.pi * time() / 12)
  setCamera{position = eye, lookAt = {eye[1] + 4 * math.sin(a), eye[2] + 4 * math.cos(a), 0.9}}
end
"""


class _Writer:
    """Scene text, one Object per call."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.lines: list[str] = []
        self.count = 0
        self.dynamic = 0

    def colour(self, lo: float = 0.25, hi: float = 0.95) -> str:
        r, g, b = self.rng.uniform(lo, hi, 3)
        return f"[{r:.3f} {g:.3f} {b:.3f}]"

    def thing(self, kind: str, position: tuple[float, float, float], size: tuple[float, ...],
              colour: str | None = None, mass: float | None = None) -> None:
        x, y, z = position
        dims = " ".join(f"{s:.4f}" for s in size)
        visual = (f'VisualAttributes {{ Geometry {{ Primitive "{kind}" }} '
                  f'Color {colour or self.colour()} }}')
        if mass is not None:
            body = (f' PhysicalAttributes {{ Mass {mass:.4f} Material "things" '
                    f'Geometry {{ Primitive "{kind}" }} }}')
            self.dynamic += 1
        else:
            body = " Dynamic 0"
        self.lines.append(f"Object {{ Position [{x:.4f} {y:.4f} {z:.4f}] Size [{dims}]{body}\n"
                          f"  {visual} }}")
        self.count += 1

    def solid(self, position: tuple[float, float, float], size: tuple[float, float, float],
              colour: str) -> None:
        """Static furniture or a wall: drawn and collided with."""
        x, y, z = position
        dims = " ".join(f"{s:.4f}" for s in size)
        self.lines.append(
            f"Object {{ Position [{x:.4f} {y:.4f} {z:.4f}] Size [{dims}] Dynamic 0\n"
            f"  VisualAttributes {{ Geometry {{ Primitive \"box\" }} Color {colour} }}\n"
            f"  PhysicalAttributes {{ Material \"things\" Geometry {{ Primitive \"box\" }} }} }}")
        self.count += 1


def _shelf_unit(w: _Writer, x0: float, y: float, width: float, shelves: int,
                per_shelf: int, kinds: tuple[str, ...]) -> None:
    """A shelf unit against a wall (facing -Y), its boards filled with things."""
    wood = "[0.55 0.4 0.25]"
    height = 0.4 * shelves
    w.solid((x0 + width / 2, y, height / 2), (width, 0.05, height), wood)  # back
    for s in range(shelves):
        z = 0.4 * s + 0.02
        w.solid((x0 + width / 2, y - 0.15, z), (width, 0.3, 0.03), wood)
        for i in range(per_shelf):
            x = x0 + (i + 0.5) * width / per_shelf
            kind = kinds[(s * per_shelf + i) % len(kinds)]
            if kind == "box":  # a book
                h = w.rng.uniform(0.18, 0.32)
                size = (0.8 * width / per_shelf, w.rng.uniform(0.15, 0.24), h)
            elif kind == "cylinder":  # a jar or a cup
                h = w.rng.uniform(0.08, 0.25)
                size = (w.rng.uniform(0.03, 0.9 * width / per_shelf), h)
            elif kind == "capsule":  # a bottle
                h = w.rng.uniform(0.15, 0.3)
                size = (0.04, h - 0.04)
            else:  # a ball or a fruit
                h = w.rng.uniform(0.03, 0.9 * width / per_shelf)
                size = (h,)
            w.thing(kind, (x, y - 0.15, z + 0.015 + h / 2), size)


def standin_scene(rng: np.random.Generator | None = None) -> tuple[str, int, int]:
    """The stand-in's main.scene text; returns (text, objects, dynamic bodies). The rooms
    are written in this order (the random generator's draws follow it)."""
    w = _Writer(rng or np.random.default_rng(16))
    wall = "[0.88 0.86 0.8]"
    # rooms: a 10 x 8 m flat, the viewer in the hall at y = -3.2 looking toward +Y
    w.solid((0, 4, 1.3), (10, 0.1, 2.6), wall)
    w.solid((-5, 0, 1.3), (0.1, 8, 2.6), wall)
    w.solid((5, 0, 1.3), (0.1, 8, 2.6), wall)
    w.solid((-3, -2, 1.3), (4, 0.1, 2.6), wall)  # hall wall with a 2 m doorway
    w.solid((3, -2, 1.3), (4, 0.1, 2.6), wall)
    w.solid((0.5, 1.5, 1.3), (0.1, 5, 2.6), wall)  # kitchen | living room
    # floor tiles in the kitchen and living room
    for i in range(20):
        for j in range(12):
            w.thing("box", (-4.75 + 0.5 * i, -1.75 + 0.5 * j, 0.005), (0.49, 0.49, 0.01),
                    colour=w.colour(0.5, 0.7))
    _living_room(w)
    _kitchen(w)
    _breakfast(w)
    _crumbs_and_plants(w)
    # the hall behind the viewer: a shoe rack and boxes (out of view)
    w.solid((0, -4.05, 1.3), (10, 0.1, 2.6), wall)
    for i in range(600):
        row, layer = (i // 30) % 4, i // 120
        position = (-4.5 + 0.3 * (i % 30), -3.55 - 0.13 * row, 0.1 + 0.25 * layer)
        w.thing("box" if i % 3 else "cylinder", position,
                (0.25, 0.12, 0.1) if i % 3 else (0.1, 0.2))
    header = [
        "// Stand-in for content/stroke (app/bench/stroke_standin.py): an apartment of "
        f"{w.count} objects, {w.dynamic} dynamic.",
        "World { TimeStep 0.01 }",
        'Material { ID "things" Friction 0.6 Bounce 0.05 }',
        f'Camera {{ ID "eyes" Position [0 -3.2 {EYE_HEIGHT}] LookAt [0 1 0.9] Fov 70 }}',
        'Light { Type "directional" Direction [0.4 0.6 -1] Intensity 0.9 }',
        'Object { ID "floor" Dynamic 0 VisualAttributes { Geometry { Primitive "plane" } '
        'Color [0.5 0.45 0.4] }',
        '  PhysicalAttributes { Material "things" Geometry { Primitive "plane" } } }',
        'Script "scripts/look_around.lua"',
    ]
    return "\n".join(header + w.lines) + "\n", w.count + 1, w.dynamic


def _living_room(w: _Writer) -> None:
    """x < 0.5: three bookshelves, a sofa, pictures."""
    for k in range(3):
        _shelf_unit(w, -4.7 + 1.5 * k, 3.85, 1.4, 5, 22, ("box",))
    for k in range(4):
        w.solid((-4 + k * 0.6, 1.2, 0.25), (0.6, 0.9, 0.5), "[0.3 0.35 0.5]")
    for i in range(30):
        w.thing("box", (-4.95 + 0.01, -1.5 + 0.18 * i, 1.6 + 0.3 * (i % 3)), (0.02, 0.14, 0.2))


def _kitchen(w: _Writer) -> None:
    """x > 0.5: a counter with drawers, wall shelves of jars, cups and bottles."""
    w.solid((2.75, 3.65, 0.45), (4.4, 0.6, 0.9), "[0.75 0.75 0.72]")
    for i in range(11):
        w.thing("box", (0.75 + 0.4 * i, 3.34, 0.6), (0.36, 0.02, 0.18), colour="[0.6 0.6 0.58]")
    for k in range(3):
        _shelf_unit(w, 0.7 + 1.45 * k, 3.95, 1.4, 4, 24, ("cylinder", "capsule", "sphere"))


def _breakfast(w: _Writer) -> None:
    """A dining table with four chairs in the kitchen, laid for breakfast (dynamic)."""
    w.solid((2.5, 1.0, 0.73), (1.4, 0.9, 0.04), "[0.6 0.42 0.26]")
    for dx, dy in ((-0.6, -0.4), (0.6, -0.4), (-0.6, 0.4), (0.6, 0.4)):
        w.solid((2.5 + dx, 1.0 + dy, 0.36), (0.05, 0.05, 0.71), "[0.5 0.35 0.2]")
    for dx in (-0.45, 0.45):
        for dy in (-0.75, 0.75):
            w.solid((2.5 + dx, 1.0 + dy, 0.45), (0.42, 0.42, 0.04), "[0.5 0.35 0.2]")
            w.solid((2.5 + dx, 1.0 + dy * 1.27, 0.7), (0.42, 0.04, 0.5), "[0.5 0.35 0.2]")
    for i in range(8):  # cups, plates, bowls and cutlery on the table
        x, y = 2.0 + 0.15 * i, 0.75 + 0.5 * (i % 2)
        w.thing("cylinder", (x, y, 0.8), (0.08, 0.1), mass=0.3)
        w.thing("cylinder", (x, y + 0.12, 0.76), (0.22, 0.015), mass=0.4)
        w.thing("sphere", (x + 0.05, y - 0.12, 0.82), (0.07,), mass=0.1)
        w.thing("box", (x - 0.06, y + 0.1, 0.76), (0.015, 0.18, 0.004), mass=0.04)
        w.thing("box", (x + 0.06, y + 0.1, 0.76), (0.015, 0.18, 0.004), mass=0.04)
    for i in range(2):  # cereal packages
        w.thing("box", (2.9 + 0.15 * i, 1.3, 0.91), (0.07, 0.19, 0.3), mass=0.5)


def _crumbs_and_plants(w: _Writer) -> None:
    """Crumbs that settle and sleep, and plants by the windows."""
    # crumbs on the kitchen floor and table: small bodies that settle and sleep
    for _ in range(260):
        x, y = w.rng.uniform(1.0, 4.5), w.rng.uniform(-1.5, 2.5)
        d = w.rng.uniform(0.006, 0.015)
        sphere = w.rng.random() < 0.5
        w.thing("sphere" if sphere else "box", (x, y, 0.02 + d + w.rng.uniform(0, 0.2)),
                (d,) if sphere else (d, d, d), colour="[0.8 0.65 0.35]", mass=2e-4)
    # plants by the windows: pots and leaves
    for k in range(6):
        px, py = -4.5 + 1.6 * k, -1.7
        w.thing("cylinder", (px, py, 0.2), (0.3, 0.4), colour="[0.6 0.3 0.2]")
        for _ in range(70):
            a, r, h = w.rng.uniform(0, 2 * np.pi), w.rng.uniform(0, 0.25), w.rng.uniform(0.45, 1.3)
            w.thing("sphere", (px + r * np.cos(a), py + r * np.sin(a), h),
                    (w.rng.uniform(0.05, 0.12),), colour=w.colour(0.1, 0.6))


def write_standin(folder: Path) -> Path:
    """Write the stand-in content folder (main.scene, scripts/); returns the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "scripts").mkdir(exist_ok=True)
    text, _, _ = standin_scene()
    (folder / "main.scene").write_text(text, encoding="utf-8")
    (folder / "scripts" / "look_around.lua").write_text(_CAMERA_SCRIPT, encoding="utf-8")
    return folder


if __name__ == "__main__":
    out = write_standin(Path(sys.argv[1] if len(sys.argv) > 1 else "stroke_standin"))
    print(f"wrote {out}")
