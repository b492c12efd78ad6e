"""A hand's 26 joints from a few numbers, and back: the anatomy every hand source shares.

Gloves that report only bend sensors, the desktop emulation (open, pinch, point, fist from
keys), the recorded sessions we ship and the tests all need a plausible 26-joint hand
(:data:`~services.input.events.HAND_JOINTS`) from a wrist pose and one curl per finger;
the physical hand needs the inverse, each joint's flexion from tracked joints. Both live
here so that they agree.

The hand's own frame (the wrist joint's): +x runs along the fingers, +z out of the back
of the hand, +y toward the thumb of a right hand (a left hand is its mirror image, its
thumb toward −y). Each joint's orientation is that of the bone starting at it (the tip's,
its distal bone's), in the same convention: local +x along the bone, +z dorsal. Sizes are
an adult's hand (about 19 cm wrist to middle tip); ``scale`` fits others.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from engine.rotation import matrices_to_quats, quat_to_matrix
from services.input.events import FINGERS, HAND_JOINTS, HandJoints, Quat, Vec3

#: The largest flexion of each finger's three joints (radians): MCP, PIP, DIP; the
#: thumb's CMC, MCP, IP. A curl of 1 bends every joint to these.
MAX_FLEXION: dict[str, tuple[float, float, float]] = {
    "thumb": (np.radians(40.0), np.radians(55.0), np.radians(75.0)),
    **{f: (np.radians(85.0), np.radians(100.0), np.radians(70.0))
       for f in ("index", "middle", "ring", "little")},
}


@dataclass(frozen=True, slots=True)
class Finger:
    """One finger's rest geometry in the hand's frame (right hand, metres)."""

    base: Vec3  # where its metacarpal starts
    heading: Vec3  # direction of its metacarpal at rest (unit after normalising)
    lengths: tuple[float, float, float, float]  # metacarpal, proximal, intermediate, distal
    radii: tuple[float, float, float, float, float]  # its 5 joints, base to tip
    roll: float = 0.0  # radians about its heading (the thumb bends across the palm)

    def rest(self) -> np.ndarray:
        """Its metacarpal's frame at rest (columns: along, lateral, dorsal)."""
        c, s = np.cos(self.roll), np.sin(self.roll)
        return _frame(self.heading) @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


#: A right hand's fingers at rest. The thumb has no intermediate bone: its four joints
#: are metacarpal (CMC), proximal (MCP), distal (IP) and tip; its ``lengths`` omit one.
ANATOMY: dict[str, Finger] = {
    "thumb": Finger((0.020, 0.018, -0.012), (0.62, 0.70, -0.35),
                    (0.046, 0.032, 0.028, 0.0), (0.012, 0.011, 0.0095, 0.0085, 0.0),
                    np.radians(-60.0)),
    "index": Finger((0.012, 0.021, 0.0), (1.0, 0.10, 0.0),
                    (0.068, 0.040, 0.024, 0.021), (0.011, 0.0105, 0.009, 0.008, 0.0072)),
    "middle": Finger((0.012, 0.004, 0.0), (1.0, 0.0, 0.0),
                     (0.066, 0.045, 0.028, 0.021), (0.011, 0.0108, 0.0093, 0.0082, 0.0072)),
    "ring": Finger((0.012, -0.012, 0.0), (1.0, -0.08, 0.0),
                   (0.060, 0.042, 0.027, 0.021), (0.0105, 0.0102, 0.0088, 0.0078, 0.0068)),
    "little": Finger((0.012, -0.027, 0.0), (1.0, -0.18, 0.0),
                     (0.055, 0.033, 0.019, 0.019), (0.010, 0.0092, 0.0080, 0.0072, 0.0062)),
}
#: Named hand shapes: the curl of each finger (0 straight, 1 fully bent).
GESTURES: dict[str, dict[str, float]] = {
    "open": dict.fromkeys(FINGERS, 0.0),
    "fist": dict.fromkeys(FINGERS, 1.0),
    "point": {"thumb": 0.8, "index": 0.0, "middle": 1.0, "ring": 1.0, "little": 1.0},
    "pinch": {"thumb": 0.35, "index": 0.4, "middle": 0.1, "ring": 0.1, "little": 0.1},
}
_PALM_RADIUS = 0.02
_WRIST_RADIUS = 0.02


def _bend(angle: float) -> np.ndarray:
    """Flexion about a bone's local +y: the bone's +x turns toward the palm (−z)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _frame(heading: Sequence[float]) -> np.ndarray:
    """A bone frame whose +x is ``heading`` and whose +z stays as dorsal as it can."""
    x = np.asarray(heading, dtype=float)
    x = x / np.linalg.norm(x)
    z = np.array([0.0, 0.0, 1.0]) - x[2] * x
    z = z / np.linalg.norm(z)
    return np.column_stack([x, np.cross(z, x), z])


def _finger_joints(name: str, curl: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The finger's joint positions and frames in the hand's frame (right hand)."""
    finger = ANATOMY[name]
    frame = finger.rest()
    point = np.asarray(finger.base, dtype=float)
    bent = tuple(a * curl for a in MAX_FLEXION[name])
    angles = bent if name == "thumb" else (0.0, *bent)  # a metacarpal is the palm's
    bones = len(angles)
    positions, frames = [], []
    for bone in range(bones):
        frame = frame @ _bend(angles[bone])
        positions.append(point.copy())
        frames.append(frame)
        point = point + frame[:, 0] * finger.lengths[bone]
    positions.append(point)
    frames.append(frame)
    return positions, frames


def local_hand(curls: Mapping[str, float], scale: float = 1.0
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A right hand's 26 joints in its own frame: positions (26, 3), rotation matrices
    (26, 3, 3) and radii (26,), for the given curls (missing fingers are straight)."""
    positions = np.zeros((26, 3))
    frames = np.tile(np.eye(3), (26, 1, 1))
    radii = np.zeros(26)
    radii[0], radii[1] = _PALM_RADIUS, _WRIST_RADIUS
    for name in FINGERS:
        curl = float(np.clip(curls.get(name, 0.0), 0.0, 1.0))
        first = HAND_JOINTS.index(f"{name}_metacarpal")
        ps, fs = _finger_joints(name, curl)
        count = len(ps)
        positions[first:first + count] = ps
        frames[first:first + count] = fs
        radii[first:first + count] = ANATOMY[name].radii[:count]
    middle = HAND_JOINTS.index("middle_metacarpal")
    positions[0] = (positions[middle] + positions[middle + 1]) / 2  # palm: mid-metacarpal
    return positions * scale, frames, radii * scale


def pose_hand(device: str, position: Sequence[float], orientation: Sequence[float],
              curls: Mapping[str, float], *, left: bool = False, scale: float = 1.0,
              timestamp: float = 0.0) -> HandJoints:
    """The hand event of a wrist at ``position``/``orientation`` (w, x, y, z) with these
    curls; a left hand mirrors the right one across its own x–z plane."""
    local, frames, radii = local_hand(curls, scale)
    if left:
        mirror = np.diag([1.0, -1.0, 1.0])
        local = local @ mirror
        frames = mirror @ frames @ mirror  # still right-handed: +y toward the little finger
    world = quat_to_matrix(np.asarray(orientation, dtype=float))
    positions = local @ world.T + np.asarray(position, dtype=float)
    quats = matrices_to_quats(world @ frames)
    return HandJoints(device, _vec3s(positions), _quats(quats), tuple(float(r) for r in radii),
                      (True,) * 26, timestamp)


def flexion(hand: HandJoints) -> dict[str, tuple[float, float, float]]:
    """Each finger's three flexion angles (radians, MCP/PIP/DIP; the thumb's CMC/MCP/IP),
    read from the joints' positions: the angle between one bone and the next, signed
    positive toward the palm."""
    p = np.asarray(hand.positions, dtype=float)
    wrist = quat_to_matrix(np.asarray(hand.orientations[1], dtype=float))
    thumb = HAND_JOINTS.index("thumb_metacarpal")
    left = bool((p[thumb] - p[1]) @ wrist[:, 1] < 0)  # a left hand's thumb is toward −y
    mirror = np.array([1.0, -1.0, 1.0]) if left else np.ones(3)
    out: dict[str, tuple[float, float, float]] = {}
    for name in FINGERS:
        first = HAND_JOINTS.index(f"{name}_metacarpal")
        count = 4 if name == "thumb" else 5
        bones = np.diff(p[first:first + count], axis=0)
        rest = ANATOMY[name].rest()
        axis = wrist @ (rest[:, 1] * mirror * (-1.0 if left else 1.0))  # the bending axis
        if name == "thumb":  # the CMC turns the metacarpal from its rest heading
            bones = np.vstack([wrist @ (rest[:, 0] * mirror), bones])
        angles = [_angle(bones[i], bones[i + 1], axis) for i in range(3)]
        out[name] = (angles[0], angles[1], angles[2])
    return out


def curl(hand: HandJoints, finger: str) -> float:
    """How bent a finger is, 0 straight to 1 fully (its flexion over its largest)."""
    if finger not in FINGERS:
        raise ValueError(f"unknown finger {finger!r} (fingers: {', '.join(FINGERS)})")
    angles = flexion(hand)[finger]
    most = MAX_FLEXION[finger]
    reach = [a / m for a, m in zip(angles, most, strict=True)]
    value = sum(r * w for r, w in zip(reach, most, strict=True)) / sum(most)
    return float(np.clip(value, 0.0, 1.0))


def _angle(a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> float:
    """The angle from bone ``a`` to bone ``b`` about ``axis`` (flexion positive)."""
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na < 1e-9 or nb < 1e-9:
        return 0.0
    a, b = a / na, b / nb
    return float(np.arctan2(np.cross(a, b) @ axis, a @ b))


def _vec3s(a: np.ndarray) -> tuple[Vec3, ...]:
    return tuple((float(x), float(y), float(z)) for x, y, z in a)


def _quats(a: np.ndarray) -> tuple[Quat, ...]:
    return tuple((float(w), float(x), float(y), float(z)) for w, x, y, z in a)
