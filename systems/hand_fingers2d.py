"""The fingered hand on pymunk: a 2D hand in the world's X–Z plane (``Hand { Fingers 1 }``).

pymunk simulates the side view, so the tracked 26 joints are projected onto the X–Z
plane (at the tracked palm's Y when the hand's bones are made) and the hand is what the
plane can hold of them: the palm-only hand's body and six-DOF drive, and each finger's
three phalanges as capsules (segments in the plane) sized from the joints' radii and
the projected bone lengths, chained to the palm and to each other by pivots about Y with
rotary limits at the anatomical ranges (:data:`systems.hand_fingers.LIMITS`, flexion
positive, counted from the straight finger seen in the plane).

Each pivot is driven toward its tracked angle by a torque-bounded servo: the joint's
motor (a pymunk ``SimpleMotor`` through :class:`~engine.physics.commands.SetMotor`) runs at
the tracked flexion rate plus the remaining error over the hand drive's time constant,
with at most :data:`BONE_TORQUE` (:data:`HOLD_TORQUE` while the hand holds something), so
a blocked finger presses with a bounded force and never through. The bones share the
collision bit :data:`~systems.hand_fingers.HAND_BIT` with the palm: none collides with
another. Grasping by contact, its release and the deviation rule are the ODE hand's
(:mod:`systems.hand_fingers`), read from the contacts pymunk reports.

Where the hand is turned so that its fingers bend out of the plane, their projection is
what is simulated: a hand seen edge-on from the side (its thumb toward ±Y) is the one
this backend represents faithfully.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from components import Graspable, Joint, Name, Physical, Shape, Transform, Visual
from components.joint import JointKind
from components.physical import BodyKind
from engine.physics.commands import SetDriveLimits, SetMotor
from engine.rotation import quat_to_matrix
from services.input.events import HAND_JOINTS, HandJoints
from systems.hand_fingers import (
    ALONG_X,
    BONE_COLOR,
    BONE_MASS,
    BONES,
    ENDS,
    HAND_BIT,
    LIMITS,
    SKIN,
    STARTS,
    Fingers,
    world_joints,
)

if TYPE_CHECKING:
    from engine.app import Engine

#: Each joint's motor torque bound (N·m): a fingertip 5 cm out presses with up to ~6 N.
BONE_TORQUE = 0.3
#: The bound while the hand holds something (the palm's constraint holds it; fingers
#: pressing at full torque through the loop palm – finger – object would sink in).
HOLD_TORQUE = 0.08
#: The thumb's joints' range in the plane (radians): it bends across the palm, out of the
#: plane, so its projection turns past any anatomical range (its distal bone's seen
#: flexion reaches 2.7 in a fist) and is limited only short of a half turn.
THUMB_PLANAR = ((-2.9, 2.9),) * 3
#: How far (rad/s) a joint's wanted rate moves before its motor is told again.
DEADBAND = 0.02
#: The fastest a joint's servo turns it toward its target (rad/s).
MAX_SPIN = 30.0



def _split_orientation(q: np.ndarray) -> tuple[float, np.ndarray, bool]:
    """The plane's turn of ``q`` (pymunk2d.planar's; imported here, when a 2D hand runs:
    the pymunk package loads pymunk, which a 3D scene does not need)."""
    from engine.physics.pymunk2d.planar import split_orientation

    return split_orientation(q)

@dataclass(slots=True, eq=False)
class PlanarFingers(Fingers):
    """:class:`~systems.hand_fingers.Fingers` with what the plane's servo needs."""

    plane_y: float = 0.0  # the Y the bones (and the tracked joints) are put at
    flex_sign: float = 1.0  # +1 when the hand's flexion axis points along +Y
    flex: tuple[float, np.ndarray] | None = None  # the last tracked flexions (t, (15,))
    rates: np.ndarray = field(default_factory=lambda: np.zeros(15))
    still: bool = False  # whether the motors were stopped (the hand untracked)
    #: the rates (15,) and torque bound the motors were last told
    told: np.ndarray = field(default_factory=lambda: np.full(15, np.nan))
    told_torque: float = -1.0


def in_plane(p: np.ndarray, y: float) -> np.ndarray:
    """Joint positions (n, 3) projected onto the X–Z plane at ``y``."""
    out = np.array(p, dtype=float)
    out[:, 1] = y
    return out


def planar_bones(flat: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each bone's centre (15, 3), pymunk angle (15,: its +x from start to end joint, X
    toward Z) and length (15,), from projected joints."""
    along = flat[ENDS] - flat[STARTS]
    lengths = np.hypot(along[:, 0], along[:, 2])
    return (flat[STARTS] + flat[ENDS]) / 2, np.arctan2(along[:, 2], along[:, 0]), lengths


def about_y(theta: np.ndarray) -> np.ndarray:
    """Quaternions (n, 4) of pymunk angles θ: a turn by −θ about +Y (see planar.py)."""
    half = -0.5 * np.asarray(theta, dtype=float)
    zero = np.zeros_like(half)
    return np.stack([np.cos(half), zero, np.sin(half), zero], axis=1)


def flexions(theta: np.ndarray, palm: float, sign: float) -> np.ndarray:
    """Each joint's flexion (15,): its parent's angle minus its bone's (the parent of a
    finger's first bone is the palm), wrapped to ±π, signed so that bending toward the
    palm is positive."""
    parent = np.empty(15)
    parent[0::3] = palm
    parent[1::3], parent[2::3] = theta[0::3], theta[1::3]
    return sign * np.angle(np.exp(1j * (parent - theta)))


def _bone_body(radius: float, length: float) -> Physical:
    capsule = Shape("capsule", (radius, max(length, 1e-3)), rotation=ALONG_X)
    return Physical(kind=BodyKind.DYNAMIC, mass=BONE_MASS, shapes=[capsule], material=SKIN,
                    category=HAND_BIT, mask=0xFFFFFFFF & ~HAND_BIT, gravity=False,
                    can_sleep=False)


def build(engine: Engine, name: str, palm: int, sample: HandJoints, frame: Transform | None,
          drive: SetDriveLimits) -> PlanarFingers:
    """Spawn one hand's phalanges where its tracked ones project onto the plane, and the
    chain of limited pivots (their motors bounded by :data:`BONE_TORQUE`)."""
    p, q = world_joints(sample, frame)
    y = float(p[0, 1])
    centres, theta, lengths = planar_bones(in_plane(p, y))
    quats = about_y(theta)
    sign = 1.0 if quat_to_matrix(q[0])[1, 1] >= 0.0 else -1.0  # the hand's +y: flexion
    # a joint's limits count from the pose it is made in: the straight finger's are
    # moved there (a hand first seen half curled opens as far as an open one)
    made = flexions(theta, _split_orientation(q[0])[0], sign)
    radii = np.asarray(sample.radii, dtype=float)
    bones, chain, sizes = [], [], []
    finger_of: dict[int, str] = {}
    for i, (finger, start, end) in enumerate(BONES):
        label = f"{name} {HAND_JOINTS[start]}"
        radius = float(np.clip(min(radii[start], radii[end]) or 0.008, 0.004, 0.015))
        sizes.append(radius)
        body = _bone_body(radius, float(lengths[i]))
        bone = engine.spawn(Name(label), Transform(centres[i].copy(), quats[i].copy()), body,
                            Visual(shapes=[replace(body.shapes[0])], color=BONE_COLOR),
                            Graspable(False))
        parent = palm if i % 3 == 0 else bones[-1]
        low, high = THUMB_PLANAR[i % 3] if finger == "thumb" else \
            (limit - float(made[i]) for limit in LIMITS[finger][i % 3])
        anchor = (float(p[start, 0]), y, float(p[start, 2]))
        chain.append(engine.spawn(Name(f"{label} joint"), Joint(
            kind=JointKind.HINGE, body_a=bone, body_b=parent, anchor=anchor,
            axis=(0.0, sign, 0.0), low=low, high=high, motor_max_force=BONE_TORQUE,
            id=f"{label} joint")))
        bones.append(bone)
        finger_of[bone] = finger
    tau = drive.time_constant if drive.time_constant else 0.03
    return PlanarFingers(bones, chain, lengths, np.array(sizes), finger_of,
                         time_constant=tau, plane_y=y, flex_sign=sign)


def aim(engine: Engine, fingers: PlanarFingers, palm: int, sample: HandJoints,
        frame: Transform | None, now: float, stale_after: float) -> None:
    """Turn every joint's motor toward its tracked flexion for this sample: the tracked
    rate (from the sample before; zero once the samples stop coming) plus the error
    over the time constant, bounded by the torque of :data:`BONE_TORQUE` (or
    :data:`HOLD_TORQUE` while holding). Also notes the tracked tips and palm, projected."""
    p, q = world_joints(sample, frame)
    flat = in_plane(p, fingers.plane_y)
    centres, theta, _ = planar_bones(flat)
    target = flexions(theta, _split_orientation(q[0])[0], fingers.flex_sign)
    previous = fingers.flex
    if previous is not None and sample.timestamp > previous[0]:
        step = np.angle(np.exp(1j * (target - previous[1])))
        fingers.rates = step / (sample.timestamp - previous[0])
    if previous is None or sample.timestamp > previous[0]:
        fingers.flex = (sample.timestamp, target)
        fingers.sample = (sample.timestamp, centres, about_y(theta))
    if now - sample.timestamp > stale_after:
        fingers.rates[:] = 0.0
    fingers.tips = chain_tips(flat, theta, fingers.lengths)
    fingers.palm = flat[0]
    error = np.angle(np.exp(1j * (target - current_flexions(engine, fingers, palm))))
    spin = fingers.rates + np.clip(error / fingers.time_constant, -MAX_SPIN, MAX_SPIN)
    torque = HOLD_TORQUE if fingers.holding else BONE_TORQUE
    fingers.still = False
    tell(engine, fingers, np.clip(spin, -2 * MAX_SPIN, 2 * MAX_SPIN), torque)


def tell(engine: Engine, fingers: PlanarFingers, rates: np.ndarray, torque: float) -> None:
    """The motors whose rate moved more than :data:`DEADBAND` from what they were last
    told (all of them when the torque bound changes) get a :class:`SetMotor` each: a
    steady hand costs no commands, and what is left out the error term takes up (at most
    ``DEADBAND`` times the time constant: 0.6 mrad, a thirtieth of a degree)."""
    if torque != fingers.told_torque:
        changed = np.ones(15, dtype=bool)
    else:
        changed = ~(np.abs(rates - fingers.told) <= DEADBAND)
    if not changed.any():
        return
    fingers.told_torque = torque
    fingers.told[changed] = rates[changed]
    push = engine.physics.push
    for i in np.flatnonzero(changed).tolist():
        push(SetMotor(fingers.chain[i], float(rates[i]), torque))


def chain_tips(flat: np.ndarray, theta: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Where the hand's rigid chain puts its tips (5, 3) at the tracked angles: from each
    finger's tracked base along its bones' tracked directions, by the lengths they were
    made with. What the fingers are blocked from (a finger's deviation, a grip's width) is
    measured from these: the thumb's projection shortens as it bends out of the plane,
    which no rigid chain follows, and which is no block."""
    steps = lengths[:, None] * np.stack([np.cos(theta), np.zeros(15), np.sin(theta)], axis=1)
    return flat[STARTS[0::3]] + steps.reshape(5, 3, 3).sum(axis=1)


def still(engine: Engine, fingers: PlanarFingers) -> None:
    """An untracked hand's fingers hold still where they are (their motors stopped once)."""
    if fingers.still:
        return
    fingers.still = True
    fingers.rates[:] = 0.0
    fingers.told_torque = -1.0  # every motor told
    tell(engine, fingers, np.zeros(15), HOLD_TORQUE if fingers.holding else BONE_TORQUE)


def current_flexions(engine: Engine, fingers: PlanarFingers, palm: int) -> np.ndarray:
    """The physical joints' flexions (15,), from the bodies' poses the last step left."""
    world = engine.world
    quats = np.array([world.component_for_entity(b, Transform).orientation
                      for b in fingers.bones])
    theta = -2.0 * np.arctan2(quats[:, 2], quats[:, 0])
    palm_theta = _split_orientation(world.component_for_entity(palm, Transform).orientation)[0]
    return flexions(theta, palm_theta, fingers.flex_sign)


def tip_error(tracked: np.ndarray, physical: np.ndarray) -> np.ndarray:
    """Each fingertip's distance (5,) from its tracked one in the plane (X and Z)."""
    d = np.asarray(physical)[:, [0, 2]] - np.asarray(tracked)[:, [0, 2]]
    return np.hypot(d[:, 0], d[:, 1])


def planar_gap(sample: HandJoints, a: str, b: str) -> float:
    """The distance between two tracked joints seen in the plane (X and Z)."""
    p = np.asarray(sample.positions)
    i, j = HAND_JOINTS.index(a), HAND_JOINTS.index(b)
    return math.hypot(p[i, 0] - p[j, 0], p[i, 2] - p[j, 2])
