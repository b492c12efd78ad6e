"""KHR_physics_rigid_bodies as the extension says it (issue 31), each checked on the public
samples in ../shared/gltf-physics/khr and on a scene of the engine's own where a number
needs an exact check: zero inertia per axis is infinite, gravityFactor scales gravity,
a kinematic body keeps its velocities. (Combine modes, collision filters, joint limits
and drives: test_khr_conformance.py, on the conformance scenes.)
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from components import Name, Transform
from engine.rotation import quat_to_matrix
from tests.interchange.conformance import SHARED, run

KHR = SHARED / "khr"


def sample(name: str) -> Path:
    path = KHR / name
    if not path.is_file():
        pytest.skip(f"{path} is not here (../shared/gltf-physics)")
    return path


# -- zero inertia: infinite ---------------------------------------------------------------

def test_motion_properties_sample_imports_without_errors_and_the_box_never_turns(tmp_path):
    """MotionProperties.glb: InfInertiaBox (inertiaDiagonal [0 0 0]) falls onto the slope and
    never turns; the wheel of mass 0 and inertia [0 1 0] is imported without an error."""
    trace = run(sample("MotionProperties.glb"), tmp_path, 3.0)
    assert trace.errors == 0
    box = trace.index("InfInertiaBox")
    assert trace.position[0, box, 2] - trace.position[-1, box, 2] > 1.0  # it fell
    assert max(trace.turned(box, f) for f in range(len(trace.times))) < 0.5


SPIN = """\
World {{ Gravity [0 0 0] }}
Object {{
  ID "top"
  Size [1 0.5 0.25]
  PhysicalAttributes {{ Mass 1 Inertia {inertia} Geometry {{ Primitive "box" }} }}
}}
"""


@pytest.mark.parametrize("inertia, free", [("[0 0 0]", None), ("[0 1 0]", 1),
                                           ("[1 0 0]", 0), ("[0 0 0.5]", 2)])
def test_a_zero_moment_locks_its_axis(tmp_path: Path, inertia: str, free: int | None) -> None:
    """A body of Inertia with zeros, pushed by a torque about every axis: it turns about
    the axes of finite moments only (to 0.01 degrees), as fast as their moment says."""
    from app.scene_loading import content_engine
    from engine.physics.commands import ApplyTorque

    (tmp_path / "main.scene").write_text(SPIN.format(inertia=inertia))
    engine = content_engine(tmp_path)
    try:
        (entity, _), = engine.world.get_component(Name)
        for _ in range(50):
            engine.physics.push(ApplyTorque(entity, (0.1, 0.1, 0.1)))
            engine.run(frames=1)
        t = engine.world.component_for_entity(entity, Transform)
        turn = quat_to_matrix(np.asarray(t.orientation, float))
        angle = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(turn) - 1) / 2))))
        if free is None:
            assert angle < 0.01
        else:
            axis = np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0],
                             turn[1, 0] - turn[0, 1]])
            axis /= np.linalg.norm(axis)
            assert abs(axis[free]) > 0.99999
            moment = [float(x) for x in inertia.strip("[]").split()][free]
            time = engine.time
            expected = math.degrees(0.5 * 0.1 / moment * time ** 2)  # from rest, torque 0.1
            assert angle == pytest.approx(expected, rel=0.05)
    finally:
        engine.close()


# -- gravityFactor ----------------------------------------------------------------------

FALL = """\
World {{ Gravity [0 0 -9.81] TimeStep 0.01 }}
Object {{
  ID "ball"
  Position [0 0 10]
  Size [0.2]
  PhysicalAttributes {{ Mass 1 GravityFactor {factor} Geometry {{ Primitive "sphere" }} }}
}}
"""


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
@pytest.mark.parametrize("factor", [0.5, -0.5, 2.0, 1.0])
def test_gravity_factor_scales_gravity(tmp_path: Path, backend: str, factor: float) -> None:
    """A ball falls (or rises) 1 s at the factor times g: z = 10 - factor g t^2 / 2."""
    pytest.importorskip("engine.physics.ode3d" if backend == "ode" else "pymunk")
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import resolve
    from systems import create_engine

    (tmp_path / "main.scene").write_text(FALL.format(factor=factor))
    scene = load_content_scene(resolve(tmp_path))
    config = EngineConfig(content_dir=tmp_path, fast=True, headless=True)
    scene.configure(config, backend=backend)
    engine = create_engine(config)
    try:
        scene.instantiate(engine)
        engine.run(seconds=1.0)
        (entity, _), = engine.world.get_component(Name)
        z = float(engine.world.component_for_entity(entity, Transform).position[2])
        # to the integrators' error: 1 % of the drop at 100 steps
        assert 10 - z == pytest.approx(factor * 9.81 * engine.time ** 2 / 2, rel=0.015)
    finally:
        engine.close()


def test_balloons_rise(tmp_path: Path) -> None:
    """MotionProperties.glb's four balloons (gravityFactor -0.5) go up at about half g
    (they start touching one another, so each a little more or less)."""
    trace = run(sample("MotionProperties.glb"), tmp_path, 0.5)
    balloons = [i for i, n in enumerate(trace.names) if n.startswith("Balloon")]
    assert len(balloons) == 4
    rises = [trace.position[-1, i, 2] - trace.position[0, i, 2] for i in balloons]
    free = 0.5 * 9.81 * trace.times[-1] ** 2 / 2
    assert min(rises) > 0.5 * free and float(np.mean(rises)) == pytest.approx(free, rel=0.2)


# -- kinematic velocities ---------------------------------------------------------------

def test_a_kinematic_body_keeps_its_angular_velocity(tmp_path: Path) -> None:
    """WaterWheel's Archimedes screw is kinematic with angularVelocity [0 -6 0] (node axes,
    glTF): it turns at 6 rad/s about its centre of mass (its node's origin, 1 mm off it,
    circles), whatever the balls do."""
    trace = run(sample("WaterWheel/WaterWheel.gltf"), tmp_path, 0.5)
    screw = trace.index("ArchimedesScrew_Insert.001")
    assert trace.kinds[screw] == "kinematic"
    assert np.abs(trace.position[:, screw] - trace.position[0, screw]).max() < 2e-3
    for frame in (10, 20, 40):
        assert trace.turned(screw, frame) == pytest.approx(
            math.degrees(6.0 * trace.times[frame]) % 360, rel=1e-3)


# -- a joint that holds only rotation -------------------------------------------------------

ALIGN = """\
World {{ Gravity [0 0 -9.81] }}
Object {{
  ID "box"
  Position [0 0 10]
  Size [1 0.5 0.25]
  PhysicalAttributes {{ Mass 1 Geometry {{ Primitive "box" }} }}
}}
Joint {{ Type "Align" Bodies ["box"] }}
"""


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_an_align_joint_holds_the_turn_and_leaves_the_fall(tmp_path: Path, backend: str):
    """KHR joints that lock the angular axes only (Robot_skinned has two) are Align joints:
    a torque about every axis turns the body not at all, gravity moves it freely."""
    pytest.importorskip("engine.physics.ode3d" if backend == "ode" else "pymunk")
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import resolve
    from engine.physics.commands import ApplyTorque
    from systems import create_engine

    (tmp_path / "main.scene").write_text(ALIGN.format())
    scene = load_content_scene(resolve(tmp_path))
    config = EngineConfig(content_dir=tmp_path, fast=True, headless=True)
    scene.configure(config, backend=backend)
    engine = create_engine(config)
    try:
        scene.instantiate(engine)
        (entity, _), = [(e, n) for e, n in engine.world.get_component(Name) if n.id == "box"]
        for _ in range(60):
            engine.physics.push(ApplyTorque(entity, (1.0, 1.0, 1.0)))
            engine.run(frames=1)
        t = engine.world.component_for_entity(entity, Transform)
        assert abs(float(np.asarray(t.orientation) @ np.array([1.0, 0, 0, 0]))) > 1 - 1e-6
        assert 10 - float(t.position[2]) == pytest.approx(9.81 * engine.time ** 2 / 2,
                                                          rel=0.02)
    finally:
        engine.close()
