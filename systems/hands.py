"""Virtual hands (paper section 5): physically simulated hands a person's trackers drive.

A hand is an object with a :class:`~components.Hand` (the scene's ``Object { Hand {...} }``):
its own dynamic body, floating, that collides with the world. This plugin gives each hand
a *control body*, kinematic and colliding with nothing, that follows the hand's tracker
(pose and velocity; it is also the marker showing where the real hand is), and a six_dof
drive from the hand to it: the hand's pose error closes with a time constant τ, the
correction capped, the control body's velocity fed forward, and the force and torque
bounded — so a hand tracks a moving tracker closely, but a heavy load lags and a wall
stops it, instead of the solver fighting (the same drive on ODE and pymunk, through the
backend protocol). While hands exist the physics step is at most 1/120 s.

Each frame, in PRE_PHYSICS (so this frame's tracker pose and glove reach this frame's
step): the control body is put at the tracker's pose (relative to the hand's ``Frame``
object, a wheelchair, when it has one); the real/virtual discrepancy rule of section 5.4
runs with D = ``DeviationDistance`` — farther than D from its tracker the hand stops
colliding and is pulled back through whatever held it; it collides again once it is
within 0.1 D and overlaps nothing; between 0.1 D and 0.7 D it is drawn see-through and
on top of everything; beyond 1 m (tracking jumped) it is put at the tracker — and a
pinch of the glove's button grasps what the hand touches: each object is attached by a
fixed joint at its current pose relative to the hand (a ball joint at the hand where a
second hand holds it already, so two grips do not over-constrain it), and released when
the button comes up. In POST_PHYSICS the step's contacts say what each hand touches
(mode contact: drawn with ``ContactModel``), and the force its contacts pushed with,
published for haptic gloves as the output ``hand:ID/force`` (and ``hand:ID/grasp``).

A hand whose tracker is lost holds still (drawn grey) and lets go after
:data:`RELEASE_AFTER` seconds. Events :class:`~engine.events.HandTouched`,
:class:`~engine.events.HandGrasped`, :class:`~engine.events.HandReleased` reach Python
and Lua (``onTouch``, ``onGrasp``, ``onRelease``).
"""

from __future__ import annotations

import logging
import math
from concurrent.futures import Future
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from components import (
    Graspable,
    Hand,
    HandState,
    Joint,
    Name,
    Physical,
    Shape,
    Transform,
    Visual,
)
from components.hand import HandMode
from components.joint import JointKind
from components.physical import BodyKind
from engine.assets.generated import MARKER_BALL
from engine.events import Contacts, CustomEvent, HandGrasped, HandReleased, HandTouched
from engine.messages import MessageLog
from engine.physics.commands import (
    CommandError,
    ConfigureWorld,
    SetCollisionEnabled,
    SetDriveLimits,
    SetPose,
    SetPoses,
    SetVelocity,
    check_limits,
)
from engine.rotation import quat_multiply, quat_to_matrix
from engine.services import HandControl
from engine.system import Phase, PluginName, System
from services.input import InputState
from systems import hand_fingers, hand_fingers2d
from systems.hand_ghost import GhostFingerSystem

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.hands")

#: The longest physics step hands are simulated with (s).
MAX_STEP = 1.0 / 120.0
#: The fewest solver iterations islands with contacts are simulated with while hands
#: exist: a hand pressing with its full drive force on a cup on a table (300 N through
#: 0.3 kg) sinks into it and jitters by millimetres at ODE's 20; at 40 it rests within a
#: millimetre, still. Islands without contacts keep the world's iterations (a fingered
#: hand in the air: its fingertips 1.5 mm from their tracked tips at 20, 1.0 at 40, for
#: half the solver's cost; WorldSettings.contact_iterations).
MIN_ITERATIONS = 40
#: The drive's time constant when the hand names none: max(2 Δt, this) seconds.
MIN_TIME_CONSTANT = 0.03
#: Farther than this from its tracker (m) a hand is taken to have lost track: it is put
#: at the tracker instead of being pulled there.
TELEPORT_DISTANCE = 1.0
#: Seconds a hand whose tracker is lost keeps holding what it holds.
RELEASE_AFTER = 1.0
#: Seconds a hand still touches what it stopped touching: a hand settling on a cup parts
#: from it for a step or two (threaded steps land between the frames that move its
#: target), which would flicker the open-hand model and repeat onTouch.
TOUCH_HOLD = 0.05
#: A tracker sample older than this (s) no longer carries its velocity forward: a tracker
#: that stops sending (dropped packets, a NaN the input layer refused) leaves the hand at
#: its last pose until it is told lost, not ahead of it by the speed it last had.
STALE_AFTER = 0.05
#: Friction coefficient of an object pressed against the palm: a grip's shear up to this
#: times the press does not count toward its BreakForce (skin on most things: 0.5–1).
GRIP_FRICTION = 1.0
#: The see-through band, as shares of the deviation distance D (paper section 5.4), the
#: share under which a hand collides again, and how see-through it is drawn.
SEE_THROUGH = (0.1, 0.7)
COLLIDE_AGAIN = 0.1
SEE_THROUGH_ALPHA = 0.45
#: Colours a hand without models of its own is tinted with per mode, and when untracked.
TINTS = {HandMode.CONTACT: (0.55, 0.85, 0.55), HandMode.GRASP: (0.95, 0.6, 0.3)}
UNTRACKED = (0.55, 0.55, 0.55)
#: The marker: a ball of this diameter (m) where the real hand is, textured with
#: :data:`~engine.assets.generated.MARKER_BALL` (its gores show the tracker turning).
MARKER_SIZE = 0.03
MARKER_COLOR = (1.0, 0.85, 0.2, 1.0)


@dataclass(slots=True, eq=False)
class _Rig:
    """What this plugin made for one hand, and what it remembers between frames."""

    hand: int
    name: str
    control: int
    drive: int
    look: tuple[str | None, tuple[float, float, float, float]]  # the author's model, colour
    grasps: dict[int, int] = field(default_factory=dict)  # object -> its grasp joint
    pressed: bool = False
    lost_for: float = 0.0
    overlap: Future | None = None
    strain: tuple[dict[int, int], Future] | None = None  # grips asked their force, answer
    shown: tuple[str, bool, bool] | None = None  # the mode, tracking and see-through drawn
    #: object -> the physics time the hand last touched it (kept TOUCH_HOLD seconds)
    touched_at: dict[int, float] = field(default_factory=dict)
    #: A fingered hand: its drive's response (the bones take it), the palm's last tracked
    #: pose and velocities (t, p, q, v, w), its bones once the first sample came
    limits: SetDriveLimits | None = None
    palm_sample: tuple[Any, ...] | None = None
    fingers: hand_fingers.Fingers | None = None
    force_output: str = field(init=False)
    grasp_output: str = field(init=False)

    def __post_init__(self) -> None:
        self.force_output, self.grasp_output = f"hand:{self.name}/force", \
            f"hand:{self.name}/grasp"


class Hands:
    """The hands' shared state (a resource, and the scripts' HandControl)."""

    def __init__(self) -> None:
        self.rigs: dict[int, _Rig] = {}
        self.messages = MessageLog(log)
        self._engine: Engine | None = None

    # -- HandControl (scripts) ----------------------------------------------------
    def _rig(self, hand: int) -> _Rig:
        rig = self.rigs.get(hand)
        if rig is None:
            self._state(hand)  # not a hand at all: says so
            raise ValueError("the hand starts holding from its first physics frame on")
        return rig

    def _state(self, hand: int) -> HandState:
        assert self._engine is not None
        state = self._engine.world.try_component(hand, HandState)
        if state is None:
            raise KeyError(f"object {_name(self._engine.world, hand)!r} is not a hand")
        return state

    def state(self, hand: int) -> str:
        rig = self.rigs.get(hand)  # a grasp made this frame is a grasp, as held() says
        if rig is not None and rig.grasps:
            return str(HandMode.GRASP)
        return str(self._state(hand).mode)

    def held(self, hand: int) -> tuple[int, ...]:
        rig = self.rigs.get(hand)  # what it holds now, a grasp this frame included
        return self._state(hand).held if rig is None else tuple(rig.grasps)

    def grasp(self, hand: int, obj: int) -> None:
        assert self._engine is not None
        self.attach(self._engine, self._rig(hand), obj)

    def release(self, hand: int) -> None:
        assert self._engine is not None
        self.let_go(self._engine, self._rig(hand))

    # -- grasping -----------------------------------------------------------------
    def attach(self, engine: Engine, rig: _Rig, obj: int) -> None:
        """Hold ``obj``: a fixed joint at its pose relative to the hand now, or a ball joint
        at the hand where another hand holds it already."""
        world = engine.world
        if obj == rig.hand:  # a joint from its body to itself: no backend takes one
            raise ValueError(f"hand {rig.name!r} cannot hold itself")
        if obj in rig.grasps or not world.entity_exists(obj):
            return
        physical = world.try_component(obj, Physical)
        if physical is None or physical.kind != BodyKind.DYNAMIC:
            raise ValueError(f"object {_name(world, obj)!r} is not a dynamic body; a hand "
                             "holds only what can move")
        graspable = world.try_component(obj, Graspable)
        if graspable is not None and not graspable.enabled:
            raise ValueError(f"object {_name(world, obj)!r} is not graspable (its scene "
                             "says Graspable 0)")
        others = [r for r in self.rigs.values() if obj in r.grasps]
        kind = JointKind.BALL if others else JointKind.FIXED
        rig.grasps[obj] = self._joint(engine, rig, obj, kind)
        for other in others:  # a second grip: the first becomes a grip point too
            # (a fingered hand's grip stays fixed: round the line between two grip points
            # the object would swing as the fingers that held it open to hand it over)
            if other.fingers is None and \
                    self._kind(world, other.grasps[obj]) == JointKind.FIXED:
                engine.despawn(other.grasps[obj])
                other.grasps[obj] = self._joint(engine, other, obj, JointKind.BALL)
        _tell(engine, HandGrasped(rig.hand, obj), "grasp")

    def let_go(self, engine: Engine, rig: _Rig, objects: list[int] | None = None) -> None:
        """Release ``objects`` (default: all); a single grip left on one becomes fixed."""
        for obj in list(rig.grasps) if objects is None else objects:
            joint = rig.grasps.pop(obj, None)
            if joint is None:
                continue
            engine.despawn(joint)
            _tell(engine, HandReleased(rig.hand, obj), "release")
            remaining = [r for r in self.rigs.values() if obj in r.grasps]
            if len(remaining) == 1 and engine.world.entity_exists(obj):
                last = remaining[0]
                engine.despawn(last.grasps[obj])
                last.grasps[obj] = self._joint(engine, last, obj, JointKind.FIXED)

    @staticmethod
    def _kind(world: Any, joint: int) -> str | None:
        j = world.try_component(joint, Joint)
        return None if j is None else j.kind

    @staticmethod
    def _joint(engine: Engine, rig: _Rig, obj: int, kind: JointKind) -> int:
        anchor = tuple(engine.world.component_for_entity(rig.hand, Transform).position)
        label = f"{rig.name} holds {_name(engine.world, obj)}"
        return engine.spawn(Name(label), Joint(kind=kind, body_a=rig.hand, body_b=obj,
                                               anchor=anchor, id=label))


def _name(world: Any, entity: int) -> str:
    name = world.try_component(entity, Name)
    return name.id if name is not None else f"entity {entity}"


def _frame(engine: Engine, hand: Hand) -> Transform | None:
    """The Transform of the object a hand's tracker is calibrated relative to, if any."""
    return None if hand.frame is None else engine.world.try_component(hand.frame, Transform)


def _carry(engine: Engine, hand: int, obj: int) -> None:
    """Give a let-go object the hand's velocity where it is (what it had while held),
    and no more: the fingers that opened round it do not throw it."""
    world = engine.world
    palm, t = world.try_component(hand, Transform), world.try_component(obj, Transform)
    if palm is None or t is None:
        return
    spin = palm.angular_velocity
    linear = palm.linear_velocity + np.cross(spin, t.position - palm.position)
    engine.physics.push(SetVelocity(obj, tuple(linear.tolist()), tuple(spin.tolist())))


def _tell(engine: Engine, event: HandGrasped | HandReleased, kind: str) -> None:
    """A grasp or release on the bus, and as a marker (``grasp HAND OBJECT``) on the
    scene's Output streams, so a recording of physiological signals lines up with it."""
    engine.events.emit(event)
    world = engine.world
    engine.events.emit(CustomEvent("marker", f"{kind} {_name(world, event.hand)} "
                                             f"{_name(world, event.object)}"))


class HandDriveSystem(System):
    """PRE_PHYSICS: trackers move the control bodies; discrepancy rule; grasp and release."""

    phase = Phase.PRE_PHYSICS
    reads = (Hand, HandState, Transform, Name, Physical, Graspable, Joint, Visual)
    writes = (HandState, Visual, Name, Transform, Physical, Joint, Graspable)

    def __init__(self, hands: Hands) -> None:
        self.hands = hands
        self._new: list[int] = []
        self._table = np.empty((0, 13))  # the control bodies' rows, reused each frame

    def setup(self, engine: Engine) -> None:
        self.hands._engine = engine
        world = engine.world
        world.on_add(Hand, lambda e, h: self._added(engine, e))
        world.on_remove(Hand, lambda e, h: self._forget(engine, e))
        world.on_remove(Physical, lambda e, p: self._dropped(engine, e))
        for entity in sorted(e for e, _ in world.get_component(Hand)):
            self._added(engine, entity)

    def _added(self, engine: Engine, entity: int) -> None:
        """Rigged at the next PRE_PHYSICS; the step is shortened and the solver given its
        iterations now, before any frame steps without (a saved state resumes with the
        same steps)."""
        self._limit_step(engine)
        self._enough_iterations(engine)
        self._new.append(entity)

    def run(self, engine: Engine, dt: float) -> None:
        if self._new:
            self._rig_new(engine)
        rigs = self.hands.rigs
        if not rigs:
            return
        inputs = engine.try_resource(InputState)
        # each hand's components in one query (the world's cached one), not three looks
        found = dict(engine.world.get_components(Hand, HandState, Transform))
        driven = [(rig, found[rig.hand]) for rig in rigs.values() if rig.hand in found]
        poses = self._move_controls(engine, driven, inputs)
        servos = self._move_fingers(engine, driven, inputs, poses, dt)
        for (rig, (hand, state, t)), pose in zip(driven, poses, strict=True):
            self._drive(engine, rig, hand, state, t, pose, dt)
            pressed = inputs is not None and hand.glove != "" and inputs.button(hand.glove,
                                                                                hand.button)
            if pressed and not rig.pressed:
                for obj in state.touching:
                    self._grasp(engine, rig, obj)
            elif rig.pressed and not pressed:  # what the fingers grip they hold on to
                grips = {} if rig.fingers is None else rig.fingers.grips
                self.hands.let_go(engine, rig, [o for o in rig.grasps if o not in grips])
            rig.pressed = pressed
            if rig.fingers is not None and rig.fingers.grips:
                self._open_grips(engine, rig)
            fingers = rig.fingers
            if fingers is not None and hand_fingers.hold(fingers, bool(rig.grasps)) and \
                    not isinstance(fingers, hand_fingers2d.PlanarFingers) and \
                    fingers.angles is not None and \
                    not any(f is fingers for f, _ in servos):
                servos.append((fingers, fingers.servos))  # its new bound, this frame
            state.held = tuple(rig.grasps)
        hand_fingers.push_servos(engine, servos)

    def _open_grips(self, engine: Engine, rig: _Rig) -> None:
        """Let go of what the fingers gripped once the tracked grip opened
        :data:`~systems.hand_fingers.RELEASE_BAND` wider than when it took hold; the object
        keeps the hand's velocity where it is, nothing more."""
        fingers = rig.fingers
        assert fingers is not None
        for obj, (parts, width) in list(fingers.grips.items()):
            if obj not in rig.grasps:
                del fingers.grips[obj]
            elif hand_fingers.aperture(fingers, parts) > width + hand_fingers.RELEASE_BAND:
                del fingers.grips[obj]
                self.hands.let_go(engine, rig, [obj])
                if not any(obj in r.grasps for r in self.hands.rigs.values()):
                    _carry(engine, rig.hand, obj)

    def _fingered(self, engine: Engine, name: str) -> bool:
        """Whether this backend simulates a hand's fingers (told once if not)."""
        backend = engine.physics.backend_name
        if backend in ("ode", "pymunk"):  # pymunk: a 2D hand in the plane
            return True
        self.hands.messages.warn(f"hand {name!r}: Fingers 1 needs the ode or pymunk backend "
                                 f"(this is {backend!r}); it is a palm only")
        return False

    def _move_fingers(self, engine: Engine, driven: list[tuple[_Rig, Any]],
                      inputs: InputState | None,
                      poses: list[tuple[np.ndarray, ...] | None], dt: float
                      ) -> list[tuple[hand_fingers.Fingers, np.ndarray]]:
        """Aim every fingered hand's joint servos at its tracked angles (their rows, sent
        in one command once the frame's grips are known); a hand's bones are made at its
        first sample (sized from it), the palm put at the tracked palm first. An
        untracked hand's joints hold still. A hand that would pass through something
        this frame goes only as far as it (:func:`~systems.hand_fingers.sweep_share`):
        its palm is held back, and its fingers with it."""
        rows: list[tuple[hand_fingers.Fingers, np.ndarray]] = []
        aiming: list[tuple[_Rig, hand_fingers.Fingers, Any, Transform | None, Any]] = []
        planar = engine.physics.backend_name == "pymunk"
        for (rig, (hand, _, _)), pose in zip(driven, poses, strict=True):
            if rig.limits is None:
                continue
            sample = None if inputs is None or pose is None else inputs.hand(hand.tracker)
            fingers = rig.fingers
            if sample is None:
                if isinstance(fingers, hand_fingers2d.PlanarFingers):
                    hand_fingers2d.still(engine, fingers)
                elif fingers is not None:
                    held = hand_fingers.still(fingers)
                    if held is not None:
                        rows.append((fingers, held))
                continue
            frame = _frame(engine, hand)
            if fingers is None:
                engine.physics.set_pose(rig.hand, pose[0], pose[1])
                fingers = rig.fingers = (hand_fingers2d if planar else hand_fingers).build(
                    engine, rig.name, rig.hand, sample, frame, rig.limits)
            if isinstance(fingers, hand_fingers2d.PlanarFingers):  # joints' motors, no aims
                hand_fingers2d.aim(engine, fingers, rig.hand, sample, frame, inputs.now,
                                   STALE_AFTER)
                self._deviation(engine, rig, fingers)
                continue
            aiming.append((rig, fingers, sample, frame, pose))
        if not aiming:
            return rows
        aims = hand_fingers.aim([(f, s, fr) for _, f, s, fr, _ in aiming], inputs.now,
                                STALE_AFTER)
        for (rig, fingers, _, _, pose), servos in zip(aiming, aims, strict=True):
            rows.append((fingers, servos))
            self._sweep(engine, rig, fingers, pose, dt)
            self._deviation(engine, rig, fingers)
        return rows

    @staticmethod
    def _deviation(engine: Engine, rig: _Rig, fingers: hand_fingers.Fingers) -> None:
        """Each physical tip (where the last step left it) from its tracked one now."""
        found = engine.world.try_component(rig.hand, HandState)
        if found is not None:
            found.finger_deviation = hand_fingers.deviations(engine, fingers)

    @staticmethod
    def _sweep(engine: Engine, rig: _Rig, fingers: hand_fingers.Fingers,
               palm: tuple[np.ndarray, ...], dt: float) -> None:
        """A fast hand's palm target held short of what the hand would pass (its fingers
        hang on it by their joints)."""
        if not fingers.colliding:
            return
        share = hand_fingers.sweep_share(engine, fingers, rig.hand, palm, dt, rig.grasps)
        if share >= 1.0:
            return
        world = engine.world
        row = np.concatenate(palm)[None]
        hand_fingers.limit(row, world.component_for_entity(rig.hand, Transform).position,
                           share)
        engine.physics.push(SetPoses([rig.control], row))

    def _grasp(self, engine: Engine, rig: _Rig, obj: int) -> None:
        try:
            self.hands.attach(engine, rig, obj)
        except ValueError as exc:
            self.hands.messages.warn(f"hand {rig.name!r}: {exc}")

    # -- rigs -----------------------------------------------------------------------
    def _rig_new(self, engine: Engine) -> None:
        new, self._new = self._new, []
        world = engine.world
        for entity in new:
            hand = world.try_component(entity, Hand)
            t = world.try_component(entity, Transform)
            if hand is None or t is None or not world.has_component(entity, Physical):
                continue
            name = _name(world, entity)
            tick = engine.config.dt / max(engine.controller.substeps, 1)
            tau = hand.time_constant or max(2.0 * tick, MIN_TIME_CONSTANT)
            try:  # a Hand made in Python is checked here (a scene's, at its line)
                limits = SetDriveLimits(0, hand.max_force, hand.max_torque, tau,
                                        hand.max_speed, hand.max_spin)
                if not hand.deviation_distance > 0.0:
                    raise CommandError(f"DeviationDistance must be positive, got "
                                       f"{hand.deviation_distance!r}")
            except CommandError as exc:
                self.hands.messages.error(f"hand {name!r}: {exc}; it is not driven")
                continue
            fingered = hand.fingers and self._fingered(engine, name)
            if fingered:
                hand_fingers.separate_palm(engine, entity)
            control = engine.spawn(
                Name(f"{name} tracker"), Transform(t.position.copy(), t.orientation.copy()),
                Physical(kind=BodyKind.KINEMATIC, mass=1.0, shapes=[], category=0, mask=0,
                         gravity=False, can_sleep=False),
                *([Visual(shapes=[Shape("sphere", (MARKER_SIZE / 2,))], color=MARKER_COLOR,
                          texture=MARKER_BALL, shadower=False)] if hand.marker else []))
            drive = engine.spawn(Name(f"{name} drive"), Joint(
                kind=JointKind.SIX_DOF, body_a=entity, body_b=control,
                motor_max_force=hand.max_force, id=f"{name} drive"))
            engine.physics.push(replace(limits, key=drive))
            visual = world.try_component(entity, Visual)
            look = (None, (0.8, 0.8, 0.8, 1.0)) if visual is None else (
                visual.model, tuple(visual.color))
            rig = _Rig(entity, name, control, drive, look)  # type: ignore[arg-type]
            rig.limits = limits if fingered else None
            self.hands.rigs[entity] = rig
            for held in hand.holding:  # a saved state: hold again what was held
                obj = next((e for e, n in world.get_component(Name) if n.id == held), None)
                if obj is None:
                    self.hands.messages.warn(f"hand {name!r}: it held {held!r}, which is not "
                                             "in the scene; it holds nothing")
                else:
                    self._grasp(engine, rig, obj)
            hand.holding = ()

    @staticmethod
    def _limit_step(engine: Engine) -> None:
        """Hands are simulated at 1/120 s or finer: more substeps per frame if needed."""
        needed = math.ceil(engine.config.dt / MAX_STEP - 1e-9)
        raised = False
        for controller in (engine.controller, engine.physics.controller):
            if controller.substeps < needed:
                raised = True
                controller.substeps = needed
                controller.pacing.substeps = needed
                controller.pacing.max_substeps = max(controller.pacing.max_substeps, needed)
        if raised:
            log.info("hands: physics steps at %.4g s (%d per frame of %.4g s)",
                     engine.config.dt / needed, needed, engine.config.dt)

    @staticmethod
    def _enough_iterations(engine: Engine) -> None:
        world = engine.config.world
        if max(world.iterations, world.contact_iterations) >= MIN_ITERATIONS:
            return
        # without the seed: the solver's random state goes on where it is
        engine.config.world = replace(world, contact_iterations=MIN_ITERATIONS,
                                      solver_seed=None)
        engine.physics.push(ConfigureWorld(engine.config.world))
        log.info("hands: islands with contacts are solved with %d iterations (the world "
                 "asked for %d)", MIN_ITERATIONS, world.iterations)

    def _forget(self, engine: Engine, entity: int) -> None:
        rig = self.hands.rigs.pop(entity, None)
        if rig is None:
            return
        self.hands.let_go(engine, rig)
        engine.despawn(rig.drive)
        engine.despawn(rig.control)
        if rig.fingers is not None:
            for part in rig.fingers.entities():
                engine.despawn(part)

    def _dropped(self, engine: Engine, entity: int) -> None:
        """A held object went away: its grips went with it (the backend removed them)."""
        for rig in self.hands.rigs.values():
            if entity in rig.grasps:
                engine.despawn(rig.grasps.pop(entity))
                _tell(engine, HandReleased(rig.hand, entity), "release")

    # -- each frame ------------------------------------------------------------------
    @staticmethod
    def _tracker_pose(engine: Engine, hand: Hand, inputs: InputState
                      ) -> tuple[np.ndarray, ...] | None:
        """The tracker's world pose and velocities (through the hand's frame object), or
        None while it is not tracked."""
        tracker = inputs.tracker(hand.tracker)
        if tracker is None or not tracker.tracked:
            return None
        p, q = tracker.position, tracker.orientation
        v, w = tracker.velocity, tracker.angular_velocity
        if inputs.now - tracker.timestamp > STALE_AFTER:
            v = w = np.zeros(3)
        frame = None if hand.frame is None else engine.world.try_component(hand.frame,
                                                                           Transform)
        if frame is None:
            return p, q, v, w
        rot = quat_to_matrix(frame.orientation)
        arm = rot @ p
        return (frame.position + arm, quat_multiply(frame.orientation, q),
                frame.linear_velocity + np.cross(frame.angular_velocity, arm) + rot @ v,
                frame.angular_velocity + rot @ w)

    @staticmethod
    def _pose_of(engine: Engine, rig: _Rig, hand: Hand, inputs: InputState
                 ) -> tuple[np.ndarray, ...] | None:
        """The pose the palm is driven toward: its tracker's, or a fingered hand's tracked
        palm joint (velocities from its samples)."""
        if rig.limits is None:
            return HandDriveSystem._tracker_pose(engine, hand, inputs)
        sample = inputs.hand(hand.tracker)
        if sample is None:
            return None
        rig.palm_sample = hand_fingers.palm_pose(rig.palm_sample, sample, _frame(engine, hand),
                                                 inputs.now, STALE_AFTER)
        return rig.palm_sample[1:]

    def _move_controls(self, engine: Engine, driven: list[tuple[_Rig, Any]],
                       inputs: InputState | None) -> list[tuple[np.ndarray, ...] | None]:
        """Put every tracked hand's control body at its tracker's pose, with its
        velocities: one command for all of them (checked in one pass), before anything
        else of the frame, so a pose no body can take changes nothing else. Each hand's
        pose, or None where it is untracked or its pose was refused (told)."""
        poses = [None if inputs is None else self._pose_of(engine, rig, hand, inputs)
                 for rig, (hand, _, _) in driven]
        tracked = [i for i, pose in enumerate(poses) if pose is not None]
        if not tracked:
            return poses
        table = self._table
        if len(table) < len(tracked):
            table = self._table = np.empty((len(driven), 13))
        for row, i in enumerate(tracked):
            p, q, v, w = poses[i]  # type: ignore[misc]
            table[row, 0:3], table[row, 3:7], table[row, 7:10], table[row, 10:13] = p, q, v, w
        keys = [driven[i][0].control for i in tracked]
        rows = table[:len(tracked)]
        try:
            engine.physics.push(SetPoses(keys, rows))
        except CommandError:  # (outside the world, too fast): which hands, and why
            good = [row for row, i in enumerate(tracked) if self._takes(engine, driven[i],
                                                                        poses, i)]
            if good:
                engine.physics.push(SetPoses([keys[row] for row in good], rows[good]))
        return poses

    def _takes(self, engine: Engine, rig_comps: tuple[_Rig, Any],
               poses: list[tuple[np.ndarray, ...] | None], i: int) -> bool:
        """Whether a body can take hand ``i``'s pose; told, and its pose dropped, if not."""
        rig, (hand, _, _) = rig_comps
        try:
            check_limits(SetPose(rig.control, *poses[i]), engine.physics.limits)  # type: ignore[misc]
        except CommandError as exc:
            self.hands.messages.error(
                f"hand {rig.name!r}: tracker {hand.tracker!r} gave a pose no body can take "
                f"({exc}); the hand holds still as if untracked", f"frame {engine.frame}: ")
            poses[i] = None
            return False
        return True

    def _drive(self, engine: Engine, rig: _Rig, hand: Hand, state: HandState,
               t: Transform, pose: tuple[np.ndarray, ...] | None, dt: float) -> None:
        """One hand's frame, its control body already moved (:meth:`_move_controls`)."""
        physics = engine.physics
        if pose is None:
            if state.tracked or rig.lost_for == 0.0:  # hold still where the hand is
                physics.push(SetVelocity(rig.control, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
            state.tracked = False
            rig.lost_for += dt
            if rig.lost_for >= RELEASE_AFTER and rig.grasps:
                self.hands.messages.warn(f"hand {rig.name!r}: its tracker {hand.tracker!r} is "
                                         f"lost; it lets go", f"frame {engine.frame}: ")
                self.hands.let_go(engine, rig)
            self._look(engine, rig, hand, state)
            return
        position, orientation, velocity, spin = pose
        state.tracked, rig.lost_for = True, 0.0
        d = math.dist(t.position.tolist(), position.tolist())
        state.deviation = d
        limit = hand.deviation_distance
        if d > TELEPORT_DISTANCE:
            self.hands.let_go(engine, rig)
            physics.set_pose(rig.hand, position, orientation)
            physics.set_velocity(rig.hand, velocity, spin)
            if rig.fingers is not None and rig.fingers.sample is not None:
                for bone, c, q in zip(rig.fingers.bones, *rig.fingers.sample[1:], strict=True):
                    physics.set_pose(bone, c, q)
        if state.colliding and d > limit:
            physics.push(SetCollisionEnabled(rig.hand, False))
            state.colliding = False
        elif not state.colliding and d < COLLIDE_AGAIN * limit:
            self._collide_again(engine, rig, state)
        if rig.fingers is not None:
            hand_fingers.set_colliding(engine, rig.fingers, state.colliding)
        self._look(engine, rig, hand, state)

    def _collide_again(self, engine: Engine, rig: _Rig, state: HandState) -> None:
        """Collide again once the hand overlaps nothing but what it holds (asked of the
        backend; in threaded mode the answer comes a frame later)."""
        if rig.overlap is None:
            hand = rig.hand
            rig.overlap = engine.physics.request(lambda backend: backend.overlapping(hand))
        if not rig.overlap.done():
            return
        future, rig.overlap = rig.overlap, None
        if future.exception() is not None:
            return
        if not set(future.result()) - set(rig.grasps):
            engine.physics.push(SetCollisionEnabled(rig.hand, True))
            state.colliding = True

    @staticmethod
    def _look(engine: Engine, rig: _Rig, hand: Hand, state: HandState) -> None:
        """The hand's look: its mode's model (or the author's look, tinted in contact and
        grasp), see-through in the band of 5.4, grey while untracked. Written only when
        one of those changes (a change rebuilds its draw; a script may recolour the hand
        in between)."""
        low, high = SEE_THROUGH
        through = low * hand.deviation_distance <= state.deviation <= \
            high * hand.deviation_distance
        shown = (state.mode, state.tracked, through)
        if shown == rig.shown:
            return
        rig.shown = shown
        visual = engine.world.try_component(rig.hand, Visual)
        if visual is None:
            return
        model, color = rig.look
        mode = HandMode(state.mode)
        own = {HandMode.NEUTRAL: hand.neutral_model, HandMode.CONTACT: hand.contact_model,
               HandMode.GRASP: hand.grasp_model}
        if own.get(mode):
            model = own[mode]
        elif mode in TINTS:
            color = (*TINTS[mode], color[3])
        if not state.tracked:
            color = (*UNTRACKED, color[3])
        if through:
            color = (*color[:3], SEE_THROUGH_ALPHA)
        if (visual.model, tuple(visual.color), visual.overlay) != (model, color, through):
            visual.model, visual.color, visual.overlay = model, color, through


class HandContactSystem(System):
    """POST_PHYSICS: what each hand touches (its mode) and the force its contacts pushed
    with; :class:`HandTouched` for what it begins to touch; grips pulled beyond the
    hand's ``BreakForce`` let go."""

    phase = Phase.POST_PHYSICS
    before = ("OutputSystem",)  # a glove gets this step's force this frame, not the next
    reads = (Hand, HandState, Physical, Graspable, Transform, Name, Joint)
    writes = (HandState, Name, Joint)

    def __init__(self, hands: Hands) -> None:
        self.hands = hands
        self._seen: tuple[int, float] = (-1, 0.0)  # the physics step and time last told

    def run(self, engine: Engine, dt: float) -> None:
        rigs = self.hands.rigs
        if not rigs:
            return
        frames = engine.events.frame(Contacts)
        snapshot = engine.physics.snapshot
        # a frame without a physics step (threaded mode) has no contacts and says nothing
        # about touching: what the last step said holds (else the mode would flicker)
        stepped = bool(frames) or snapshot.step != self._seen[0]
        elapsed = snapshot.time - self._seen[1] if self._seen[0] >= 0 else dt
        if stepped:
            self._seen = (snapshot.step, snapshot.time)
        contacts = _contact_batch(frames)
        touches = {} if contacts is None else _hand_contacts(contacts, self._owners(rigs))
        world = engine.world
        outputs = _outputs(engine)
        sent = frozenset() if outputs is None else outputs.sent  # what Output blocks name
        found = dict(world.get_components(Hand, HandState))
        for rig in rigs.values():
            comps = found.get(rig.hand)
            if comps is None:
                continue
            hand, state = comps
            if stepped:
                impulse, others = touches.get(rig.hand, (0.0, ()))
                # the steps' impulses over the physics time they took
                state.contact_force = impulse / (elapsed if elapsed > 0 else dt)
                if others or rig.touched_at:
                    self._touching(engine, rig, state, others, snapshot.time)
            if rig.fingers is not None:
                self._fingers(engine, rig, state, contacts if stepped else None,
                              elapsed if elapsed > 0 else dt)
            state.held = tuple(rig.grasps)
            state.mode = HandMode.GRASP if rig.grasps else HandMode.CONTACT if \
                state.touching else HandMode.NEUTRAL
            if rig.force_output in sent:
                outputs.set(rig.force_output, state.contact_force)
            if rig.grasp_output in sent:
                outputs.set(rig.grasp_output, 1.0 if rig.grasps else 0.0)
            if hand.break_force is not None and rig.grasps:
                self._strain(engine, rig, hand.break_force)

    @staticmethod
    def _owners(rigs: dict[int, _Rig]) -> dict[int, int]:
        """Each palm and bone -> its hand."""
        owners = {rig.hand: rig.hand for rig in rigs.values()}
        for rig in rigs.values():
            if rig.fingers is not None:
                owners.update(dict.fromkeys(rig.fingers.bones, rig.hand))
        return owners

    def _fingers(self, engine: Engine, rig: _Rig, state: HandState,
                 contacts: np.ndarray | None, elapsed: float) -> None:
        """A fingered hand after a step: what its thumb and an opposing finger or its palm
        grip is held (:func:`~systems.hand_fingers.opposed`); which parts grip what it
        holds."""
        fingers = rig.fingers
        assert fingers is not None
        world = engine.world
        if contacts is not None:
            owner: dict[int, str] = {**fingers.finger_of, rig.hand: "palm"}
            pressed = hand_fingers.presses(contacts, owner, elapsed) if len(contacts) else {}
            fingers.pressing = {obj: tuple(parts) for obj, parts in pressed.items()}
            for obj, parts in pressed.items():
                grip = hand_fingers.opposed(parts)
                if not grip or obj in rig.grasps or not _graspable(world, obj):
                    continue
                # closing on it: the tracked grip narrower than the physical one round it
                # (fingers opening off it still touch it; they do not take it again)
                palm = world.component_for_entity(rig.hand, Transform).position
                width = hand_fingers.grip_width(fingers, grip, parts,
                                                hand_fingers.tips_now(engine, fingers), palm)
                if hand_fingers.aperture(fingers, grip) > width - hand_fingers.CLOSING:
                    continue
                try:
                    self.hands.attach(engine, rig, obj)
                except ValueError as exc:
                    self.hands.messages.warn(f"hand {rig.name!r}: {exc}")
                    continue
                # the tracked grip lets go once it opens RELEASE_BAND wider than this
                fingers.grips[obj] = (grip, width)
        parts = set()
        for obj in rig.grasps:
            parts.update(fingers.grips[obj][0] if obj in fingers.grips else
                         fingers.pressing.get(obj, ()))
        state.grip = tuple(p for p in (*hand_fingers.FINGERS, "palm") if p in parts)

    @staticmethod
    def _touching(engine: Engine, rig: _Rig, state: HandState, others: list[int],
                  now: float) -> None:
        """What the hand touches after this step: the graspable objects among ``others``,
        and those it touched within :data:`TOUCH_HOLD`; HandTouched for each new one."""
        world = engine.world
        for obj in others:
            if _graspable(world, obj):
                rig.touched_at[obj] = now
        rig.touched_at = {o: t for o, t in rig.touched_at.items()
                          if now - t <= TOUCH_HOLD and world.entity_exists(o)}
        touching = tuple(sorted(rig.touched_at))
        if touching != state.touching:
            for obj in set(touching) - set(state.touching):
                engine.events.emit(HandTouched(rig.hand, obj))
            state.touching = touching

    def _strain(self, engine: Engine, rig: _Rig, limit: float) -> None:
        """Let go of what a grip carried more than ``limit`` N for in the last step (see
        :func:`_grip_load`; asked of the backend, in threaded mode a frame later)."""
        if rig.strain is None:
            grips = dict(rig.grasps)
            rig.strain = grips, engine.physics.request(lambda backend: {
                obj: backend.joint_force(joint) for obj, joint in grips.items()
                if backend.has_joint(joint)})
        grips, future = rig.strain
        if not future.done():
            return
        rig.strain = None
        if future.exception() is not None:
            self.hands.messages.error(f"hand {rig.name!r}: its grips' force could not be "
                                      f"measured ({future.exception()}); BreakForce is not "
                                      "applied")
            return
        world = engine.world
        hand = world.component_for_entity(rig.hand, Transform).position
        for obj, on_hand in future.result().items():
            t = world.try_component(obj, Transform)
            if t is None or rig.grasps.get(obj) != grips[obj]:
                continue
            load = _grip_load(-on_hand, t.position - hand)
            if load > limit:
                log.info("hand %r: its grip on %r carried %.4g N > BreakForce %.4g N; it "
                         "lets go", rig.name, _name(world, obj), load, limit)
                self.hands.let_go(engine, rig, [obj])


def _grip_load(on_object: np.ndarray, away: np.ndarray) -> float:
    """The force a grip carries, from what it puts on the object (N) and ``away`` (from
    the hand to the object): the pull toward the hand, and the shear beyond what
    friction of the object pressed against the palm holds (:data:`GRIP_FRICTION` times
    the press). A press alone the palm takes (a held cup pushed into a table)."""
    n = float(np.linalg.norm(away))
    if n == 0.0:
        return float(np.linalg.norm(on_object))
    d = away / n
    along = float(on_object @ d)  # > 0: pressed away from the hand
    shear = float(np.linalg.norm(on_object - along * d))
    return math.hypot(max(-along, 0.0), max(shear - GRIP_FRICTION * max(along, 0.0), 0.0))


def _contact_batch(frames: list[Contacts]) -> np.ndarray | None:
    """The contacts of the steps since the last frame, in one array (None: none)."""
    batches = [c.batch for c in frames if len(c.batch)]
    if not batches:
        return None
    return np.concatenate(batches) if len(batches) > 1 else batches[0]


def _hand_contacts(contacts: np.ndarray | None, owners: dict[int, int]
                   ) -> dict[int, tuple[float, list[int]]]:
    """Each hand in a contact this step: its contacts' summed impulse and what it touched
    (``owners``: each palm and bone -> its hand). Hands are a few entity ids among the
    step's contacts: a range test in numpy narrows the contacts to those near the hands'
    ids, a set picks the hands' own."""
    if contacts is None:
        return {}
    a, b = contacts["a"], contacts["b"]
    low, high = min(owners), max(owners)
    rows = np.flatnonzero(((a >= low) & (a <= high)) | ((b >= low) & (b <= high)))
    out: dict[int, tuple[float, list[int]]] = {}
    impulses = contacts["impulse"][rows].tolist()
    for x, y, impulse in zip(a[rows].tolist(), b[rows].tolist(), impulses, strict=True):
        for part, other in ((x, y), (y, x)):
            hand = owners.get(part)
            if hand is not None:
                total, others = out.get(hand, (0.0, []))
                others.append(other)
                out[hand] = (total + impulse, others)
    return out


def _graspable(world: Any, entity: int) -> bool:
    if entity < 0:
        return False
    physical = world.try_component(entity, Physical)
    if physical is None or physical.kind != BodyKind.DYNAMIC or \
            world.has_component(entity, Hand):
        return False
    grasp = world.try_component(entity, Graspable)
    return grasp is None or grasp.enabled


def _outputs(engine: Engine) -> Any:
    from systems.input import Outputs

    return engine.try_resource(Outputs)


class HandsPlugin:
    """Virtual hands (``requestPlugin("hands")``; the paper's "interaction")."""

    name = PluginName.HANDS

    def build(self, engine: Engine) -> None:
        from systems.input import InputPlugin

        engine.add_plugin(InputPlugin())  # the trackers and gloves hands follow
        hands = Hands()
        engine.insert_resource(hands)
        engine.insert_resource(hands, as_type=HandControl)
        engine.add_system(HandDriveSystem(hands))
        engine.add_system(HandContactSystem(hands))
        engine.add_system(GhostFingerSystem(SEE_THROUGH_ALPHA))  # a blocked finger's look
