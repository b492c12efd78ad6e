"""pymunk backend: joints the plane can only approximate, motors, and joint lifetimes."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from components import Joint
from engine.physics.backend import WorldSettings
from engine.physics.pymunk2d import PymunkBackend

LOGGER = "colosseum.physics.pymunk"

# a failing pymunk callback is only printed by cffi: make it fail the test
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")


@pytest.fixture
def backend() -> PymunkBackend:
    b = PymunkBackend()
    b.configure(WorldSettings(auto_sleep=False))
    return b


@pytest.mark.parametrize(("kind", "words"), [
    ("ball", "ball joint"), ("universal", "universal joint"), ("hinge2", "hinge2")])
def test_approximated_joints_warn_once_per_joint_and_still_pivot(kit,
        backend: PymunkBackend, caplog: pytest.LogCaptureFixture, kind: str, words: str) -> None:
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        for key in (1, 2):
            kit.add(backend, key, kit.sphere(), (float(key), 0.0, 1.0))
            backend.add_joint(10 + key, Joint(kind=kind, body_a=key, anchor=(key, 0.0, 2.0),
                                              axis=(0.0, 0.0, 1.0), axis2=(0.0, 1.0, 0.0),
                                              id=f"j{key}"))
        for _ in range(60):
            backend.step(1 / 60)
    mine = [r.getMessage() for r in caplog.records if words in r.getMessage()]
    assert sorted(m.split(":")[0] for m in mine) == ["joint j1", "joint j2"]
    # a pivot keeps the body hanging 1 m under its anchor
    assert np.linalg.norm(kit.row(backend, 1)["position"] - [1.0, 0.0, 2.0]) == pytest.approx(1.0,
                                                                                       abs=1e-3)


def test_hinge_axis_off_y_is_reported(kit, backend: PymunkBackend,
                                      caplog: pytest.LogCaptureFixture) -> None:
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 1.0))
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        backend.add_joint(10, Joint(kind="hinge", body_a=1, anchor=(0.0, 0.0, 2.0),
                                    axis=(0.0, 0.0, 1.0), id="door"))
    assert any(r.getMessage().startswith("joint door: hinge axis") for r in caplog.records)


def test_minus_y_axis_flips_the_angle(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, kit.box((1.0, 0.1, 0.1)), (0.5, 0.0, 2.0))
    kit.add(backend, 2, kit.box((1.0, 0.1, 0.1)), (0.5, 3.0, 2.0))
    backend.add_joint(10, kit.hinge(1, (0.0, 0.0, 2.0)))
    backend.add_joint(11, Joint(kind="hinge", body_a=2, anchor=(0.0, 3.0, 2.0),
                                axis=(0.0, -1.0, 0.0)))
    for _ in range(20):
        backend.step(1 / 60)
    (a, ra), (b, rb) = backend.joint_state(10), backend.joint_state(11)
    assert a > 0.05 and b == pytest.approx(-a) and rb == pytest.approx(-ra)


def test_slider_motor_reaches_speed_with_bounded_force(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, kit.box((0.2, 0.2, 0.2), mass=2.0), (0.0, 0.0, 1.0))
    backend.add_joint(10, Joint(kind="slider", body_a=1, axis=(1.0, 0.0, 0.0),
                                motor_velocity=0.5, motor_max_force=10.0))
    for _ in range(60):
        backend.step(1 / 60)
    pos, rate = backend.joint_state(10)
    assert rate == pytest.approx(0.5, rel=1e-6)
    assert kit.row(backend, 1)["position"][2] == pytest.approx(1.0, abs=1e-3)  # held on the axis
    backend.set_motor(10, -0.5, 1.0)  # 1 N on 2 kg: 0.5 m/s² toward the new target
    for _ in range(30):
        backend.step(1 / 60)
    assert backend.joint_state(10)[1] == pytest.approx(0.5 - 0.5 * 0.5, abs=0.02)


def test_removing_a_body_removes_its_joints(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 1.0))
    kit.add(backend, 2, kit.sphere(), (1.0, 0.0, 1.0))
    backend.add_joint(10, Joint(kind="fixed", body_a=1, body_b=2))
    backend.remove_body(2)
    backend.step(1 / 60)
    with pytest.raises(KeyError, match="no joint with key 10"):
        backend.joint_state(10)
    assert len(backend._space.constraints) == 0


def test_bad_joints_raise_clear_errors(kit, backend: PymunkBackend) -> None:
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 1.0))
    with pytest.raises(KeyError, match="no body with key 5"):
        backend.add_joint(10, Joint(kind="hinge", body_a=1, body_b=5))
    with pytest.raises(ValueError, match="unknown kind 'weld'"):
        backend.add_joint(10, Joint(kind="weld", body_a=1, id="w"))
    with pytest.raises(ValueError, match="slider axis"):
        backend.add_joint(10, Joint(kind="slider", body_a=1, axis=(0.0, 1.0, 0.0)))


def test_a_joint_made_from_its_reference_poses_is_the_joint_first_made(kit) -> None:
    """A saved joint comes back anchored where it was first made, not where it is now."""
    first = PymunkBackend()
    kit.add(first, 1, kit.box((1.0, 0.1, 0.1)), (0.5, 0.0, 2.0))
    kit.add(first, 2, kit.box((1.0, 0.1, 0.1)), (1.5, 0.0, 2.0))
    reference = ((0.5, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0), (1.5, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0))
    limited = Joint(kind="hinge", body_a=2, body_b=1, anchor=(1.0, 0.0, 2.0),
                    axis=(0.0, 1.0, 0.0), low=-0.5, high=0.5)
    first.add_joint(10, kit.hinge(1, (0.0, 0.0, 2.0)))
    first.add_joint(11, limited)
    for _ in range(45):  # the chain swings down and bends at its limited middle hinge
        first.step(1 / 60)
    state = first.read_state()
    again = PymunkBackend()
    for i, key in enumerate(state.keys):
        kit.add(again, int(key), kit.box((1.0, 0.1, 0.1)), tuple(state.position[i]),
                state.orientation[i])
    again.add_joint(10, Joint(**{**_fields(kit.hinge(1, (0.0, 0.0, 2.0))),
                                 "reference": (reference[0], None)}))
    again.add_joint(11, Joint(**{**_fields(limited), "reference": reference[::-1]}))
    for key in (10, 11):
        assert again.joint_state(key)[0] == pytest.approx(first.joint_state(key)[0], abs=1e-12)
        for made, remade in zip(first._joints[key].constraints, again._joints[key].constraints,
                                strict=True):
            for side in ("anchor_a", "anchor_b"):
                if hasattr(made, side):
                    assert tuple(getattr(remade, side)) == pytest.approx(
                        tuple(getattr(made, side)), abs=1e-12)
    np.testing.assert_array_equal(again.read_state().position, state.position)  # put back


def _fields(joint: Joint) -> dict:
    return {name: getattr(joint, name) for name in Joint.__dataclass_fields__}
