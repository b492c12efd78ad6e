"""A screen of a projection wall or CAVE, in world coordinates."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare

Vec3 = tuple[float, ...]  # three numbers


@dataclass(slots=True)
class Display:
    """A flat screen given by three corners (m, world frame), drawn off-axis from the
    viewer's eye: the position of ``head`` (an entity a head tracker moves), else of this
    node's tracker ``tracker``, else ``eye``."""

    lower_left: Vec3 = (-1.0, 0.0, 0.0)
    lower_right: Vec3 = (1.0, 0.0, 0.0)
    upper_left: Vec3 = (-1.0, 0.0, 1.5)
    head: int | None = None
    tracker: str | None = None
    eye: Vec3 = (0.0, -2.0, 0.75)
    near: float = 0.05
    far: float = 500.0


#: The controllers' actions a scene may rebind (``Display { Bind { Action ... } }``); the
#: OpenXR display (services.xr.bindings) defines what each is.
HEADSET_ACTIONS = ("grip", "aim", "trigger", "trigger_value", "squeeze", "squeeze_value",
                   "thumbstick", "thumbstick_click", "a", "b", "x", "y", "menu", "select",
                   "haptic")
#: The interaction profiles bound by default, short names (``/interaction_profiles/`` left
#: out).
HEADSET_PROFILES = ("khr/simple_controller", "oculus/touch_controller",
                    "valve/index_controller", "htc/vive_controller",
                    "hp/mixed_reality_controller", "microsoft/motion_controller",
                    "bytedance/pico4_controller")


@dataclass(slots=True)
class Headset:
    """The scene's wish to be shown in a headset (``Display { Kind "openxr" }``): how the
    OpenXR display runs (see :mod:`services.xr`)."""

    space: str = "stage"
    when_hidden: str = "run"
    mirror: str = "none"
    fallback: str = "none"
    refresh_rate: float = 0.0
    render_scale: float = 1.0
    depth: bool = True
    recenter_key: str = "f8"
    haptic_grasp: float = 0.6
    haptic_touch: float = 0.25
    haptic_impulse: float = 0.5
    #: (action, profile, path) rebindings of the controllers' actions.
    bindings: tuple[tuple[str, str, str], ...] = ()


def binding_problem(action: str, profile: str, path: str,
                    suggest: Callable[[str, Any], str]) -> str | None:
    """What is wrong with a headset's ``Bind`` (None: nothing); ``suggest`` gives the
    did-you-mean of a name among choices."""
    if action not in HEADSET_ACTIONS:
        return f"unknown action {action!r}{suggest(action, HEADSET_ACTIONS)} " \
               f"(actions: {', '.join(HEADSET_ACTIONS)})"
    if profile not in HEADSET_PROFILES:
        return f"unknown interaction profile {profile!r}{suggest(profile, HEADSET_PROFILES)}"
    if not path.startswith(("/user/hand/left/", "/user/hand/right/")):
        return f"the path {path!r} must start with /user/hand/left/ or /user/hand/right/"
    return None


def _floats(value: Any) -> Vec3:
    return tuple(float(x) for x in value)


def build_display(d: Mapping[str, Any], ctx: BuildContext) -> list[Any] | None:
    """A ``Display`` block: a screen (it needs an ID, the name ``colosseum join --display``
    gives; its Head is linked once the objects exist), or the headset (one a run)."""
    if d["Kind"] == "openxr":
        return _headset(d, ctx)
    if not d["ID"]:
        ctx.error(None, "a screen Display needs an ID (the name colosseum join --display "
                  "gives); it is left out")
        return None
    display = Display(_floats(d["LowerLeft"]), _floats(d["LowerRight"]),
                      _floats(d["UpperLeft"]), None, d["Tracker"], _floats(d["Eye"]),
                      float(d["Near"]), float(d["Far"]))
    if ctx.given("Head"):
        ctx.link(display, "head", d["Head"])
    return [display]


def _headset(d: Mapping[str, Any], ctx: BuildContext) -> list[Any] | None:
    """``Display { Kind "openxr" }``: the headset, as a Headset component (one)."""
    if ctx.made(Headset):
        ctx.error(None, "a second headset Display: a run draws into one headset; this one "
                  "is left out")
        return None
    scale = float(d["RenderScale"])
    if not 0.25 <= scale <= 2.0:
        ctx.error("RenderScale", f"RenderScale must be 0.25 to 2, got {scale:g}")
        scale = min(max(scale, 0.25), 2.0)
    bindings = []
    for b, at in ctx.inner("Bind"):
        problem = binding_problem(b["Action"], b["Profile"], b["Path"], ctx.suggest)
        if problem is not None:
            at.error(None, f"Bind: {problem}; this binding is left out")
            continue
        bindings.append((b["Action"], b["Profile"], b["Path"]))
    return [Headset(
        space=d["Space"], when_hidden=d["WhenHidden"], mirror=d["Mirror"],
        fallback=d["Fallback"], refresh_rate=float(d["RefreshRate"]), render_scale=scale,
        depth=bool(d["Depth"]), recenter_key=str(d["RecenterKey"]).lower(),
        haptic_grasp=min(max(float(d["HapticGrasp"]), 0.0), 1.0),
        haptic_touch=min(max(float(d["HapticTouch"]), 0.0), 1.0),
        haptic_impulse=max(float(d["HapticImpulse"]), 0.0), bindings=tuple(bindings))]


def _values_only(values: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A block whose values the block around it reads (it builds nothing itself)."""
    return []


_XR = "openxr: "
DISPLAY_BLOCK = declare(BlockDeclaration(
    "Display", inside=("Scene",), build=build_display, unnamed="headset",
    doc="a screen of a wall or CAVE, drawn off-axis from the viewer's head (colosseum join "
    "--display ID)", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this display (a "
            "screen's is required)"),
        Key("Kind", "enum", "screen", "screen: a flat screen of a wall or CAVE (the keys "
            "below up to Far); openxr: the headset, through the active OpenXR runtime (the "
            "keys from Space on)", allowed=("screen", "openxr")),
        Key("LowerLeft", "vec3", (-1.0, 0.0, 0.0), "world frame: the screen's lower left "
            "corner", unit="m"),
        Key("LowerRight", "vec3", (1.0, 0.0, 0.0), "world frame: its lower right corner",
            unit="m"),
        Key("UpperLeft", "vec3", (-1.0, 0.0, 1.5), "world frame: its upper left corner",
            unit="m"),
        Key("Head", "ref", None, "object whose position is the viewer's eye (one a head "
            "tracker moves on the server: Tracker { ID \"USER/head\" Object ... })",
            ref="Object"),
        Key("Tracker", "string", None, "a tracker of this node's own input whose position is "
            "the eye (when there is no Head)"),
        Key("Eye", "vec3", (0.0, -2.0, 0.75), "world frame: the eye while no head is "
            "tracked", unit="m"),
        Key("Near", "float", 0.05, "nearest distance drawn", unit="m"),
        Key("Far", "float", 500.0, "farthest distance drawn", unit="m"),
        Key("Space", "enum", "stage", _XR + "the tracking space (stage: the floor at z = 0; "
            "local_floor, then local, where the runtime has no stage)",
            allowed=("stage", "local_floor", "local")),
        Key("WhenHidden", "enum", "run", _XR + "a headset taken off pauses the simulation "
            "(pause) or not (run)", allowed=("run", "pause")),
        Key("Mirror", "enum", "none", _XR + "a window for the experimenter showing the left "
            "eye or both (needs a display)", allowed=("none", "left", "both")),
        Key("Fallback", "enum", "none", _XR + "when no headset can be used, run in the "
            "window (window) or end with the message (none)", allowed=("none", "window")),
        Key("RefreshRate", "float", 0.0, _XR + "the display's rate where the runtime can set "
            "it (0: the runtime's)", unit="Hz"),
        Key("RenderScale", "float", 1.0, _XR + "the share of the runtime's recommended "
            "resolution per eye each axis is drawn at (0.25 to 2)"),
        Key("Depth", "bool", 1, _XR + "hand the runtime the depth of each eye (for its "
            "reprojection), where it takes it"),
        Key("RecenterKey", "string", "f8", _XR + "the key that moves the player over the "
            "camera, facing its way (Lua: recenter())"),
        Key("HapticGrasp", "float", 0.6, _XR + "amplitude 0..1 of the pulse a grasp gives "
            "the holding controller (0: none)"),
        Key("HapticTouch", "float", 0.25, _XR + "amplitude 0..1 of the pulse when a hand "
            "starts touching something it could grasp (0: none)"),
        Key("HapticImpulse", "float", 0.5, _XR + "a hand's contact pulses with amplitude "
            "impulse times this (capped at 1; 0: none)", unit="1/(N s)"),
    )))
BIND_BLOCK = declare(BlockDeclaration(
    "Bind", inside=("Display",), build=_values_only, repeat=True,
    doc=_XR + "bind an action to another input of a controller", keys=(
        Key("Action", "string", None, "the action: " + ", ".join(HEADSET_ACTIONS),
            required=True),
        Key("Profile", "string", None, "the interaction profile, e.g. "
            "oculus/touch_controller", required=True),
        Key("Path", "string", None, "the input, e.g. /user/hand/right/input/trigger/value",
            required=True),
    )))
