"""The Lua scripting API: what a script can do to the running simulation.

Every name below is a global in each script and also a field of the
``colosseum`` table. Vectors are passed as three numbers or a table
``{x, y, z}`` and returned as three numbers (orientations: four, ``w, x, y, z``).
Objects are handles (``find`` returns them, callbacks receive them); ``self`` is
the object a script is attached to (nil for a scene script).

Objects (``obj:method(...)``)::

    obj.id                          entity id;  obj:getName() -> the scene ID
    obj:getPosition() -> x, y, z    obj:setPosition(x, y, z)
    obj:getOrientation() -> w,x,y,z obj:setOrientation(w, x, y, z)
    obj:getVelocity() -> x, y, z    obj:setVelocity(x, y, z)
    obj:getAngularVelocity()        obj:setAngularVelocity(x, y, z)   (rad/s)
    obj:addForce(fx, fy, fz [, px, py, pz])   for the next physics step (N, world point)
    obj:addTorque(tx, ty, tz)       obj:addImpulse(ix, iy, iz [, px, py, pz])
    obj:setKinematicTarget(x, y, z) obj:delete()
    obj:playSound()                 obj:stopSound()   (its Sound component)
    obj:setGain(gain)               volume of its sound, now and for later plays
    hand:getHandState() -> "neutral" | "contact" | "grasp"   (a virtual hand's mode; also
    hand.state)   hand:getHeld() -> {obj, ...} (also hand.held)   hand:grasp(obj)
    hand:release()  hand:getGrip() -> {"thumb", "index", ...} the fingers holding (also
    hand.grip; "palm" too; empty for a palm-only hand)
    hand:joint(name) -> x, y, z, qw, qx, qy, qz, radius, valid   a tracked joint of the
                                    hand's input hand in the world ("index_tip", "palm",
                                    ...: services.input.events.HAND_JOINTS), nil before seen
    hand:curl(finger) -> 0..1       how bent the tracked finger is ("thumb" to "little")

Avatars (``Avatar`` blocks; the avatars plugin)::

    avatar:play(clip [, {fade=s, speed=x, loop=bool}])   crossfade to a clip now
    avatar:queue(clip or {Walk=w, ...} [, opts])         start it when the current ends
    avatar:blend{Walk=0.7, Run=0.3} [, opts]             clips at once, in step; called
                                    again with the same clips, only the weights change
    avatar:stopAnimation([{fade=s}])  avatar:animation() -> clip, seconds   avatar:clips()
    avatar:setPath({{x, y, z}, ...} [, loop])            walk through points
    avatar:hold(obj, bone [, {offset={..}, orientation={..}}])   avatar:release(obj)
    avatar:driveBone(bone, {x, y, z}, {w, x, y, z})      a tracked hand: the arm bends to it
    avatar:releaseBone(bone)        avatar:bonePose(bone) -> x, y, z, w, x, y, z

Scene and engine::

    find(id) -> obj or nil          spawn(sceneText) -> {obj, ...}   (scene format)
    delete(obj)                     setMotor(joint, velocity, maxForce)
    createJoint{kind=, a=obj, b=obj|nil, anchor={..}, axis={..}, low=, high=, id=,
                spring={stiffness=, damping=, target=, maxForce=}}   (radians, N·m/rad;
        a slider's in m, N/m) -> joint id;   breakJoint(joint)   (joint: id string or number)
    playSound(obj) / stopSound(obj) / setGain(obj, gain)
    setUniform(state, name, value | {v1, v2, ...})
    setAnomaly(id, on [, {param=value, onset=s, eye="left"}])   a visual anomaly (a name of
                                    engine.anomalies.ANOMALIES or a scene block's ID): on
                                    true/false switches it (its effect ramps over onset s),
                                    nil leaves it; params as the scene keys, lower-case first
                                    (offset={2, 0}, mix=0.5, side="right", sparing=5); out of
                                    range: clamped, told at the calling line
    getAnomaly(id) -> {kind=, enabled=, level=, onset=, eye=, <params>}
    enablePost(id, on)              setPostUniform(id, uniform, value)   a scene's PostPass
    setCamera{position=, lookAt=, follow=obj, offset=, fov=, id=}
    haptic(hand, amplitude, seconds) -> bool   pulse the headset controller driving a hand
                                    (a hand object or a tracker name, "hand_r"); amplitude 0..1
    recenter()                      put the headset's wearer over the camera, facing its way
    requestPlugin(name) -> bool     (the engine's plugin names and the paper's aliases:
                                     osg, osgsim -> render; openalpp -> sound; the paper's
                                     spelling ``requrestPlugin`` works too)
    time() -> simulated seconds     log(...), warn(...), print(...)
    measure(name, value)            a final value of the run (--stats measures, sweeps)
    experiment:condition(factor) -> the level (text) of the trial running, nil outside one
    experiment:trial() -> the trial running or nil: index, block, blockTrial, practice,
                                    condition, participant, staircase, intensity;
                                    trial:respond(name, value) records a response,
                                    trial:finish(outcome) ends it (``experiment``: colosseum
                                    experiment run, docs/experiments.md)
    after(sec, fn) / every(sec, fn) -> timer; cancel(timer)
    on(name, fn(data, name)); emit(name, data)   custom events (also seen by Python);
                                    data is plain data: objects in it arrive as entity ids

Callbacks a script may define: ``onStart()``, ``onUpdate(dt)``,
``onCollision(other, impulse)`` (object scripts) or ``onCollision(a, b,
impulse)`` (scene scripts; ``b`` is nil for static world geometry), called once
per frame for every pair of bodies in contact, with the impulse (N s) summed
over the pair's contacts and steps; ``onCollisionBegin(other, impulse)`` /
``onCollisionBegin(a, b, impulse)`` once when a pair starts touching and
``onCollisionEnd(other)`` / ``onCollisionEnd(a, b)`` once when it stops (bodies
asleep on each other still touch; see :mod:`systems.contacts`);
``onKey(key, pressed)``, ``onButton(device, name, pressed)`` (a glove's pinch, a
controller's trigger), ``onTracker(name, x, y, z, qw, qx, qy, qz)`` (once a frame
per tracker that moved, calibrated), ``onInput(device, value)``
(``axis:DEVICE/NAME`` values and ``wheel:NAME`` counts), ``onDeviceLost(name)`` /
``onDeviceFound(name)``, ``onTouch(hand, object)`` / ``onGrasp(hand, object, fingers)``
/ ``onRelease(hand, object, fingers)`` (a virtual hand's, told to the hand's scripts, the
object's and the scene's; ``fingers``: the fingers that hold it, a table as
``hand:getGrip()``), ``onTimer(name)`` (engine TimerEvents),
``onAnimationEnd(clip)`` (an avatar's scripts; scene scripts ``onAnimationEnd(avatar,
clip)``), ``onReload()``
(after the file changed and was re-run in the script's environment: write ``count =
count or 0`` to keep state across reloads), ``onResume()`` (instead of ``onStart``
when a saved state runs: the script's variables, timers and handlers are back, see
:mod:`services.scripting.persist`), ``onTrialStart(trial)`` and ``onTrialEnd(trial)`` (a
trial of ``colosseum experiment run`` begins, its condition set, and ends).

Input state, any time (nil before a device has said anything)::

    input.tracker(name) -> x, y, z, qw, qx, qy, qz, tracked
    input.wheel(name) -> rad/s          input.button(device, name) -> bool
    input.axis(device, name) -> value   input.key(name) -> bool

Limits: each callback runs under an instruction budget (time in C library
calls counts too); a script exceeding it, or the memory cap, is stopped with one
message; a callback failing three times is disabled. Errors read
``scripts/name.lua:LINE: message`` followed by a Lua traceback.

Everything that touches physics (forces, poses, motors, joints, spawning,
deleting) becomes a physics command (:mod:`engine.physics.commands`), checked
when the call is made — a bad value fails at the script's line — and queued,
so the same script behaves alike in serial and threaded mode. Missing
subsystems (no sound or render plugin loaded) turn their calls into no-ops
with one warning each.
"""

from __future__ import annotations

import difflib
import logging
import math
from collections import OrderedDict
from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING, Any, TypeVar

from components import Camera, Hand, HandState, Joint, Name, Physical, Sound, Transform
from components.joint import SCENE_JOINT_TYPES, JointKind, Spring
from engine.anomalies import Anomalies
from engine.messages import MessageLog
from engine.physics import commands as cmd
from engine.services import (
    AVATAR_METHODS,
    AvatarControl,
    ExperimentControl,
    HandControl,
    HeadsetControl,
    ShaderControl,
    SoundControl,
)
from engine.system import PluginName
from services.input.events import HandJoints
from services.input.hand_query import finger_curl, finger_named, joint_index, tracked_hand
from services.input.hand_query import joint as hand_joint
from services.input.state import InputState
from services.scripting.runtime import ScriptRuntime, to_python

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.script")

S = TypeVar("S")

#: The joint kinds a script may create: those a scene file may declare.
JOINT_KINDS = tuple(SCENE_JOINT_TYPES.values())
#: Scene IDs of deleted objects remembered, so a call on one still names it.
GONE_NAMES = 1024


def _number(value: Any) -> float:
    """A script's number (not a boolean, which Python would take for 0 or 1)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"not a number: {value!r}")
    return float(value)


def _numbers(value: Any) -> tuple[float, ...]:
    return tuple(_number(v) for v in value)


#: A createJoint spring's fields (engine units: per radian, radians; N·m, or N and m for a
#: slider) and the Spring fields they set.
_SPRING_FIELDS = {"stiffness": "stiffness", "damping": "damping", "target": "target",
                  "maxForce": "max_force"}


def _spring(value: Any) -> Spring:
    """A script's ``spring={stiffness=, damping=, target=, maxForce=}`` as a Spring (its
    values are checked where every joint's are: the AddJoint command)."""
    if not isinstance(value, dict) or any(k not in _SPRING_FIELDS for k in value):
        raise ValueError(f"not a spring table: {value!r}")
    return Spring(**{_SPRING_FIELDS[k]: _number(v) for k, v in value.items()})


#: createJoint's fields: how each is read, and what it must be (for the message).
_JOINT_FIELDS: dict[str, tuple[Callable[[Any], Any], str]] = {
    "anchor": (_numbers, "a table {x, y, z}"), "axis": (_numbers, "a table {x, y, z}"),
    "axis2": (_numbers, "a table {x, y, z}"), "low": (_number, "a number"),
    "high": (_number, "a number"), "motor_velocity": (_number, "a number"),
    "motor_max_force": (_number, "a number"), "id": (str, "a string"),
    "spring": (_spring, "a table {stiffness=, damping=, target=, maxForce=} of numbers"),
}


def _finite(what: str, key: str, value: Any, n: int) -> tuple[float, ...]:
    """``n`` finite numbers from a script's value, or ScriptAPIError naming ``key``."""
    try:
        numbers = tuple(_number(v) for v in value)
    except (TypeError, ValueError):
        numbers = ()
    if len(numbers) != n or not all(map(math.isfinite, numbers)):
        form = "a number" if n == 1 else f"{n} finite numbers {{x, y, z}}"
        raise ScriptAPIError(f"{what}: {key} must be {form}, got {value!r}")
    return numbers


class ScriptAPIError(RuntimeError):
    """A script called the API wrongly; the message is shown as ``file:line: message``."""


_LUA_API = r"""
local K, P = ...
local Object, handle, id_of = K.Object, K.handle, K.id_of
local type, error = type, error

local function on(h)  -- " for object \"ID\"" when h is an object's handle
  local id = id_of(h)
  return id == nil and "" or " for " .. P.called(id)
end
local function vec(what, x, y, z, h)
  if type(x) == "table" then x, y, z = x[1], x[2], x[3] end
  if type(x) ~= "number" or type(y) ~= "number" or type(z) ~= "number" then
    error(what .. ": expected three numbers or a table {x, y, z}" .. on(h), 3)
  end
  return x, y, z
end
local function point(what, x, y, z, h)
  if x == nil then return nil, nil, nil end
  return vec(what, x, y, z, h)
end
local function oid(what, h, owner)  -- owner: the object the call is on, named if h is bad
  local id = id_of(h)
  if id == nil then error(what .. ": expected an object, got " .. type(h) .. on(owner), 3) end
  return id
end
local function joint(what, j)
  if type(j) ~= "string" and type(j) ~= "number" then
    error(what .. ": expected a joint id (string or number), got " .. type(j), 3)
  end
  return j
end
local plain = K.plain

function Object.getName(h) return P.name(oid("getName", h)) end
function Object.getPosition(h) return P.get(oid("getPosition", h), 0) end
function Object.getOrientation(h) return P.get(oid("getOrientation", h), 1) end
function Object.getVelocity(h) return P.get(oid("getVelocity", h), 2) end
function Object.getAngularVelocity(h) return P.get(oid("getAngularVelocity", h), 3) end
function Object.setPosition(h, x, y, z)
  P.set_position(oid("setPosition", h), vec("setPosition", x, y, z, h))
end
function Object.setOrientation(h, w, x, y, z)
  if type(w) == "table" then w, x, y, z = w[1], w[2], w[3], w[4] end
  P.set_orientation(oid("setOrientation", h), w, x, y, z)
end
function Object.setVelocity(h, x, y, z)
  P.set_velocity(oid("setVelocity", h), 0, vec("setVelocity", x, y, z, h))
end
function Object.setAngularVelocity(h, x, y, z)
  P.set_velocity(oid("setAngularVelocity", h), 1, vec("setAngularVelocity", x, y, z, h))
end
function Object.addForce(h, x, y, z, px, py, pz)
  local fx, fy, fz = vec("addForce", x, y, z, h)
  P.push(oid("addForce", h), 0, fx, fy, fz, point("addForce", px, py, pz, h))
end
function Object.addTorque(h, x, y, z)
  P.push(oid("addTorque", h), 1, vec("addTorque", x, y, z, h))
end
function Object.addImpulse(h, x, y, z, px, py, pz)
  local ix, iy, iz = vec("addImpulse", x, y, z, h)
  P.push(oid("addImpulse", h), 2, ix, iy, iz, point("addImpulse", px, py, pz, h))
end
function Object.setKinematicTarget(h, x, y, z)
  P.kinematic(oid("setKinematicTarget", h), vec("setKinematicTarget", x, y, z, h))
end
function Object.delete(h) P.delete(oid("delete", h)) end
function Object.playSound(h) P.sound(oid("playSound", h), true) end
function Object.stopSound(h) P.sound(oid("stopSound", h), false) end
function Object.setGain(h, gain) P.set_gain(oid("setGain", h), gain) end
function Object.getHandState(h) return P.hand_state(oid("getHandState", h)) end
function Object.getHeld(h)
  local ids = P.hand_held(oid("getHeld", h))
  local out = {}
  for i = 1, #ids do out[i] = handle(ids[i]) end
  return out
end
function Object.grasp(h, other) P.hand_grasp(oid("grasp", h), oid("grasp", other, h)) end
function Object.getGrip(h) return P.hand_grip(oid("getGrip", h)) end
K.Fields.state, K.Fields.held = Object.getHandState, Object.getHeld  -- hand.state, hand.held
K.Fields.grip = Object.getGrip  -- hand.grip
function Object.joint(h, name) return P.hand_joint(oid("joint", h), name) end
function Object.curl(h, finger) return P.hand_curl(oid("curl", h), finger) end
for i = 1, #P.avatar_methods do  -- avatar:play("Run", {fade=0.3}), avatar:blend{...}, ...
  local method = P.avatar_methods[i]
  Object[method] = function(h, ...)
    return P.avatar(oid(method, h), method, plain({...}))
  end
end
local avatar_release = Object.release
function Object.release(h, ...)  -- a hand lets go of all it holds; an avatar, its object
  local id = oid("release", h)
  if P.is_hand(id) then return P.hand_release(id) end
  return avatar_release(h, ...)
end

local C = {}
function C.find(name) return handle(P.find(name)) end
function C.spawn(text)
  if type(text) ~= "string" then error("spawn: expected scene-format text", 2) end
  local ids = P.spawn(text)
  local out = {}
  for i = 1, #ids do out[i] = handle(ids[i]) end
  return out
end
function C.delete(h) P.delete(oid("delete", h)) end
function C.setMotor(j, velocity, maxForce)
  P.set_motor(joint("setMotor", j), velocity, maxForce)
end
function C.createJoint(spec)
  if type(spec) ~= "table" then error("createJoint: expected a table {kind=, a=, b=, ...}", 2) end
  return P.create_joint(plain(spec))
end
function C.breakJoint(j) P.break_joint(joint("breakJoint", j)) end
function C.playSound(h) P.sound(oid("playSound", h), true) end
function C.stopSound(h) P.sound(oid("stopSound", h), false) end
function C.setGain(h, gain) P.set_gain(oid("setGain", h), gain) end
function C.setUniform(state, name, value)
  P.set_uniform(state, name, plain(value))
end
function C.setCamera(opts)
  if type(opts) ~= "table" then error("setCamera: expected a table of options", 2) end
  P.set_camera(plain(opts))
end
function C.setAnomaly(id, on, params)
  if type(id) ~= "string" then
    error("setAnomaly: expected an anomaly's name or ID, got " .. type(id), 2)
  end
  if on ~= nil and type(on) ~= "boolean" then
    error("setAnomaly: the second argument switches it: true, false or nil, got " .. type(on), 2)
  end
  if params ~= nil and type(params) ~= "table" then
    error("setAnomaly: the third argument is a table of parameters, got " .. type(params), 2)
  end
  P.set_anomaly(K.where(2), id, on, plain(params))
end
function C.getAnomaly(id) return P.get_anomaly(id) end
function C.enablePost(id, on) P.enable_post(id, on ~= false) end
function C.setPostUniform(id, name, value) P.set_post_uniform(id, name, plain(value)) end
function C.haptic(hand, amplitude, seconds)
  if type(hand) ~= "string" then hand = oid("haptic", hand) end
  return P.haptic(hand, amplitude, seconds)
end
function C.recenter() P.recenter() end
function C.requestPlugin(name) return P.request_plugin(name) end
C.requrestPlugin = C.requestPlugin
function C.time() return P.time() end
function C.measure(name, value) P.measure(name, value) end

local E = {}  -- the experiment running (colosseum experiment run), as experiment:...
function E:condition(name) return P.experiment("condition", name) end
function E:trial() return P.experiment("trial") end
C.experiment = E

local I = {}
function I.tracker(name) return P.tracker(name) end
function I.wheel(name) return P.wheel(name) end
function I.button(device, name) return P.button(device, name) end
function I.axis(device, name) return P.axis(device, name) end
function I.key(name) return P.key(name) end
C.input = I

local G = {colosseum = C}
for k, v in pairs(C) do G[k] = v end
return G
"""


class NameIndex:
    """Scene ID -> the entities named so (the latest last), kept by the world's Name
    hooks: finding an object costs the same in a world of any size, and a deleted
    object's ID leaves the index with it (a script spawning and deleting forever grows
    nothing). The IDs of the last :data:`GONE_NAMES` deleted entities are remembered, so
    a call on one still names it."""

    def __init__(self, world: Any) -> None:
        self._by_name: dict[str, list[int]] = {}
        self.gone: OrderedDict[int, str] = OrderedDict()
        world.on_add(Name, self._added)
        world.on_remove(Name, self._removed)
        for entity, name in sorted(world.get_component(Name), key=lambda pair: pair[0]):
            self._added(entity, name)

    def _added(self, entity: int, name: Name) -> None:
        self._by_name.setdefault(name.id, []).append(entity)

    def _removed(self, entity: int, name: Name) -> None:
        found = self._by_name.get(name.id)
        if found is not None and entity in found:
            found.remove(entity)
            if not found:
                del self._by_name[name.id]
        self.gone[entity] = name.id
        if len(self.gone) > GONE_NAMES:
            self.gone.popitem(last=False)

    def entities(self, name: str) -> list[int]:
        """The entities named ``name``, the latest last (empty: none)."""
        return self._by_name.get(name, [])


class LivePoses(Mapping[str, tuple[tuple[float, ...], tuple[float, ...]]]):
    """Object ID -> current pose (position, quaternion) of the latest body of that ID,
    read when asked: what a spawned snippet's joints may attach to, without copying the
    world's poses on every spawn."""

    def __init__(self, world: Any, names: NameIndex) -> None:
        self._world, self._names = world, names

    def _body(self, name: str) -> Transform | None:
        for entity in reversed(self._names.entities(name)):
            if self._world.has_component(entity, Physical):
                return self._world.try_component(entity, Transform)
        return None

    def __getitem__(self, name: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
        t = self._body(name) if isinstance(name, str) else None
        if t is None:
            raise KeyError(name)
        return tuple(map(float, t.position)), tuple(map(float, t.orientation))

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self._body(name) is not None

    def __iter__(self) -> Iterator[str]:  # the whole world: only for "did you mean"
        return (n.id for _, (n, _t, _p) in self._world.get_components(Name, Transform,
                                                                      Physical))

    def __len__(self) -> int:
        return sum(1 for _ in self)


class ScriptAPI:
    """The Python side of the API, bound to one engine (main thread only)."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self._names = NameIndex(engine.world)
        self._poses = LivePoses(engine.world, self._names)
        self._warned: set[str] = set()
        self._messages = MessageLog(log)
        self.runtime: ScriptRuntime | None = None

    def flush(self) -> None:
        """Tell the repeats of messages said once (at the end of a run)."""
        self._messages.flush()

    def _called(self, entity: int, joint: bool = False) -> str:
        """How a message names an object (or joint): by its scene ID."""
        named = self.engine.world.try_component(entity, Name) \
            if self.engine.world.entity_exists(entity) else None
        name = named.id if named is not None else self._names.gone.get(entity)
        what = "joint" if joint else "object"
        return f'{what} "{name}"' if name else f"an unnamed {what}"

    def _command(self, what: str, make: Callable[..., cmd.Command], *args: Any,
                 target: str | None = None) -> cmd.Command:
        """The command ``make(*args)``, checked as made and against the world's limits; a
        bad value fails here, at the script's line: ``what: why for object "ID"`` (or
        for ``target``)."""
        try:
            command = make(*args)
            cmd.check_limits(command, self.engine.physics.limits)
        except cmd.CommandError as exc:
            if target is None and args and isinstance(args[0], int):
                target = self._called(args[0], make.on_joint)  # type: ignore[attr-defined]
            on = "" if target is None else f" for {target}"
            raise ScriptAPIError(f"{what}: {str(exc).partition(': ')[2]}{on}") from None
        return command

    def _push(self, what: str, make: Callable[..., cmd.Command], *args: Any) -> None:
        """Make the command (checked: :meth:`_command`) and queue it."""
        self.engine.physics.push(self._command(what, make, *args))

    def install(self, runtime: ScriptRuntime) -> Any:
        """Build the Lua API table for ``runtime`` (passed as ``api=`` to it)."""
        self.runtime = runtime
        P = runtime.lua.table_from({
            "name": self.name, "called": self._called, "get": self.get,
            "set_position": self.set_position,
            "set_orientation": self.set_orientation, "set_velocity": self.set_velocity,
            "push": self.push, "kinematic": self.kinematic, "delete": self.delete,
            "sound": self.sound, "find": self.find, "spawn": self.spawn,
            "set_motor": self.set_motor, "create_joint": self.create_joint,
            "break_joint": self.break_joint, "set_uniform": self.set_uniform,
            "set_gain": self.set_gain, "hand_state": self.hand_state,
            "hand_held": self.hand_held, "hand_grasp": self.hand_grasp,
            "hand_release": self.hand_release, "is_hand": self.is_hand,
            "hand_grip": self.hand_grip, "hand_joint": self.hand_joint,
            "hand_curl": self.hand_curl,
            "set_camera": self.set_camera, "request_plugin": self.request_plugin,
            "time": self.time, "measure": self.measure, "tracker": self.tracker,
            "wheel": self.wheel,
            "button": self.button, "axis": self.axis, "key": self.key,
            "avatar": self.avatar, "set_anomaly": self.set_anomaly,
            "get_anomaly": self.get_anomaly, "enable_post": self.enable_post,
            "set_post_uniform": self.set_post_uniform, "experiment": self.experiment,
            "avatar_methods": runtime.lua.table_from(AVATAR_METHODS),
        })
        return runtime.lua.execute(_LUA_API, runtime.kernel, P, name="=colosseum")

    # -- lookup ---------------------------------------------------------------
    def find(self, name: Any) -> int:
        """Entity id of the object whose scene ID is ``name`` (-1: none)."""
        if isinstance(name, int | float) and not isinstance(name, bool):
            if not (math.isfinite(name) and float(name).is_integer()):
                return -1
            entity = int(name)
            return entity if self.engine.world.entity_exists(entity) else -1
        if not isinstance(name, str):
            raise ScriptAPIError(f"find: expected an object ID string, got {name!r}")
        found = self._names.entities(name)
        return found[-1] if found else -1

    def _entity(self, entity: int, what: str) -> int:
        if not self.engine.world.entity_exists(entity):
            raise ScriptAPIError(f"{what}: {self._called(entity)} no longer exists "
                                 "(it was deleted)")
        return entity

    def _joint(self, ref: Any, what: str) -> tuple[int, Joint]:
        entity = self.find(ref)
        joint = self.engine.world.try_component(entity, Joint) if entity >= 0 else None
        if joint is None:
            known = sorted(j.id for _, j in self.engine.world.get_component(Joint) if j.id)
            hint = difflib.get_close_matches(str(ref), known, 1)
            extra = f"; did you mean {hint[0]!r}?" if hint else f" (joints: {', '.join(known)})"
            raise ScriptAPIError(f"{what}: no joint {ref!r}{extra}")
        return entity, joint

    def name(self, entity: int) -> str | None:
        named = self.engine.world.try_component(self._entity(entity, "getName"), Name)
        return None if named is None else named.id

    # -- state ------------------------------------------------------------------
    def _transform(self, entity: int, what: str) -> Transform:
        t = self.engine.world.try_component(self._entity(entity, what), Transform)
        if t is None:
            raise ScriptAPIError(f"{what}: {self._called(entity)} has no position")
        return t

    def get(self, entity: int, which: int) -> tuple[float, ...]:
        t = self._transform(entity, "get")
        arr = (t.position, t.orientation, t.linear_velocity, t.angular_velocity)[which]
        return tuple(arr.tolist())

    def set_position(self, entity: int, x: float, y: float, z: float) -> None:
        t = self._transform(entity, "setPosition")
        self._set_pose("setPosition", entity, t, (x, y, z), t.orientation)

    def set_orientation(self, entity: int, w: float, x: float, y: float, z: float) -> None:
        t = self._transform(entity, "setOrientation")
        self._set_pose("setOrientation", entity, t, t.position, (w, x, y, z))

    def _set_pose(self, what: str, entity: int, t: Transform, position: Any,
                  orientation: Any) -> None:
        """Check the pose (a SetPose command), teleport the body if it has one, and write
        the Transform so the script reads back what it set."""
        pose = self._command(what, cmd.SetPose, entity, position, orientation)
        if self.engine.world.has_component(entity, Physical):
            self.engine.physics.set_pose(entity, pose.position, pose.orientation)
        t.position[:] = pose.position
        t.orientation[:] = pose.orientation

    def set_velocity(self, entity: int, which: int, x: float, y: float, z: float) -> None:
        what = "setVelocity" if which == 0 else "setAngularVelocity"
        t = self._transform(entity, what)
        linear = (x, y, z) if which == 0 else t.linear_velocity
        angular = (x, y, z) if which == 1 else t.angular_velocity
        velocity = self._command(what, cmd.SetVelocity, entity, linear, angular)
        if self.engine.world.has_component(entity, Physical):
            self.engine.physics.set_velocity(entity, velocity.linear, velocity.angular)
        t.linear_velocity[:] = velocity.linear
        t.angular_velocity[:] = velocity.angular

    def push(self, entity: int, kind: int, x: float, y: float, z: float,
             px: float | None = None, py: float | None = None, pz: float | None = None) -> None:
        what = ("addForce", "addTorque", "addImpulse")[kind]
        physical = self.engine.world.try_component(self._entity(entity, what), Physical)
        if physical is None:
            raise ScriptAPIError(f"{what}: {self._called(entity)} has no physical body")
        where = None if px is None else (px, py, pz)
        if kind == 1:
            self._push(what, cmd.ApplyTorque, entity, (x, y, z))
            return
        make = cmd.ApplyForce if kind == 0 else cmd.ApplyImpulse
        load = self._command(what, make, entity, (x, y, z), where)
        if physical.mass:  # the speed it gives in one step is known here: refused at the call
            seconds = self.engine.config.dt if kind == 0 else 1.0
            reach = math.hypot(x, y, z) * seconds / physical.mass
            limit = self.engine.physics.limits.max_speed
            if reach > limit:
                raise ScriptAPIError(
                    f"{what}: {math.hypot(x, y, z):g} {'N' if kind == 0 else 'N s'} on "
                    f"{physical.mass:g} kg gives {reach:g} m/s in one step, over the limit "
                    f"of {limit:g} m/s, for {self._called(entity)}")
        self.engine.physics.push(load)

    def kinematic(self, entity: int, x: float, y: float, z: float) -> None:
        what = "setKinematicTarget"
        t = self._transform(entity, what)
        dt = self.engine.config.dt
        target = self._command(what, cmd.SetKinematicTarget, entity, (x, y, z),
                               t.orientation, dt)
        limit = self.engine.physics.limits.max_speed
        speed = math.dist(target.position, t.position) / dt
        if speed > limit:  # known here, from where the body is: refused at the call
            raise ScriptAPIError(f"{what}: reaching ({x:g}, {y:g}, {z:g}) in one step of "
                                 f"{dt:g} s needs {speed:g} m/s, over the limit of "
                                 f"{limit:g} m/s, for {self._called(entity)}")
        self.engine.physics.push(target)

    def delete(self, entity: int) -> None:
        self.engine.despawn(entity)

    def time(self) -> float:
        return float(self.engine.time)

    def measure(self, name: Any, value: Any) -> None:
        """A final value of the run (the last one given wins): --stats measures, sweeps."""
        from engine.measures import Measures

        measures = self.engine.try_resource(Measures)
        if measures is None:
            measures = Measures()
            self.engine.insert_resource(measures)
        try:
            measures.set(name, value)
        except (TypeError, ValueError) as exc:
            raise ScriptAPIError(f"measure: {exc}") from None

    # -- structure --------------------------------------------------------------
    def spawn(self, text: str) -> Any:
        """Objects (and joints) from scene-format text, through the scene factory.

        What it made is recorded on :class:`SceneIds` (so ``--save-state`` writes it).
        A joint of the snippet on a body that already existed gets that body's pose now
        as its reference (see :meth:`_reference`); one on the snippet's own bodies only
        has their spawn poses from the factory.
        """
        from engine.scene import SceneError, SceneIds, spec_from_text
        from engine.scene.factory import SpawnRecord

        content = self.engine.config.content_dir or "."
        scene = self.engine.try_resource(SceneIds)
        try:
            spec = spec_from_text(str(text), content, self.engine.rng, path="<spawn>",
                                  scene=None if scene is None else scene.spec,
                                  bodies=self._poses,
                                  allow=self.engine.config.allow_paths)
        except SceneError as exc:
            raise ScriptAPIError(f"spawn: {exc}") from None
        for problem in spec.problems:  # an asset failed: told, its object left out
            log.error("spawn: %s", problem.render())
        ids: dict[str, int] = {}
        made: list[int] = []  # -1 where an object was left out, keeping blocks in step
        for es in spec.entities:
            ids[es.id] = -1 if es.skipped else self.engine.spawn(*es.components)
            made.append(ids[es.id])
        objects = made[:len(spec.db.blocks("Object"))] if spec.db is not None else []
        avatars = [ids[str(b.get("ID") or f"avatar{i}")]  # (the factory's name by place)
                   for i, b in enumerate(spec.db.blocks("Avatar"))] if spec.db is not None \
            else []
        joints: list[int] = []
        for js in spec.joints:
            if js.skipped:
                joints.append(-1)
                continue
            a, b = js.bodies
            joint = js.joint
            joint.body_a = ids[a] if a in ids else self.find(a)
            joint.body_b = None if b is None else (ids[b] if b in ids else self.find(b))
            if joint.reference is None:
                joint.reference = self._reference(joint.body_a, joint.body_b)
            joints.append(self.engine.spawn(Name(js.id), joint))
        made = [e for e in (*made, *joints) if e >= 0]
        if scene is not None:
            scene.record(SpawnRecord(spec.db, spec.content_dir, objects, joints, avatars),
                         self.engine.world.entity_exists)
        assert self.runtime is not None
        return self.runtime.lua.table_from(made)

    def _reference(self, a: int, b: int | None
                   ) -> tuple[tuple[float, ...], tuple[float, ...] | None] | None:
        """The poses (x y z qw qx qy qz) of a joint's bodies now, as its reference poses.

        Read from their Transforms: in serial mode exactly where the backend has them
        (nothing steps between a script and the joint's creation), so a saved state
        re-creates the joint exactly; in threaded mode the last synced poses.
        """
        world = self.engine.world
        ta = world.try_component(a, Transform)
        tb = None if b is None else world.try_component(b, Transform)
        if ta is None or (b is not None and tb is None):
            return None

        def pose(t: Transform) -> tuple[float, ...]:
            return (*map(float, t.position), *map(float, t.orientation))

        return pose(ta), None if tb is None else pose(tb)

    def set_motor(self, ref: Any, velocity: Any, max_force: Any) -> None:
        entity, joint = self._joint(ref, "setMotor")
        motor = self._command("setMotor", cmd.SetMotor, entity, velocity, max_force)
        assert isinstance(motor, cmd.SetMotor)
        joint.motor_velocity, joint.motor_max_force = motor.velocity, motor.max_force
        self.engine.physics.push(motor)

    def create_joint(self, spec: Any) -> int:
        """A joint between existing objects, made with their poses now as its reference
        poses (see :meth:`_reference`); recorded on :class:`SceneIds` for saved states."""
        from engine.scene.factory import SceneIds, SpawnRecord

        opts = to_python(spec)
        if not isinstance(opts, dict):
            raise ScriptAPIError("createJoint: expected a table {kind=, a=, b=, ...}")
        kind = str(opts.pop("kind", "hinge"))
        if kind not in JOINT_KINDS:
            raise ScriptAPIError(f"createJoint: unknown kind {kind!r} "
                                 f"(one of {', '.join(JOINT_KINDS)})")
        a = self.find(opts.pop("a", -1))
        b_ref = opts.pop("b", None)
        b = None if b_ref is None else self.find(b_ref)
        if a < 0 or (b is not None and b < 0):
            raise ScriptAPIError("createJoint: a and b must be existing objects")
        if a == b:
            raise ScriptAPIError(f"createJoint: a joint needs two different bodies, got "
                                 f"{self._called(a)} as both a and b (leave b out to join "
                                 "it to the world)")
        if kind == JointKind.HINGE2 and b is not None and not all(
                getattr(self.engine.world.try_component(e, Physical), "kind", "static")
                != "static" for e in (a, b)):
            raise ScriptAPIError(f"createJoint: {cmd.HINGE2_BODIES}; got "
                                 f"{self._called(a)} and {self._called(b)}")
        kwargs: dict[str, Any] = {}
        named = opts.get("id")
        target = f'joint "{named}"' if named else f"the joint on {self._called(a)}"
        for key, value in opts.items():
            key = {"maxForce": "motor_max_force", "velocity": "motor_velocity"}.get(key, key)
            if key not in _JOINT_FIELDS:
                raise ScriptAPIError(f"createJoint: unknown field {key!r} for {target}")
            kind_of, form = _JOINT_FIELDS[key]
            try:
                kwargs[key] = kind_of(value)
            except (TypeError, ValueError):
                raise ScriptAPIError(f"createJoint: {key} must be {form}, got "
                                     f"{value!r} for {target}") from None
        joint = Joint(kind=kind, body_a=a, body_b=b, **kwargs)
        joint.reference = self._reference(a, b)
        self._command("createJoint", cmd.AddJoint, a, joint,  # its values, checked now
                      target=f'joint "{joint.id}"' if joint.id else target)
        entity = self.engine.spawn(Name(joint.id or f"joint{a}_{b}"), joint)
        scene = self.engine.try_resource(SceneIds)
        if scene is not None:
            scene.record(SpawnRecord(None, None, [], [entity]),
                         self.engine.world.entity_exists)
        return entity

    def break_joint(self, ref: Any) -> None:
        entity, joint = self._joint(ref, "breakJoint")
        joint.broken = True
        self.engine.despawn(entity)

    # -- virtual hands -------------------------------------------------------------
    def _hands(self, what: str, entity: int) -> HandControl:
        hands = self.engine.try_resource(HandControl)
        self._entity(entity, what)
        if hands is None:
            raise ScriptAPIError(f"{what}: the {HandControl.plugin} plugin is not loaded "
                                 f"(requestPlugin('{HandControl.plugin}') loads it)")
        return hands

    def _hand_call(self, what: str, entity: int, call: Any) -> Any:
        try:
            return call(self._hands(what, entity))
        except (KeyError, ValueError) as exc:
            raise ScriptAPIError(f"{what}: {exc.args[0] if exc.args else exc}") from None

    def is_hand(self, entity: int) -> bool:
        return self.engine.world.has_component(self._entity(entity, "release"), Hand)

    def hand_state(self, entity: int) -> str:
        return self._hand_call("getHandState", entity, lambda h: h.state(entity))

    def hand_held(self, entity: int) -> Any:
        assert self.runtime is not None
        held = self._hand_call("getHeld", entity, lambda h: h.held(entity))
        return self.runtime.lua.table_from(list(held))

    def hand_grasp(self, entity: int, obj: int) -> None:
        if not self.engine.world.entity_exists(obj):
            raise ScriptAPIError(f"grasp: nothing to hold: {self._called(obj)} does not exist "
                                 f"(any more), for {self._called(self._entity(entity, 'grasp'))}")
        self._hand_call("grasp", entity, lambda h: h.grasp(entity, obj))

    def hand_release(self, entity: int) -> None:
        self._hand_call("release", entity, lambda h: h.release(entity))

    def _hand(self, what: str, entity: int) -> Hand:
        hand = self.engine.world.try_component(self._entity(entity, what), Hand)
        if hand is None:
            raise ScriptAPIError(f"{what}: {self._called(entity)} is not a hand")
        return hand

    def hand_grip(self, entity: int) -> Any:
        """The fingers holding what the hand holds (HandState.grip), a Lua table."""
        assert self.runtime is not None
        self._hand("getGrip", entity)
        state = self.engine.world.try_component(entity, HandState)
        return self.runtime.lua.table_from(list(state.grip) if state is not None else [])

    def _tracked(self, what: str, entity: int) -> HandJoints | None:
        self._hand(what, entity)
        inputs = self._inputs()
        return None if inputs is None else tracked_hand(self.engine.world, entity, inputs)

    def hand_joint(self, entity: int, name: Any) -> tuple[Any, ...] | None:
        """Tracked joint ``name`` of the hand in the world: position, orientation, radius,
        valid; None before its input hand was seen (or while it is lost)."""
        try:
            joint_index(name)
        except ValueError as exc:
            raise ScriptAPIError(f"joint ({self._called(entity)}): {exc}") from None
        joints = self._tracked("joint", entity)
        if joints is None:
            return None
        pose = hand_joint(joints, name)
        return (*pose.position.tolist(), *pose.orientation.tolist(), pose.radius, pose.valid)

    def hand_curl(self, entity: int, finger: Any) -> float | None:
        """How bent tracked finger ``finger`` is (0..1); None before the hand was seen."""
        try:
            finger_named(finger)
        except ValueError as exc:
            raise ScriptAPIError(f"curl ({self._called(entity)}): {exc}") from None
        joints = self._tracked("curl", entity)
        return None if joints is None else finger_curl(joints, finger)

    # -- input ------------------------------------------------------------------
    def _inputs(self) -> InputState | None:
        return self.engine.try_resource(InputState)

    def tracker(self, name: Any) -> tuple[Any, ...] | None:
        inputs = self._inputs()
        pose = None if inputs is None else inputs.tracker(str(name))
        if pose is None:
            return None
        return (*pose.position.tolist(), *pose.orientation.tolist(), pose.tracked)

    def wheel(self, name: Any) -> float | None:
        inputs = self._inputs()
        wheel = None if inputs is None else inputs.wheel(str(name))
        return None if wheel is None else float(wheel.angular_velocity)

    def button(self, device: Any, name: Any = None) -> bool:
        inputs = self._inputs()
        return inputs is not None and inputs.button(str(device),
                                                    None if name is None else str(name))

    def axis(self, device: Any, name: Any) -> float | None:
        inputs = self._inputs()
        return None if inputs is None else inputs.axis(str(device), str(name))

    def key(self, name: Any) -> bool:
        inputs = self._inputs()
        return inputs is not None and inputs.key(str(name))

    # -- optional subsystems ---------------------------------------------------
    def _service(self, kind: type[S], what: str) -> S | None:
        """The plugin service ``kind`` (None, warned once, when its plugin is not loaded)."""
        found = self.engine.try_resource(kind)
        if found is None and what not in self._warned:
            self._warned.add(what)
            plugin = kind.plugin  # type: ignore[attr-defined]
            if plugin == PluginName.RENDER and self.engine.config.headless:  # nothing to look at
                log.warning("%s: nothing is drawn in this run (headless, without --screenshot "
                            "or --record-frames), so the call does nothing; run it with a "
                            "display, or with --screenshot FILE.png, to see it", what)
            else:
                log.warning("%s: the %s plugin is not loaded; the call does nothing "
                            "(requestPlugin('%s') loads it)", what, plugin, plugin)
        return found

    def sound(self, entity: int, play: bool) -> None:
        system = self._service(SoundControl, "playSound" if play else "stopSound")
        if system is None:
            return
        if play:
            system.play(self.engine, self._entity(entity, "playSound"))
        else:
            system.stop(self._entity(entity, "stopSound"))

    def set_gain(self, entity: int, gain: Any) -> None:
        if not isinstance(gain, int | float) or isinstance(gain, bool) or not 0 <= gain < 1e6:
            raise ScriptAPIError(f"setGain: gain must be a number from 0 to 1e6, got {gain!r} "
                                 f"for {self._called(entity)}")
        sound = self.engine.world.try_component(self._entity(entity, "setGain"), Sound)
        if sound is None:
            raise ScriptAPIError(f"setGain: {self._called(entity)} has no Sound")
        sound.gain = float(gain)
        system = self._service(SoundControl, "setGain")
        if system is not None:
            system.set_gain(entity, float(gain))

    def avatar(self, entity: int, method: str, args: Any) -> Any:
        """``avatar:method(...)``: the avatars plugin's script call (a list comes back as a
        Lua table, a tuple as several values)."""
        control = self._service(AvatarControl, method)
        if control is None:
            return None
        plain = to_python(args)
        listed = plain if isinstance(plain, list) else [plain[k] for k in sorted(plain)] \
            if isinstance(plain, dict) else []
        try:
            result = control.script_call(self._entity(entity, method), method, listed)
        except cmd.CommandError as exc:  # a pose no world can take: named like the rest
            raise ScriptAPIError(f"{method}: {str(exc).partition(': ')[2]} for "
                                 f"{self._called(entity)}") from None
        except (KeyError, ValueError) as exc:
            raise ScriptAPIError(f"{method}: {exc.args[0] if exc.args else exc}") from None
        assert self.runtime is not None
        return self.runtime.to_lua(result) if isinstance(result, list) else result

    def set_uniform(self, state: Any, name: Any, value: Any) -> None:
        system = self._service(ShaderControl, "setUniform")
        if system is None:
            return
        value = _uniform_value("setUniform", value)
        try:
            system.set_uniform(str(state), str(name), value)
        except (KeyError, ValueError) as exc:
            raise ScriptAPIError(f"setUniform: {exc.args[0] if exc.args else exc}") from None

    def set_anomaly(self, where: str, anomaly: str, on: bool | None, params: Any) -> None:
        """``setAnomaly(id, on, {param=value, onset=s, eye="left"})``: switch and set a visual
        anomaly; a value out of range is clamped and told at the script's line (once per
        message), the call goes on."""
        anomalies = self._service(Anomalies, "setAnomaly")
        if anomalies is None:
            return
        options = to_python(params) if params is not None else {}
        if not isinstance(options, dict):
            raise ScriptAPIError("setAnomaly: parameters are a table {offset={2, 0}, mix=0.5, "
                                 "onset=1, eye=\"left\"}")
        onset, eye = options.pop("onset", None), options.pop("eye", None)
        call = f"setAnomaly({anomaly!r})"
        try:
            problems = anomalies.set(anomaly, f"lua:{where.rstrip(': ')}", on, options, onset,
                                     None if eye is None else str(eye))
        except (KeyError, ValueError) as exc:
            raise ScriptAPIError(f"{call}: {exc.args[0] if exc.args else exc}") from None
        for problem in problems:
            self._messages.warn(f"{where}{call}: {problem}")

    def get_anomaly(self, anomaly: Any) -> Any:
        """``getAnomaly(id)``: a table of what it is and is set to (``enabled``, ``level``,
        the ramp's progress 0..1, ``onset``, ``eye``, ``kind`` and its parameters)."""
        anomalies = self._service(Anomalies, "getAnomaly")
        if anomalies is None:
            return None
        try:
            state = anomalies.get(str(anomaly))
        except KeyError as exc:
            raise ScriptAPIError(f"getAnomaly: {exc.args[0]}") from None
        out: dict[str, Any] = {"kind": state.kind.name, "enabled": state.enabled,
                               "level": state.level, "onset": state.onset, "eye": state.eye}
        out.update({state.kind.param(key).lua: value for key, value in state.values.items()})
        assert self.runtime is not None
        return self.runtime.to_lua(out)

    def experiment(self, method: str, *args: Any) -> Any:
        """``experiment:condition(name)``, ``experiment:trial()`` and a trial's
        ``respond``/``finish`` (the experiment plugin's :class:`ExperimentControl`)."""
        control = self.engine.try_resource(ExperimentControl)
        if control is None:
            if method in ("condition", "trial"):
                return None
            raise ScriptAPIError(f"trial:{method}: no experiment is running (colosseum "
                                 "experiment run)")
        try:
            if method == "condition":
                return control.condition(str(args[0]) if args else "")
            if method == "respond":
                name, value = (list(args) + [None, None])[:2]
                control.respond(str(name), to_python(value))
                return None
            if method == "finish":
                control.finish("done" if not args or args[0] is None else str(args[0]))
                return None
        except (KeyError, ValueError, TypeError) as exc:  # TypeError: a function as a value
            raise ScriptAPIError(f"experiment: {exc.args[0] if exc.args else exc}") from None
        data = control.trial_data()
        return None if data is None else self.trial_table(data)

    def trial_table(self, data: dict[str, Any]) -> Any:
        """A Lua table of the trial's data with its methods ``respond`` and ``finish``."""
        assert self.runtime is not None
        table = self.runtime.to_lua(data)
        table["respond"] = lambda _t, name=None, value=None: self.experiment(
            "respond", name, value)
        table["finish"] = lambda _t, outcome=None: self.experiment("finish", outcome)
        table["condition"] = lambda _t, name=None: self.experiment("condition", name)
        return table

    def enable_post(self, name: Any, on: bool) -> None:
        """``enablePost(id, on)``: switch a scene's PostPass."""
        system = self._service(ShaderControl, "enablePost")
        if system is not None:
            try:
                system.enable_post(str(name), bool(on))
            except KeyError as exc:
                raise ScriptAPIError(f"enablePost: {exc.args[0]}") from None

    def set_post_uniform(self, name: Any, uniform: Any, value: Any) -> None:
        """``setPostUniform(id, uniform, value)``: retune a scene's PostPass."""
        system = self._service(ShaderControl, "setPostUniform")
        if system is not None:
            try:
                system.set_post_uniform(str(name), str(uniform), _uniform_value(
                    "setPostUniform", value))
            except (KeyError, ValueError) as exc:
                raise ScriptAPIError(f"setPostUniform: {exc.args[0]}") from None

    def set_camera(self, opts: Any) -> None:
        """Move, aim or attach the active camera (or the one named ``id``)."""
        options = to_python(opts)
        world = self.engine.world
        cameras = world.get_component(Camera)
        if "id" in options:
            entity = self.find(options.pop("id"))
            cameras = [(e, c) for e, c in cameras if e == entity]
        else:
            cameras = [(e, c) for e, c in cameras if c.active][:1]
        if not cameras:
            raise ScriptAPIError("setCamera: no such camera in the scene")
        entity, camera = cameras[0]
        for key, value in options.items():
            if key == "position":
                t = world.try_component(entity, Transform)
                if t is not None:
                    t.position[:] = _finite("setCamera", key, value, 3)
            elif key == "lookAt":
                camera.look_at = _finite("setCamera", key, value, 3)
            elif key == "follow":
                camera.follow = None if value is None else self.find(value)
            elif key == "offset":
                camera.offset = _finite("setCamera", key, value, 3)
            elif key == "fov":
                fov = _finite("setCamera", key, [value], 1)[0]
                if not 0 < fov < 180:
                    raise ScriptAPIError(f"setCamera: fov is degrees between 0 and 180, got "
                                         f"{fov:g}")
                camera.fov = fov
            else:
                raise ScriptAPIError(f"setCamera: unknown option {key!r} "
                                     "(position, lookAt, follow, offset, fov, id)")

    def haptic(self, hand: Any, amplitude: Any, seconds: Any) -> bool:
        """Pulse the headset controller driving ``hand`` (a hand object, or a tracker name
        such as ``hand_r``); False without a headset or a controller for it."""
        for what, value, top in (("amplitude", amplitude, 1.0), ("seconds", seconds, 10.0)):
            if not isinstance(value, int | float) or isinstance(value, bool) or \
                    not 0 <= value <= top:
                raise ScriptAPIError(f"haptic: {what} must be a number from 0 to {top:g}, "
                                     f"got {value!r}")
        if isinstance(hand, str):
            source = hand
        else:
            component = self.engine.world.try_component(self._entity(hand, "haptic"), Hand)
            if component is None:
                raise ScriptAPIError(f"haptic: {self._called(hand)} is not a hand")
            source = component.tracker
        headset = self._service(HeadsetControl, "haptic")  # type: ignore[type-abstract]
        return bool(headset is not None and headset.haptic(source, float(amplitude),
                                                           float(seconds)))

    def recenter(self) -> None:
        """Put the headset's wearer over the active camera, facing its way."""
        headset = self._service(HeadsetControl, "recenter")  # type: ignore[type-abstract]
        if headset is not None:
            headset.recenter()

    def request_plugin(self, name: Any) -> bool:
        """Load an engine plugin by the name (or alias) the engine registered it under."""
        if not isinstance(name, str):
            raise ScriptAPIError(f"requestPlugin: expected a plugin name, got {name!r}")
        engine = self.engine
        if name in engine.plugins:
            return True
        if name not in engine.plugin_factories:
            known = sorted(engine.plugin_factories)
            hint = difflib.get_close_matches(name, known, 1)
            extra = f"; did you mean {hint[0]!r}?" if hint else ""
            raise ScriptAPIError(f"requestPlugin: unknown plugin {name!r}{extra} "
                                 f"(known: {', '.join(known) or 'none'})")
        engine.request_plugin(name)
        return True


def _uniform_value(what: str, value: Any) -> float | tuple[float, ...]:
    """A uniform's value from Lua: a finite number or a table of them (true is not 1)."""
    value = to_python(value)
    numbers = value if isinstance(value, list) else [value]
    if not numbers or not all(isinstance(v, int | float) and not isinstance(v, bool) and
                              math.isfinite(v) for v in numbers):
        raise ScriptAPIError(f"{what}: value must be a finite number or a table of them, "
                             f"got {value!r}")
    return tuple(float(v) for v in value) if isinstance(value, list) else value
