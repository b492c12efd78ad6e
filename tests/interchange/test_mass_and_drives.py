"""A model's centres of mass, inertia, position drives and springs (glTF and Collada)
imported into the scene's keys and run: each moves as physics says it should, on both
backends where the plane holds it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.bench import interchange_samples as samples_
from components import Joint, Physical
from engine.assets import Assets
from engine.interchange import import_model
from engine.rotation import quat_to_matrix
from engine.scene import load_spec
from tests.interchange.helpers import Run, import_scene

pytest.importorskip("engine.physics.ode3d")

BACKENDS = ["ode", "pymunk"]
GRAVITY = 9.81


def joint_angles(run: Run, joint: str, seconds: float, dt: float) -> list[float]:
    """The joint's position (rad or m) after each step for ``seconds``."""
    (entity,) = [e for e, j in run.engine.world.get_component(Joint) if j.id == joint]
    backend = run.engine.physics.backend
    out = []
    for _ in range(round(seconds / dt)):
        run.engine.step()
        out.append(backend.joint_state(entity)[0])
    return out


def period(values: list[float], dt: float, centre: float | None = None) -> float:
    """The mean time between upward crossings of ``centre`` (default: the middle)."""
    v = np.asarray(values)
    v = v - ((v.max() + v.min()) / 2 if centre is None else centre)
    k = np.flatnonzero((v[:-1] < 0) & (v[1:] >= 0))
    assert len(k) >= 3, "fewer than three upward crossings"
    return float(np.diff(k + v[k] / (v[k] - v[k + 1])).mean() * dt)


def bodies(spec) -> dict[str, Physical]:
    return {es.id: c for es in spec.entities for c in es.components if isinstance(c, Physical)}


def test_a_khr_motions_centre_of_mass_and_inertia_become_the_bodys_in_engine_axes(models):
    """glTF's centerOfMass 0.5 m below (its -Y) is -Z here; principal moments along glTF
    X Y Z are along X Z Y here, their axes turned 45 degrees about glTF Y (Z here)."""
    spec = load_spec(import_scene(models / "drives.glb"))
    weight = bodies(spec)["Weight"]
    np.testing.assert_allclose(weight.center_of_mass, (0, 0, -samples_.WEIGHT_REACH),
                               atol=1e-7)
    ix, iy, iz = samples_.WEIGHT_INERTIA
    np.testing.assert_allclose(weight.inertia, (ix, iz, iy))
    np.testing.assert_allclose(quat_to_matrix(np.asarray(weight.inertia_rotation)) @ [1, 0, 0],
                               (math.sqrt(0.5), math.sqrt(0.5), 0), atol=1e-6)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_pendulum_of_the_files_centre_and_inertia_swings_as_they_make_it(models, backend):
    """Its collider sits at the pivot; by the file its mass hangs 0.5 m below with 0.035
    kg m^2 about the hinge axis (0.04 and 0.03 turned 45 degrees): T = 2 pi sqrt((I + m r^2)
    / (m g r)), lengthened by theta0^2 / 16 for its 0.1 rad swing."""
    ix, _, iz = samples_.WEIGHT_INERTIA  # glTF X and Z: here X and Y, turned about Z
    moment = ix / 2 + iz / 2
    m, r = samples_.WEIGHT_MASS, samples_.WEIGHT_REACH
    expected = 2 * math.pi * math.sqrt((moment + m * r * r) / (m * GRAVITY * r))
    dt = 1 / 240
    with Run.start(import_scene(models / "drives.glb"), backend, dt) as run:
        angles = joint_angles(run, "WeightPivot", 5.0, dt)
    assert period(angles, dt) == pytest.approx(expected * (1 + samples_.WEIGHT_SWING ** 2 / 16),
                                               rel=0.003)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_position_drive_is_a_spring_at_sqrt_k_over_m(models, backend):
    dt = 1 / 240
    with Run.start(import_scene(models / "drives.glb"), backend, dt) as run:
        offsets = joint_angles(run, "CartRail", 4.0, dt)
    assert period(offsets, dt, samples_.DRIVE_TARGET) == pytest.approx(
        2 * math.pi * math.sqrt(samples_.DRIVE_MASS / samples_.DRIVE_STIFFNESS), rel=2e-3)
    # from rest at 0 toward 0.3 m: it swings to 0.6 m and back, undamped
    assert max(offsets) == pytest.approx(2 * samples_.DRIVE_TARGET, rel=0.01)


@pytest.mark.parametrize("backend", BACKENDS)
def test_an_acceleration_mode_position_drive_oscillates_at_sqrt_of_its_stiffness(models,
                                                                               backend):
    """In acceleration mode the stiffness is per unit of the flap's moment about its hinge
    (the importer multiplies it in): the period is 2 pi / sqrt(stiffness), whatever the
    flap weighs."""
    dt = 1 / 240
    with Run.start(import_scene(models / "drives.glb"), backend, dt) as run:
        angles = joint_angles(run, "FlapHinge", 4.0, dt)
    assert period(angles, dt) == pytest.approx(2 * math.pi / math.sqrt(
        samples_.FLAP_ACCELERATION), rel=3e-3)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_drive_that_only_damps_slows_its_joint_as_e_to_the_minus_d_t_over_i(models,
                                                                            backend):
    """A disc spinning about its axle, its drive's velocity target 0: w = w0 e^(-d t / I),
    I = m r^2 / 2 (it was told as not represented and the disc spun on)."""
    with Run.start(import_scene(models / "drives.glb"), backend, 1 / 240) as run:
        run.step(1.0)
        spin = float(np.linalg.norm(run.spin("Spinner")))
    inertia = samples_.SPINNER_MASS * samples_.SPINNER_RADIUS ** 2 / 2
    assert spin == pytest.approx(samples_.SPINNER_SPIN * math.exp(
        -samples_.SPINNER_DAMPING / inertia), rel=0.01)


def test_a_drive_toward_a_position_and_a_velocity_is_a_spring_toward_a_moved_target(tmp_path):
    """KHR's drive pulls k (x0 - x) + d (v0 - v): the spring -k (x - x0 - d v0 / k) - d v,
    exactly."""
    b = samples_.GltfBuilder()
    cart = samples_._body(b, "Cart", (0, 0, 1), b.shape("box", size=[0.2] * 3), (0.2,) * 3,
                          mass=1.0, gravityFactor=0)
    samples_._joint(b, "Rail", None, cart, (0, 0, 1), (0, 0, 0),
                    samples_._locked("linear", (1, 2)) + samples_._locked("angular", (0, 1, 2)),
                    [{"type": "linear", "mode": "force", "axis": 0, "stiffness": 20.0,
                      "damping": 4.0, "positionTarget": 0.1, "velocityTarget": 0.5,
                      "maxForce": 30.0}])
    path = b.write(tmp_path / "rail.gltf")
    (joint,) = import_model(path.name, path.name, Assets(tmp_path)).scene.joints
    assert joint.type == "Slider" and joint.motor_max_force == 0
    spring = joint.spring
    assert (spring.stiffness, spring.damping, spring.max_force) == (20, 4, 30)
    assert spring.target == pytest.approx(0.1 + 4.0 * 0.5 / 20.0)


def test_colladas_mass_frame_and_inertia_become_the_bodys(tmp_path):
    """``<mass_frame>`` places the centre of mass and turns the principal axes, in the
    body's frame; ``<inertia>`` gives the moments, in the file's unit squared."""
    path = samples_.collada(tmp_path / "heavy.dae", "Y_UP", 0.01)
    text = path.read_text().replace(
        '<rigid_body sid="Box-rb" name="Box"><technique_common>',
        '<rigid_body sid="Box-rb" name="Box"><technique_common><mass_frame><translate>10 0 0'
        '</translate><rotate>0 1 0 90</rotate></mass_frame><inertia>1000 2000 3000</inertia>')
    path.write_text(text)
    box = bodies(load_spec(import_scene(path)))["Box"]
    # 10 cm along the file's X is 0.1 m along X; its Y (up) is Z here, its Z is -Y
    np.testing.assert_allclose(box.center_of_mass, (0.1, 0, 0), atol=1e-9)
    np.testing.assert_allclose(box.inertia, (0.1, 0.3, 0.2))
    # a quarter turn about the file's up turns its X to its -Z: +Y here
    turn = quat_to_matrix(np.asarray(box.inertia_rotation))
    np.testing.assert_allclose(turn @ [1, 0, 0], (0, 1, 0), atol=1e-6)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("up, meter", [("Z_UP", 1.0), ("Y_UP", 0.01)])
def test_a_collada_linear_spring_oscillates_at_sqrt_k_over_m(tmp_path, backend, up, meter):
    """The cart's ``<spring><linear>``, written per file unit (N/cm in a centimetre file),
    pulls it toward 0.3 m."""
    path = samples_.collada_springs(tmp_path / "springs.dae", up, meter)
    dt = 1 / 240
    with Run.start(import_scene(path), backend, dt) as run:
        offsets = joint_angles(run, "CartRail", 4.0, dt)
    assert period(offsets, dt, samples_.CART_TARGET) == pytest.approx(
        2 * math.pi * math.sqrt(samples_.CART_MASS / samples_.CART_STIFFNESS), rel=2e-3)
    assert max(offsets) == pytest.approx(2 * samples_.CART_TARGET, rel=0.01)


@pytest.mark.parametrize("up, meter", [("Z_UP", 1.0), ("Y_UP", 0.01)])
def test_a_collada_angular_spring_oscillates_at_sqrt_k_over_i(tmp_path, up, meter):
    """The flap's ``<spring><angular>``: stiffness per degree (Collada's angles), target
    10 degrees; a rod hinged at one end, I = m (L^2 + w^2) / 12 + m (L / 2)^2. Its hinge is
    vertical, so only the 3D backend holds it."""
    path = samples_.collada_springs(tmp_path / "springs.dae", up, meter)
    dt = 1 / 240
    with Run.start(import_scene(path), "ode", dt) as run:
        angles = joint_angles(run, "FlapHinge", 6.0, dt)
    m, length = samples_.FLAP_MASS, samples_.FLAP_LENGTH
    inertia = m * (length ** 2 + 0.05 ** 2) / 12 + m * (length / 2) ** 2
    stiffness = samples_.FLAP_STIFFNESS * 180 / math.pi  # per radian
    assert period(angles, dt) == pytest.approx(2 * math.pi * math.sqrt(inertia / stiffness),
                                               rel=3e-3)
    assert max(angles) == pytest.approx(math.radians(2 * samples_.FLAP_TARGET), rel=0.01)


@pytest.mark.parametrize("backend,tolerance", [("ode", 0.03), ("pymunk", 0.05)])
def test_collada_friction_and_restitution_change_the_motion(tmp_path, backend, tolerance):
    """Blocks sliding at 3 m/s stop after v^2 / (2 mu g), mu the average of theirs and the
    floor's (Collada names no rule: the importer's); a ball dropped 1 m rebounds to e^2 m,
    e the average restitution; the one of restitution 0 stays down."""
    path = samples_.collada_springs(tmp_path / "springs.dae")
    dt = 1 / 240
    with Run.start(import_scene(path), backend, dt) as run:
        start = {oid: run.position(oid)[0] for oid in ("Slow", "Grip")}
        peak = dict.fromkeys(("Bouncy", "Dead"), 0.0)
        landed = dict.fromkeys(peak, False)
        for _ in range(round(2.0 / dt)):
            run.engine.step()
            for oid in peak:
                height = run.position(oid)[2] - 0.2  # the ball's bottom
                landed[oid] |= height < 0.01
                if landed[oid]:
                    peak[oid] = max(peak[oid], height)
        for oid, mu in (("Slow", samples_.DAE_SLOW), ("Grip", samples_.DAE_GRIP)):
            pair = (mu + samples_.DAE_FLOOR_FRICTION) / 2
            assert run.position(oid)[0] - start[oid] == pytest.approx(
                3.0 ** 2 / (2 * pair * GRAVITY), rel=tolerance), oid
    assert peak["Bouncy"] == pytest.approx((samples_.DAE_BOUNCY / 2) ** 2 * 1.0, rel=0.05)
    assert peak["Dead"] < 0.01
