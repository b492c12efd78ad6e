"""Collada physics scenes imported and run: rigid bodies, shapes, materials, a constraint
with limits and a spring, world settings and extras; any up axis and unit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.bench import interchange_samples as samples_
from components import Physical, Visual
from engine.rotation import quat_to_euler
from engine.scene import load_spec
from tests.interchange.helpers import Run, import_scene

pytest.importorskip("engine.physics.ode3d")


def bodies(spec):
    return {es.id: c for es in spec.entities for c in es.components if isinstance(c, Physical)}


def test_the_scene_has_the_bodies_and_constraint_the_file_declares(models):
    spec = load_spec(import_scene(models / "physics.dae"))
    assert {oid: (p.kind, [s.kind for s in p.shapes]) for oid, p in bodies(spec).items()} == {
        "Ground": ("static", ["plane"]), "Slab": ("static", ["mesh"]),
        "Box": ("dynamic", ["box"]), "Ball": ("dynamic", ["sphere"]),
        "Pill": ("dynamic", ["capsule"]), "Can": ("dynamic", ["cylinder"]),
        "Gem": ("dynamic", ["hull"]), "Pebble": ("dynamic", ["sphere"]),
        "Post": ("static", ["box"]), "Door": ("dynamic", ["box"])}
    (hinge,) = spec.joints
    assert (hinge.id, hinge.joint.kind, hinge.bodies) == ("DoorHinge", "hinge", ("Door", None))
    assert (hinge.joint.low, hinge.joint.high) == pytest.approx(
        (math.radians(samples_.DOOR_LOW), math.radians(samples_.DOOR_HIGH)))
    assert spec.world.gravity == (0, 0, -9.81) and spec.time_step == 0.01
    assert bodies(spec)["Box"].mass == 2.0 and bodies(spec)["Ball"].material.friction == 0.9
    color = next(c for es in spec.entities if es.id == "Box" for c in es.components
                 if isinstance(c, Visual)).color
    assert color == (1.0, 0.0, 0.0, 1.0)  # typed into the node's <extra>


def test_any_up_axis_and_unit_give_the_same_scene(tmp_path):
    z_up = load_spec(import_scene(samples_.collada(tmp_path / "z.dae", "Z_UP", 1.0)))
    y_up_cm = load_spec(import_scene(samples_.collada(tmp_path / "y.dae", "Y_UP", 0.01)))
    a, b = bodies(z_up), bodies(y_up_cm)
    for oid in a:
        assert [s.kind for s in a[oid].shapes] == [s.kind for s in b[oid].shapes], oid
        for sa, sb in zip(a[oid].shapes, b[oid].shapes, strict=True):
            np.testing.assert_allclose(sa.size, sb.size, atol=1e-9, err_msg=oid)
    for ea, eb in zip(z_up.entities, y_up_cm.entities, strict=True):
        ta, tb = ea.components[1], eb.components[1]
        np.testing.assert_allclose(ta.position, tb.position, atol=1e-9)
        np.testing.assert_allclose(np.abs(ta.orientation @ tb.orientation), 1.0, atol=1e-9)
    ja, jb = z_up.joints[0].joint, y_up_cm.joints[0].joint
    np.testing.assert_allclose(ja.axis, jb.axis, atol=1e-9)
    np.testing.assert_allclose(ja.anchor, jb.anchor, atol=1e-9)


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
@pytest.mark.parametrize("dt", [0.01, 0.005])
def test_bodies_come_to_rest_on_the_imported_plane_and_slab(models, backend, dt):
    with Run.start(import_scene(models / "physics.dae"), backend, dt) as run:
        run.step(3.0)
        for oid, height in samples_.COLLADA_REST.items():
            assert run.position(oid)[2] == pytest.approx(height, abs=0.005), oid


@pytest.mark.parametrize("dt", [0.01, 0.005])
def test_the_hinged_door_turns_at_the_rate_momentum_allows_and_stops_at_its_limit(models, dt):
    """The door starts spinning about its centre at w0; the hinge, 0.45 m away, keeps its
    angular momentum about the hinge: w = w0 I_c / (I_c + m d^2)."""
    inertia = (0.8 ** 2 + 0.1 ** 2) / 12  # per kg, about the door's vertical axis
    rate = samples_.DOOR_SPIN * inertia / (inertia + 0.45 ** 2)
    with Run.start(import_scene(models / "physics.dae"), "ode", dt) as run:
        run.step(1.0)
        yaw = quat_to_euler(run.transform("Door").orientation)[2]
        assert yaw == pytest.approx(rate * 1.0, rel=0.02)
        run.step(4.0)
        yaw = quat_to_euler(run.transform("Door").orientation)[2]
        assert yaw == pytest.approx(samples_.DOOR_HIGH, abs=1.0)
