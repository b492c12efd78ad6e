"""The fingered hand's bones (``Hand { Fingers 1 }``): built, driven, and read back.

A fingered hand is the palm-only hand (its body, its six-DOF drive toward a control body,
the deviation rule of section 5.4) plus, for each finger, three phalanges: capsules sized
from the tracked joints' radii and bone lengths (the thumb's metacarpal, proximal and
distal; each other finger's proximal, intermediate and distal, its metacarpal being the
palm). They are chained to the palm and to each other by joints with the anatomical
limits — a universal joint (flexion and spread) at the MCP and the thumb's CMC, hinges
at the PIP and DIP (the thumb's MCP and IP) — and each joint's own motor is a servo
toward its tracked angles (:class:`~engine.physics.commands.SetServos`: aimed each step
from the joint's angle then, the tracked rate fed forward, the torque bounded by
:data:`BONE_FORCE` at the fingertip, so a blocked finger pushes with a bounded force,
never through).
No control bodies and no drive rows of their own: the chain's joints carry the drive (a
hand is 15 fewer bodies and about a fifth fewer constraint rows than with a six-DOF
drive per bone). The hand's bones share the collision bit :data:`HAND_BIT` and none of
them collides with another (a fist is no collision).

Grasping by contact reads the step's contacts: an object is held when the thumb and an
opposing finger or the palm press it (each at least :data:`PRESS_FORCE`; the tracked grip
:data:`CLOSING` narrower than the physical one round it) with forces that oppose
— the line between the two presses lies inside both contacts' friction cones of
:data:`GRIP_MU` — and let go when the tracked grip opens :data:`RELEASE_BAND` wider than it
was when it took hold — as wide as the physical fingers round the object then — (the
hysteresis: a grip does not flicker at its edge). Holding uses
the palm-only hand's constraint (:meth:`systems.hands.Hands.attach`), so two hands and
several users hold one object as before.
"""

from __future__ import annotations

import math
from collections.abc import Container
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Graspable, Joint, Name, Physical, Shape, Transform, Visual
from components.joint import JointKind
from components.physical import BodyKind, MaterialProps
from engine.physics.commands import SetCollisionEnabled, SetDriveLimits, SetServos
from engine.rotation import matrices_to_quats, quat_to_matrix
from services.input.events import FINGERS, HAND_JOINTS, HandJoints
from services.input.hand_pose import ANATOMY
from systems import _fingers

if TYPE_CHECKING:
    from engine.app import Engine

#: The collision bit every fingered hand's palm and bones have, and none of them collides
#: with (a hand's bones never touch each other; hands pass through hands).
HAND_BIT = 1 << 30
#: A phalanx's mass (kg): heavy enough beside a 0.45 kg palm and a 0.3 kg cup for the
#: solver's 40 iterations, light enough that a finger stops on what it touches.
BONE_MASS = 0.1
#: The force (N) a fingertip presses with at most: each joint's servo torque is bounded
#: by it times the joint's distance to the tip along the finger (a blocked finger
#: pushes with at most this at its tip, whichever joint bends it).
BONE_FORCE = 8.0
#: The bound while the hand holds something (N): the object is held by the palm's
#: constraint, and fingers pressing it at full force through the loop palm – finger –
#: object – palm sink into it (the solver converges slowly round a loop).
HOLD_FORCE = 1.5
#: The fastest a joint's servo corrects its error (rad/s; the tracked rate comes on top).
MAX_SPIN = 30.0
#: Skin: the bones' friction.
SKIN = MaterialProps(name="skin", friction=1.0, density=1000.0)
#: The anatomical limits (radians, flexion positive) of each finger's three joints, and
#: of the spread (abduction) at its MCP or CMC.
LIMITS: dict[str, tuple[tuple[float, float], ...]] = {
    "thumb": ((-0.6, 1.2), (-0.3, 1.3), (-0.4, 1.6)),
    **{f: ((-0.4, 1.75), (-0.1, 2.0), (-0.2, 1.5)) for f in FINGERS[1:]},
}
SPREAD = 0.45
#: Grasping by contact: a press counts from this normal force (N); the friction
#: coefficient whose cone the opposing presses must lie in; how much wider (m) than it
#: was when it took hold the tracked grip opens before it lets go.
PRESS_FORCE = 0.3
GRIP_MU = 0.8
RELEASE_BAND = 0.008
#: How much narrower than the physical grip round an object the tracked one must be for
#: the presses to take hold (m): a hand closing on it, not opening off it.
CLOSING = 0.002
#: The capsule of a bone lies along its body's +x (a capsule's own axis is local +z).
ALONG_X = (math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0)
BONE_COLOR = (0.85, 0.7, 0.6, 1.0)
TIPS = tuple(HAND_JOINTS.index(f"{f}_tip") for f in FINGERS)


def bone_layout() -> list[tuple[str, int, int]]:
    """The 15 phalanges: (finger, joint at its start, joint at its end), base to tip."""
    out = []
    for finger in FINGERS:
        first = HAND_JOINTS.index(f"{finger}_metacarpal")
        start = first if finger == "thumb" else first + 1
        out += [(finger, start + k, start + k + 1) for k in range(3)]
    return out


BONES = bone_layout()
STARTS = np.array([s for _, s, _ in BONES])
ENDS = np.array([e for _, _, e in BONES])
BASES = np.arange(0, 15, 3)  # each finger's first bone (its joint: universal)
#: Each bone's parent bone as two joints (its vector: p[PARENT_B] - p[PARENT_A]): the
#: bone before it, or a finger's metacarpal (the thumb's first bone: its rest heading).
PARENT_A = np.array([STARTS[i - 1] if i % 3 else max(STARTS[i] - 1, 0) for i in range(15)])
PARENT_B = np.array([ENDS[i - 1] if i % 3 else STARTS[i] for i in range(15)])
#: Each bone's flexion axis and the thumb's rest heading, in the wrist's frame (right).
REST_Y = np.array([ANATOMY[f].rest()[:, 1] for f, _, _ in BONES])
THUMB_REST_X = np.ascontiguousarray(ANATOMY["thumb"].rest()[:, 0])  # (read in C)
THUMB_FIRST = HAND_JOINTS.index("thumb_metacarpal")
_fingers.layout(STARTS, ENDS, PARENT_A, PARENT_B, TIPS)


@dataclass(slots=True, eq=False)
class Fingers:
    """The bodies and joints of one hand's fingers, their servos' state, and its grips'
    memory."""

    bones: list[int]
    chain: list[int]
    lengths: np.ndarray  # each bone's length (m)
    radii: np.ndarray  # each bone's capsule radius (m)
    finger_of: dict[int, str]  # bone entity -> its finger
    #: the tracked joints' angles (15, 2: flexion, spread) when the joints were made: each
    #: joint counts its angles from there
    zero: np.ndarray = field(default_factory=lambda: np.zeros((15, 2)))
    #: the forms its angles are measured with, and whether it is a left hand
    #: (:func:`angle_forms`: its spread axes in the tracked wrist's frame)
    forms: tuple[np.ndarray, int] = (np.zeros((20, 9, 2)), 0)
    keys: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # its joints
    time_constant: float = 0.03  # the servos' (s): the hand drive's
    sample: tuple[float, np.ndarray, np.ndarray] | None = None  # t, positions, quats
    velocity: np.ndarray = field(default_factory=lambda: np.zeros((15, 3)))  # tracked
    angles: tuple[float, np.ndarray] | None = None  # the last sample's (t, (15, 2))
    rates: np.ndarray = field(default_factory=lambda: np.zeros((15, 2)))
    #: each joint's distance to its fingertip along the finger (15,; m): its torque arm
    levers: np.ndarray = field(default_factory=lambda: np.zeros(15))
    #: the servos' rows (15, 7) sent each frame (SetServos' layout)
    servos: np.ndarray = field(default_factory=lambda: np.zeros((15, 7)))
    tips: np.ndarray = field(default_factory=lambda: np.zeros((5, 3)))  # tracked
    palm: np.ndarray = field(default_factory=lambda: np.zeros(3))  # tracked palm joint
    #: object -> (the fingers gripping it, the tracked grip's width when it took hold)
    grips: dict[int, tuple[tuple[str, ...], float]] = field(default_factory=dict)
    #: object -> the parts ("palm" or fingers) pressing it in the last step
    pressing: dict[int, tuple[str, ...]] = field(default_factory=dict)
    colliding: bool = True
    holding: bool = False  # whether the servos have their holding bound
    #: the thinnest bone's radius (m): a hand slower than it per frame casts no rays
    thinnest: float = 0.0
    #: the fastest of its tracked bones' velocity components (m/s; :func:`aim`'s)
    fastest: float = 0.0
    #: the pose table's version and the bones' rows in it (read each frame in one go)
    rows: tuple[int, np.ndarray] = (-1, np.zeros(0, np.int64))

    def entities(self) -> list[int]:
        return [*self.chain, *self.bones]


def world_joints(sample: HandJoints, frame: Transform | None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The sample's joint positions (26, 3) and orientations (26, 4) in the world (through
    the hand's frame object, a wheelchair, when it has one)."""
    if frame is None:
        return joint_arrays(sample)
    return _fingers.read_joints(sample.positions, sample.orientations, frame.position,
                                frame.orientation)


#: The last samples' joints as arrays, by sample (the palm's drive, the bones' and the
#: ghost fingers read each sample in the same frame; a sample's tuples are converted once).
_SEEN: dict[int, tuple[HandJoints, np.ndarray, np.ndarray]] = {}


def joint_arrays(sample: HandJoints) -> tuple[np.ndarray, np.ndarray]:
    """The sample's positions (26, 3) and orientations (26, 4), read-only: shared."""
    seen = _SEEN.get(id(sample))
    if seen is not None and seen[0] is sample:
        return seen[1], seen[2]
    if len(_SEEN) >= 64:
        _SEEN.clear()
    p, q = _fingers.read_joints(sample.positions, sample.orientations)
    p.setflags(write=False)
    q.setflags(write=False)
    _SEEN[id(sample)] = (sample, p, q)
    return p, q


def bone_poses(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each bone's centre (15, 3), orientation (15, 4; +x from its start joint to its end,
    +y the start joint's flexion axis) and length (15,), from world joints."""
    along = p[ENDS] - p[STARTS]
    lengths = np.linalg.norm(along, axis=1)
    x = along / np.maximum(lengths, 1e-9)[:, None]
    y = quat_to_matrix(q[STARTS])[:, :, 1]
    y = y - np.sum(y * x, axis=1, keepdims=True) * x
    y /= np.maximum(np.linalg.norm(y, axis=1, keepdims=True), 1e-9)
    frames = np.stack([x, y, np.cross(x, y)], axis=2)
    return (p[STARTS] + p[ENDS]) / 2, matrices_to_quats(frames), lengths


def _bone_body(radius: float, length: float, kind: str = BodyKind.DYNAMIC) -> Physical:
    capsule = Shape("capsule", (radius, max(length, 1e-3)), rotation=ALONG_X)
    return Physical(kind=kind, mass=BONE_MASS, shapes=[capsule], material=SKIN,
                    category=HAND_BIT, mask=0xFFFFFFFF & ~HAND_BIT, gravity=False,
                    can_sleep=False)


def separate_palm(engine: Engine, palm: int) -> None:
    """The palm's body in the hands' collision bit, so its own bones pass through it
    (its body made again: a backend takes a body's filter when it is made)."""
    world = engine.world
    body = world.component_for_entity(palm, Physical)
    wanted = replace(body, category=HAND_BIT, mask=body.mask & ~HAND_BIT)
    if (body.category, body.mask) != (wanted.category, wanted.mask):
        world.remove_component(palm, Physical)
        world.add_component(palm, wanted)


def _cross_flat(axes: np.ndarray) -> np.ndarray:
    """Each axis' (n, 3) cross-product form flattened (n, 9): ``outer(a, b) · it`` is the
    triple product (a × b) · axis."""
    out = np.zeros((len(axes), 3, 3))
    out[:, 0, 1], out[:, 1, 2], out[:, 2, 0] = axes[:, 2], axes[:, 0], axes[:, 1]
    out[:, 1, 0], out[:, 2, 1], out[:, 0, 2] = -axes[:, 2], -axes[:, 0], -axes[:, 1]
    return out.reshape(len(axes), 9)


#: The flexion rows' forms (15, 9, 2) in the wrist's frame, a right hand's and a left
#: hand's (its mirror image, the axis turned round): the triple product with the
#: flexion axis, and the dot product.
FLEX_FORMS = tuple(np.stack([_cross_flat(axes), np.tile(np.eye(3).ravel(), (15, 1))],
                            axis=2) for axes in (REST_Y, REST_Y * (-1.0, 1.0, -1.0)))
#: The thumb's rest heading (its first bone's parent) in the wrist's frame: right, left.
THUMB_REST = (THUMB_REST_X, THUMB_REST_X * (1.0, -1.0, 1.0))
#: x, y, z into the flattened cross-product form (3, 9): ``axes @ CROSS_FLAT``.
CROSS_FLAT = _cross_flat(np.eye(3))


def _matrix(q: np.ndarray) -> np.ndarray:
    """A unit quaternion's rotation matrix, from plain floats (one quaternion: numpy's
    machinery for stacks costs more than the arithmetic)."""
    w, x, y, z = q.tolist()
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def angle_forms(p: np.ndarray, q: np.ndarray, spread_axes: np.ndarray | None = None
                ) -> tuple[np.ndarray, int]:
    """The quadratic forms (20, 9, 2) :func:`joint_angles` measures one hand's angles
    with, and whether it is a left hand (its thumb toward the wrist's -y), from world
    joints: the flexions about their axes in the wrist's frame (a left hand's mirrored);
    each finger's spread about ``spread_axes`` (5, 3, world; None: no spread), seen
    along it: (a × b) · s over a · b - (a · s)(b · s). Made once per hand: its spread
    axes turn with its wrist."""
    wrist = _matrix(q[1])
    left = int(float((p[THUMB_FIRST] - p[1]) @ wrist[:, 1]) < 0.0)
    forms = np.zeros((20, 9, 2))
    forms[:15] = FLEX_FORMS[left]
    if spread_axes is not None:
        s = spread_axes @ wrist
        forms[15:, :, 0] = s @ CROSS_FLAT
        forms[15:, :, 1] = np.eye(3).ravel() - (s[:, :, None] * s[:, None, :]).reshape(5, 9)
    return forms, left


def joint_angles(p: np.ndarray, q: np.ndarray,
                 forms: tuple[np.ndarray, int] | None = None) -> np.ndarray:
    """Each joint's tracked angles (15, 2), from world joints: its flexion (radians, toward
    the palm positive: :func:`services.input.hand_pose.flexion`'s, all fingers at once,
    in the wrist's frame) and, at a finger's base, its spread: the angle from the parent
    bone to the bone about an axis (a spread: seen along it), each atan2 of two
    quadratic forms of the two bones (:func:`angle_forms`; default: this sample's, no
    spread), in C (:func:`systems._fingers.angles`): this runs for every hand every
    frame."""
    forms, left = angle_forms(p, q) if forms is None else forms
    return _fingers.angles(np.ascontiguousarray(p, float), np.ascontiguousarray(q, float),
                           np.ascontiguousarray(forms, float), THUMB_REST[left])


def build(engine: Engine, name: str, palm: int, sample: HandJoints, frame: Transform | None,
          drive: SetDriveLimits) -> Fingers:
    """Spawn one hand's phalanges where the tracked ones are and the chain of anatomical
    joints, whose servos take ``drive``'s time constant (their bounds:
    :data:`BONE_FORCE` at the tip)."""
    p, q = world_joints(sample, frame)
    centres, quats, lengths = bone_poses(p, q)
    radii = np.asarray(sample.radii, dtype=float)
    # a joint's zero is its pose when made: the limits and the servo count from it
    bent = joint_angles(p, q)[:, 0]
    bones, chain, sizes, spreads = [], [], [], []
    finger_of: dict[int, str] = {}
    for i, (finger, start, end) in enumerate(BONES):
        label = f"{name} {HAND_JOINTS[start]}"
        radius = float(np.clip(min(radii[start], radii[end]) or 0.008, 0.004, 0.015))
        sizes.append(radius)
        pose = Transform(centres[i].copy(), quats[i].copy())
        bone = engine.spawn(Name(label), pose, _bone_body(radius, float(lengths[i])),
                            Visual(shapes=[replace(_bone_body(radius, float(lengths[i]))
                                                   .shapes[0])], color=BONE_COLOR),
                            Graspable(False))
        parent = palm if i % 3 == 0 else bones[-1]
        # spread about the palm's dorsal axis (the thumb's CMC: about its own, the palm's
        # being near its flexion axis)
        spread = _spread_axis(quats[i], quat_to_matrix(quats[i] if finger == "thumb"
                                                       else q[0])[:, 2])
        if i % 3 == 0:
            spreads.append(spread)
        chain.append(_link(engine, label, bone, parent, p[start], quats[i], spread, finger,
                           i % 3, float(bent[i])))
        bones.append(bone)
        finger_of[bone] = finger
    forms = angle_forms(p, q, np.array(spreads))
    return Fingers(bones, chain, lengths, np.array(sizes), finger_of,
                   zero=joint_angles(p, q, forms), forms=forms,
                   keys=np.array(chain, np.int64), time_constant=drive.time_constant or 0.03,
                   thinnest=min(sizes),
                   levers=lengths.reshape(5, 3)[:, ::-1].cumsum(axis=1)[:, ::-1].ravel())


def _spread_axis(quat: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """A base joint's spread axis: ``spread`` made square to the bone's flexion axis."""
    flex = quat_to_matrix(quat)[:, 1]
    spread = spread - (spread @ flex) * flex
    return spread / max(float(np.linalg.norm(spread)), 1e-9)


def _link(engine: Engine, label: str, bone: int, parent: int, anchor: np.ndarray,
          quat: np.ndarray, spread: np.ndarray, finger: str, k: int, bent: float) -> int:
    """The anatomical joint at a bone's start: universal (flexion about the bone's +y,
    limited; spread about ``spread``) at the base of a finger, a hinge further on.
    ``bent``: its flexion now (rad), which the joint takes as its zero."""
    rot = quat_to_matrix(quat)
    low, high = (limit - bent for limit in LIMITS[finger][k])
    kind = JointKind.UNIVERSAL if k == 0 else JointKind.HINGE
    joint = Joint(kind=kind, body_a=bone, body_b=parent, anchor=tuple(anchor.tolist()),
                  axis=tuple(rot[:, 1].tolist()), axis2=tuple(spread.tolist()),
                  low=low, high=high, id=f"{label} joint")
    return engine.spawn(Name(f"{label} joint"), joint)


def aim(hands: list[tuple[Fingers, HandJoints, Transform | None]], now: float,
        stale_after: float) -> list[np.ndarray]:
    """Each hand's servos' rows (15, 7) for its sample: each joint's tracked angles
    counted from its zero, their rates from the sample before (zero once the samples
    stop coming), the torque bound (:data:`BONE_FORCE` at the tip, :data:`HOLD_FORCE`
    while holding). Also notes each hand's tracked bones' centres and velocities (the
    fast-hand rays'), tips and palm (:func:`systems._fingers.aim`)."""
    out = []
    for fingers, sample, frame in hands:
        p, q = world_joints(sample, frame)
        fingers.fastest = _fingers.aim(fingers, p, q, THUMB_REST[fingers.forms[1]],
                                       sample.timestamp, now - sample.timestamp > stale_after,
                                       HOLD_FORCE if fingers.holding else BONE_FORCE, MAX_SPIN)
        out.append(fingers.servos)
    return out


def servo_rows(fingers: Fingers, angles: np.ndarray) -> np.ndarray:
    """The servos' rows (15, 7) aiming at ``angles`` (tracked, 15 × 2) at the fingers'
    tracked rates, with the bound that fits whether the hand holds something."""
    _fingers.servo_rows(fingers.servos, angles, fingers.zero, fingers.rates, fingers.levers,
                        HOLD_FORCE if fingers.holding else BONE_FORCE,
                        fingers.time_constant, MAX_SPIN)
    return fingers.servos


def still(fingers: Fingers) -> np.ndarray | None:
    """An untracked hand's servos held at their last targets, not moving on (once: None
    when they already are)."""
    if fingers.angles is None or not fingers.rates.any():
        return None
    fingers.rates = np.zeros((15, 2))
    fingers.velocity = np.zeros((15, 3))
    fingers.fastest = 0.0
    return servo_rows(fingers, fingers.angles[1])


def palm_pose(previous: tuple[float, np.ndarray, ...] | None, sample: HandJoints,
              frame: Transform | None, now: float, stale_after: float
              ) -> tuple[float, np.ndarray, ...]:
    """The palm joint's world pose and velocities (t, p, q, v, w): the velocities by
    finite difference from ``previous`` (kept while no newer sample came; zero once the
    samples stop coming; :func:`systems._fingers.palm_motion`)."""
    p, q = world_joints(sample, frame)
    return _fingers.palm_motion(p, q, sample.timestamp, previous,
                                now - sample.timestamp > stale_after)


def sweep_share(engine: Engine, fingers: Fingers, palm: int,
                palm_target: tuple[np.ndarray, ...], dt: float,
                held: Container[int] = frozenset()) -> float:
    """How much of this frame's way to its targets the hand may go (0 to 1) before one
    of its bodies would pass through something: once the hand is fast enough for its
    thinnest bone to move its thickness in a frame, a ray per body that would move more
    than half its thickness (a fast hand; 3 m/s is 25 mm a step, more than
    a finger and a 5 mm plate), from where it is to where its target will be; a body
    whose centre would go past the surface the ray meets goes only half its thickness
    into it (its contacts take it from there; a hand pressing on something is not
    held back). What the hand holds is no obstacle. Serial physics answers at once;
    threaded physics a frame later, so this frame goes unlimited. The bones' targets:
    the tracked bones' centres and velocities (:func:`aim`'s); the palm's: its pose and
    velocities (position, orientation, velocity, spin)."""
    if fingers.sample is None:
        return 1.0
    centres, velocity = fingers.sample[1], fingers.velocity
    position, _, palm_velocity, _ = palm_target
    speed = max(fingers.fastest, *map(abs, palm_velocity.tolist()))
    if 1.8 * speed * dt < fingers.thinnest:
        return 1.0  # slow: no body moves its thickness (√3 times an axis's speed bounds it)
    world = engine.world
    palm_t = world.try_component(palm, Transform)
    if palm_t is None:
        return 1.0
    bodies = [palm, *fingers.bones]
    here = np.vstack([palm_t.position, bone_table(engine, fingers)[:, :3]])
    there = np.vstack([position + palm_velocity * dt,
                       centres + velocity * dt])
    way = there - here
    far = np.linalg.norm(way, axis=1)
    thick = np.concatenate([[_palm_reach(world, palm, way[0], far[0])], fingers.radii])
    fast = np.flatnonzero(far > 0.5 * thick)
    if not len(fast):
        return 1.0
    mask = 0xFFFFFFFF & ~HAND_BIT
    rays = [(bodies[i], here[i], way[i], far[i] + thick[i], thick[i], far[i]) for i in fast]
    answer = engine.physics.request(lambda backend: [
        (backend.raycast(o, d, reach, ignore=key, mask=mask), th, f)
        for key, o, d, reach, th, f in rays])
    if not answer.done() or answer.exception() is not None:
        return 1.0
    share = 1.0
    for hit, th, f in answer.result():
        if hit is not None and hit.key not in held and f > hit.distance:
            share = min(share, max(hit.distance - 0.5 * th, 0.0) / f)
    return share


def _palm_reach(world: Any, palm: int, way: np.ndarray, far: float) -> float:
    """How far the palm's box reaches from its centre along ``way``."""
    body, t = world.try_component(palm, Physical), world.try_component(palm, Transform)
    box = next((s for s in body.shapes if s.kind == "box"), None) if body else None
    if box is None or t is None or far <= 0.0:
        return 0.02
    local = quat_to_matrix(t.orientation).T @ (way / far)
    return float(np.abs(local) @ (np.asarray(box.size[:3]) / 2))


def limit(rows: np.ndarray, here: np.ndarray, share: float) -> None:
    """Targets moved only ``share`` of the way from where the bodies are, their
    velocities scaled alike (rows: position, orientation, velocities)."""
    rows[:, :3] = here + share * (rows[:, :3] - here)
    rows[:, 7:] *= share


def push_servos(engine: Engine, rigs: list[tuple[Fingers, np.ndarray]]) -> None:
    """Every fingered hand's servos aimed by one command."""
    if not rigs:
        return
    if len(rigs) == 1:
        engine.physics.push(SetServos(rigs[0][0].keys, rigs[0][1]))
        return
    engine.physics.push(SetServos(np.concatenate([f.keys for f, _ in rigs]),
                                  np.vstack([rows for _, rows in rigs])))


def hold(fingers: Fingers, holding: bool) -> bool:
    """The servos at their holding bound while the hand holds something; whether that
    changed (their rows then go again)."""
    if fingers.holding == holding:
        return False
    fingers.holding = holding
    fingers.servos[:, 4] = (HOLD_FORCE if holding else BONE_FORCE) * fingers.levers
    return True


def set_colliding(engine: Engine, fingers: Fingers, enabled: bool) -> None:
    """The fingers collide as their palm does (the deviation rule)."""
    if fingers.colliding == enabled:
        return
    fingers.colliding = enabled
    for bone in fingers.bones:
        engine.physics.push(SetCollisionEnabled(bone, enabled))


def bone_table(engine: Engine, fingers: Fingers) -> np.ndarray:
    """The bones' rows of the pose table (15, 13: position, orientation, velocities), read
    in one go (their row indices kept while no Transform comes or goes)."""
    return engine.world.poses.table[_rows(engine, fingers)]


def _rows(engine: Engine, fingers: Fingers) -> np.ndarray:
    """The bones' row indices in the pose table (kept while no Transform comes or
    goes)."""
    poses = engine.world.poses
    version, rows = fingers.rows
    if version != poses.version:
        rows = poses.rows(fingers.bones)
        if (rows < 0).any():
            raise LookupError("a fingered hand's bone has no Transform")
        fingers.rows = (poses.version, rows)
    return rows


def deviations(engine: Engine, fingers: Fingers) -> tuple[float, ...]:
    """Each physical fingertip's distance (m; where the last step left it) from its
    tracked one now, read from the pose table in one go."""
    return _fingers.deviations(engine.world.poses.table, _rows(engine, fingers),
                               fingers.lengths, fingers.tips)


def tips_now(engine: Engine, fingers: Fingers) -> np.ndarray:
    """Where the physical fingertips are (5, 3): each distal bone's far end, read from the
    pose table in one go (:func:`systems._fingers.far_ends`)."""
    return _fingers.far_ends(engine.world.poses.table, fingers.lengths[2::3],
                             _rows(engine, fingers)[2::3])  # (made contiguous there)


def presses(contacts: np.ndarray, owner: dict[int, str], elapsed: float
            ) -> dict[int, dict[str, tuple[np.ndarray, np.ndarray, float]]]:
    """Each object pressed by a hand's parts this step, and for each part ("palm" or a
    finger): the mean point, the unit direction of its force on the object and its size
    (N), from the contacts (whose normal points from ``b`` into ``a``)."""
    keys = np.fromiter(owner, dtype=np.int64, count=len(owner))
    a, b = contacts["a"], contacts["b"]
    rows = np.flatnonzero(np.isin(a, keys) | np.isin(b, keys))
    sums: dict[tuple[int, str], list[Any]] = {}
    for r in rows.tolist():
        x, y = int(a[r]), int(b[r])
        part, obj, sign = (owner[x], y, -1.0) if x in owner else (owner[y], x, 1.0)
        if obj < 0 or obj in owner:
            continue
        impulse = float(contacts["impulse"][r])
        entry = sums.setdefault((obj, part), [np.zeros(3), np.zeros(3), 0.0])
        entry[0] += contacts["position"][r] * impulse
        entry[1] += contacts["normal"][r] * (sign * impulse)
        entry[2] += impulse
    out: dict[int, dict[str, tuple[np.ndarray, np.ndarray, float]]] = {}
    for (obj, part), (point, push, total) in sums.items():
        size = float(np.linalg.norm(push))
        if total <= 0.0 or size <= 0.0:
            continue
        out.setdefault(obj, {})[part] = (point / total, push / size, size / elapsed)
    return out


def opposed(parts: dict[str, tuple[np.ndarray, np.ndarray, float]],
            mu: float = GRIP_MU) -> tuple[str, ...]:
    """The parts that grip with the thumb (thumb first), or () where no finger or the
    palm presses against the thumb: both presses at least :data:`PRESS_FORCE`, and the
    line between them inside both friction cones (half-angle atan ``mu``)."""
    thumb = parts.get("thumb")
    if thumb is None or thumb[2] < PRESS_FORCE:
        return ()
    cone = math.cos(math.atan(mu))
    holding = []
    for part in (*FINGERS[1:], "palm"):
        other = parts.get(part)
        if other is None or other[2] < PRESS_FORCE:
            continue
        line = other[0] - thumb[0]
        n = float(np.linalg.norm(line))
        if n < 1e-6:
            continue
        line /= n
        if float(thumb[1] @ line) >= cone and float(other[1] @ -line) >= cone:
            holding.append(part)
    return ("thumb", *holding) if holding else ()


def grip_width(fingers: Fingers, grip: tuple[str, ...],
               presses: dict[str, tuple[np.ndarray, np.ndarray, float]], tips: np.ndarray,
               palm: np.ndarray) -> float:
    """How wide the physical grip ``grip`` is round what it presses: between the thumb's
    press and each finger's (their mean contact points, :func:`presses`) plus both
    fingertips' radii — the width of fingertips touching it, wherever on the finger
    it is touched (a finger pressing with its middle phalanx holds its tip off the
    object) — or from the thumb's tip to the palm (:func:`aperture`'s); the narrowest."""
    thumb = presses["thumb"][0]
    spans = []
    for part in grip[1:]:
        if part == "palm" or part not in presses:
            spans.append(aperture(fingers, ("thumb", part), tips, palm))
        else:
            tip = fingers.radii[3 * FINGERS.index(part) + 2] + fingers.radii[2]
            spans.append(float(np.linalg.norm(presses[part][0] - thumb)) + float(tip))
    return min(spans)


def aperture(fingers: Fingers, parts: tuple[str, ...], tips: np.ndarray | None = None,
             palm: np.ndarray | None = None) -> float:
    """How wide the grip of ``parts`` is: the thumb tip's distance to the nearest other
    tip (or the palm) among them; the tracked hand's, or that of ``tips`` and ``palm``
    (the physical hand's)."""
    tips = fingers.tips if tips is None else tips
    palm = fingers.palm if palm is None else palm
    thumb = tips[0]
    spots = [palm if part == "palm" else tips[FINGERS.index(part)]
             for part in parts if part != "thumb"]
    return min((float(np.linalg.norm(s - thumb)) for s in spots), default=0.0)
