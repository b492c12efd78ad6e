"""Ground following against the ground's own shape: a ramp, a plateau and steps down, on
ODE and on pymunk (in its X-Z plane), at several time steps; feet on a slope by IK."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import avatar_engine, avatars, content, entity, position

#: The course, along the walking axis s: flat to 1 m, a ramp rising 0.15 per metre to
#: 3 m (0.3 m high), a plateau to 4 m, a step 0.6 m deep half way down, flat on: two
#: steps down of 0.15 m.
RAMP = (1.0, 3.0, 0.15)
STEP = (4.0, 4.6, 0.15)
SMOOTHING = 0.05


def ground(s: float) -> float:
    if s < RAMP[0]:
        return 0.0
    if s < RAMP[1]:
        return RAMP[2] * (s - RAMP[0])
    if s < STEP[0]:
        return 0.3
    return STEP[2] if s < STEP[1] else 0.0


def course(backend: str) -> str:
    """The course as static boxes along Y (ODE) or X (pymunk's plane)."""
    angle = float(np.degrees(np.arctan(RAMP[2])))
    length = (RAMP[1] - RAMP[0]) / np.cos(np.radians(angle))
    t = 0.2  # thickness of the ramp slab
    mid = 0.5 * (RAMP[0] + RAMP[1]) + 0.5 * t * np.sin(np.radians(angle))
    mid_z = 0.15 - 0.5 * t * np.cos(np.radians(angle))
    blocks = [(mid, mid_z, length, t, angle), (3.5, 0.15, 1.0, 0.3, 0.0),
              (4.3, 0.075, 0.6, 0.15, 0.0)]
    out = ['Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" '
           '} } }']
    for i, (s, z, size_s, size_z, tilt) in enumerate(blocks):
        if backend == "pymunk":  # the plane is X-Z: the course runs along X, tilted about Y
            pos, size, turn = f"[{s} 0 {z}]", f"[{size_s} 2 {size_z}]", f"[0 {-tilt} 0]"
        else:
            pos, size, turn = f"[0 {s} {z}]", f"[2 {size_s} {size_z}]", f"[{tilt} 0 0]"
        out.append(f'Object {{ ID "block{i}" Dynamic 0 Position {pos} Orientation {turn} '
                   f'Size {size} PhysicalAttributes {{ Geometry {{ Primitive "box" }} }} }}')
    return "\n".join(out)


def walker(backend: str, start: float = 0.0, stop: float = 6.5) -> str:
    a, b = ((f"{start} 0 0", f"{stop} 0 0") if backend == "pymunk"
            else (f"0 {start} 0", f"0 {stop} 0"))
    heading = ("-90" if stop > start else "90") if backend == "pymunk" else (
        "0" if stop > start else "180")
    return (f'Avatar {{ ID "w" Model "models/walker.glb" Position [{a}] Orientation [0 0 '
            f'{heading}] Animation "Walk" Path [{a}  {b}] PathLoop 0 GroundFollow 1 '
            f'Smoothing {SMOOTHING} }}')


@pytest.mark.parametrize("dt", [1 / 60, 1 / 120])
def test_the_root_stays_within_a_centimetre_of_sloped_and_stepped_ground(
        tmp_path: Path, backend_name: str, dt: float):
    backend = backend_name
    if backend == "ballistic":
        pytest.skip("ballistic particles have no extent: no ground to stand on")
    folder = content(tmp_path, course(backend) + "\n" + walker(backend))
    axis = 0 if backend == "pymunk" else 1
    settle = 6 * SMOOTHING * 1.4  # metres walked while a step is being taken
    edges = [STEP[0], STEP[1]]
    checked = 0
    with avatar_engine(folder, backend=backend, dt=dt) as engine:
        last = None
        for _ in range(int(5.6 / dt)):
            engine.step()
            p = position(engine, "w")
            s, z = float(p[axis]), float(p[2])
            if s > 6.3:
                break
            since = [s - e for e in edges if s >= e]
            if not since or min(since) > settle:  # on the ramp, the plateau, a tread
                assert abs(z - ground(s)) < 0.01, (s, z, ground(s))
                checked += 1
            else:  # taking a step down: between the two heights, never past them
                before = ground(edges[len(since) - 1] - 1e-6)
                after = ground(edges[len(since) - 1] + 1e-6)
                assert min(before, after) - 0.01 < z < max(before, after) + 0.01, (s, z)
            if last is not None:  # smoothed: no jump of a whole step in one frame
                assert abs(z - last) < 0.075
            last = z
        assert s > 6.0  # it walked the whole course
    assert checked > 2.5 / (1.4 * dt)


def test_a_step_up_is_taken_over_the_smoothing_time_and_settles_on_it(tmp_path: Path):
    """Walking the course backwards: two steps up of 0.15 m, then a ramp down."""
    folder = content(tmp_path, course("ode") + "\n" + walker("ode", start=6.5, stop=0.0))
    dt = 1 / 120
    with avatar_engine(folder, dt=dt) as engine:
        heights = []
        for _ in range(int(2.2 / dt)):
            engine.step()
            p = position(engine, "w")
            heights.append((float(p[1]), float(p[2])))
    # crossing s = 4.6 (up 0.15): the root rises smoothly, and is on the tread 6 tau later
    crossed = next(i for i, (s, _) in enumerate(heights) if s < STEP[1])
    rise = [z for _, z in heights[crossed:crossed + 8]]
    assert all(b >= a - 1e-9 for a, b in zip(rise, rise[1:], strict=False))
    assert 0.0 < rise[0] < rise[1] < 0.15  # not at once
    settled = heights[crossed + int(6 * SMOOTHING / dt)]
    assert abs(settled[1] - ground(settled[0])) < 0.01


@pytest.mark.parametrize("ik", [True, False])
def test_foot_ik_puts_both_feet_on_a_slope(tmp_path: Path, ik: bool):
    """Standing across the ramp (facing +X, so one foot is uphill): with FootIK each ankle
    is as high over the ground under it as it is over flat ground; without, one floats."""
    legs = 'FootIK ["thigh.L" "shin.L" "foot.L" "thigh.R" "shin.R" "foot.R"]' if ik else ""
    folder = content(tmp_path, course("ode") + "\n" + (
        f'Avatar {{ ID "w" Model "models/walker.glb" Position [0 2 0.15] Orientation [0 0 -90]'
        f' Animation "Idle" GroundFollow 1 {legs} }}'
        '\nAvatar { ID "flat" Model "models/walker.glb" Position [1.5 -2 0] Animation "Idle" '
        'GroundFollow 1 }'))
    with avatar_engine(folder, dt=1 / 60) as engine:
        engine.run(frames=30)
        system = avatars(engine)
        w, flat = entity(engine, "w"), entity(engine, "flat")
        rest = system.bone_pose(flat, "foot.L")[0][2]  # an ankle's height on flat ground
        errors = []
        for foot in ("foot.L", "foot.R"):
            ankle = system.bone_pose(w, foot)[0]
            errors.append(abs(ankle[2] - ground(ankle[1]) - rest))
    if ik:
        assert max(errors) < 0.01, errors
    else:
        assert max(errors) > 0.01, errors  # the check can fail: the slope is felt
