"""pymunk backend: the side-view mapping (X–Z plane, Y kept, rotation about Y)."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from engine.physics.pymunk2d import PymunkBackend
from engine.physics.pymunk2d.planar import split_orientation
from engine.rotation import quat_multiply, quat_to_matrix

LOGGER = "colosseum.physics.pymunk"

# a failing pymunk callback is only printed by cffi: make it fail the test
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")


@pytest.fixture
def backend() -> PymunkBackend:
    return PymunkBackend()


def test_positive_pymunk_angle_turns_x_toward_z(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, kit.box(), (0.0, 0.0, 0.0))
    backend._bodies[1].body.angle = 0.3  # pymunk's counter-clockwise turn in the side view
    q = kit.row(backend, 1)["orientation"]
    np.testing.assert_allclose(quat_to_matrix(q) @ [1.0, 0.0, 0.0],
                               [math.cos(0.3), 0.0, math.sin(0.3)], atol=1e-12)


@pytest.mark.parametrize("phi", [-3.0, -0.7, 0.0, 0.4, 2.9])
def test_rotation_about_y_round_trips(kit, backend: PymunkBackend, phi: float) -> None:
    kit.add(backend, 1, kit.box(), (1.0, 2.5, -3.0), kit.quat_y(phi))
    backend.set_velocity(1, np.array([0.5, 0.0, -1.0]), np.array([0.0, 1.25, 0.0]))
    r = kit.row(backend, 1)
    assert abs(float(np.dot(r["orientation"], kit.quat_y(phi)))) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(r["position"], [1.0, 2.5, -3.0])
    np.testing.assert_allclose(r["linear"], [0.5, 0.0, -1.0])
    np.testing.assert_allclose(r["angular"], [0.0, 1.25, 0.0])


def test_split_orientation_rebuilds_any_quaternion(kit) -> None:
    rng = np.random.default_rng(5)
    for q in rng.normal(size=(50, 4)):
        q /= np.linalg.norm(q)
        theta, rest, _ = split_orientation(q)
        rebuilt = quat_multiply(kit.quat_y(-theta), rest)
        assert abs(float(np.dot(rebuilt, q))) == pytest.approx(1.0, abs=1e-12)


def test_y_is_kept_as_authored_while_falling(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, kit.sphere(), (0.0, 4.2, 1.0))
    for _ in range(30):
        backend.step(1 / 60)
    assert kit.row(backend, 1)["position"][1] == 4.2


def test_tilted_body_keeps_its_tilt_and_warns_once(kit, backend: PymunkBackend,
                                                   caplog: pytest.LogCaptureFixture) -> None:
    tilt = np.array([math.cos(0.2), math.sin(0.2), 0.0, 0.0])  # 0.4 rad about X
    q = quat_multiply(kit.quat_y(0.5), tilt)
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        kit.add(backend, 7, kit.box((1.0, 1.0, 0.2)), (0.0, 0.0, 3.0), q)
        backend.set_pose(7, np.array([0.0, 0.0, 3.0]), q)
        for _ in range(10):
            backend.step(1 / 60)
    assert abs(float(np.dot(kit.row(backend, 7)["orientation"], q))) == pytest.approx(1.0, abs=1e-9)
    messages = [r.getMessage() for r in caplog.records if r.name == LOGGER]
    assert len(messages) == 1
    assert "body 7" in messages[0] and "silhouette" in messages[0]


def test_out_of_plane_inputs_are_reported_once_per_body(kit,
        backend: PymunkBackend, caplog: pytest.LogCaptureFixture) -> None:
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 0.0))
    kit.add(backend, 2, kit.sphere(), (1.0, 0.0, 0.0))
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        for _ in range(3):
            backend.add_force(1, np.array([1.0, 5.0, 0.0]))
            backend.add_force(2, np.array([1.0, 5.0, 0.0]))
            backend.add_torque(1, np.array([1.0, 0.0, 0.0]))
            backend.step(1 / 60)
    messages = [r.getMessage() for r in caplog.records if r.name == LOGGER]
    assert sorted(m.split(":")[0] for m in messages) == ["body 1", "body 1", "body 2"]
    assert kit.row(backend, 1)["linear"][0] == pytest.approx(3 / 60, rel=1e-9)
