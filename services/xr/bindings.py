"""Controllers through OpenXR actions, in the engine's input vocabulary.

One action set, ``colosseum``, with the actions below, each for both hands (subaction
paths ``/user/hand/left`` and ``/user/hand/right``). The runtime binds them to whatever
controller the person holds, from the suggested bindings of :data:`PROFILES` (the
common controllers, each listed only where the runtime knows it). What they become:

* poses ``grip`` and ``aim``: trackers ``hand_l``/``hand_r`` and ``hand_l_aim``/``hand_r_aim``
  (:class:`~services.input.events.TrackerPose`), so ``Hand { Tracker "hand_r" }`` follows
  the controller;
* buttons ``trigger squeeze a b x y menu thumbstick select``: ``Button("hand_r", NAME)``,
  so ``Hand { Tracker "hand_r" Glove "hand_r" Button "squeeze" }`` grasps on a squeeze;
* values ``trigger squeeze`` and ``thumbstick_x``/``thumbstick_y``: ``Axis("hand_r", NAME)``;
* ``haptic``: the output a hand's touch, grasp and contacts pulse.

A scene rebinds with ``Display { Kind "openxr" Bind { Action "squeeze" Profile
"oculus/touch_controller" Path "/user/hand/right/input/trigger/value" } }``.
"""

from __future__ import annotations

from dataclasses import dataclass

LEFT, RIGHT = "/user/hand/left", "/user/hand/right"
#: The engine's source names of the two hands.
HAND_SOURCES = {LEFT: "hand_l", RIGHT: "hand_r"}


@dataclass(frozen=True, slots=True)
class ActionSpec:
    name: str
    kind: str  # "pose" | "boolean" | "float" | "vector2" | "haptic"
    localized: str


ACTIONS: tuple[ActionSpec, ...] = (
    ActionSpec("grip", "pose", "Grip pose"),
    ActionSpec("aim", "pose", "Aim pose"),
    ActionSpec("trigger", "boolean", "Trigger"),
    ActionSpec("trigger_value", "float", "Trigger value"),
    ActionSpec("squeeze", "boolean", "Squeeze"),
    ActionSpec("squeeze_value", "float", "Squeeze value"),
    ActionSpec("thumbstick", "vector2", "Thumbstick"),
    ActionSpec("thumbstick_click", "boolean", "Thumbstick click"),
    ActionSpec("a", "boolean", "A"),
    ActionSpec("b", "boolean", "B"),
    ActionSpec("x", "boolean", "X"),
    ActionSpec("y", "boolean", "Y"),
    ActionSpec("menu", "boolean", "Menu"),
    ActionSpec("select", "boolean", "Select"),
    ActionSpec("haptic", "haptic", "Haptic pulse"),
)
ACTION_NAMES = tuple(a.name for a in ACTIONS)
#: The engine's name of a boolean action's Button and a float action's Axis.
BUTTON_NAMES = {"trigger": "trigger", "squeeze": "squeeze", "thumbstick_click": "thumbstick",
                "a": "a", "b": "b", "x": "x", "y": "y", "menu": "menu", "select": "select"}
AXIS_NAMES = {"trigger_value": "trigger", "squeeze_value": "squeeze"}

_BOTH = (LEFT, RIGHT)
_POSES = {"grip": "input/grip/pose", "aim": "input/aim/pose", "haptic": "output/haptic"}


@dataclass(frozen=True, slots=True)
class Profile:
    """An interaction profile: its path, the extension it needs (None: core), and per
    action the component path on each hand (None: that hand lacks it)."""

    path: str
    extension: str | None
    components: dict[str, tuple[str | None, str | None]]


def _both(path: str) -> tuple[str, str]:
    return (path, path)


def _common(trigger_click: bool, squeeze: str, stick: str | None) -> dict:
    parts = {name: _both(path) for name, path in _POSES.items()}
    parts["trigger_value"] = _both("input/trigger/value")
    parts["trigger"] = _both("input/trigger/click" if trigger_click else "input/trigger/value")
    parts["squeeze"] = _both(squeeze)
    if squeeze.endswith("/value") or squeeze.endswith("/force"):
        parts["squeeze_value"] = _both(squeeze)
    if stick is not None:
        parts["thumbstick"] = _both(f"input/{stick}")
        parts["thumbstick_click"] = _both(f"input/{stick}/click")
    return parts


def _face(left: tuple[str, str], right: tuple[str, str]) -> dict:
    """Face buttons: two on the left controller, two on the right."""
    return {left[0]: (f"input/{left[0]}/click", None), left[1]: (f"input/{left[1]}/click", None),
            right[0]: (None, f"input/{right[0]}/click"),
            right[1]: (None, f"input/{right[1]}/click")}


PROFILES: tuple[Profile, ...] = (
    Profile("/interaction_profiles/khr/simple_controller", None, {
        "grip": _both("input/grip/pose"), "aim": _both("input/aim/pose"),
        "select": _both("input/select/click"), "trigger": _both("input/select/click"),
        "menu": _both("input/menu/click"), "haptic": _both("output/haptic")}),
    Profile("/interaction_profiles/oculus/touch_controller", None, {
        **_common(False, "input/squeeze/value", "thumbstick"), **_face(("x", "y"), ("a", "b")),
        "menu": ("input/menu/click", None)}),
    Profile("/interaction_profiles/valve/index_controller", None, {
        **_common(True, "input/squeeze/value", "thumbstick"),
        "a": _both("input/a/click"), "b": _both("input/b/click")}),
    Profile("/interaction_profiles/htc/vive_controller", None, {
        **_common(True, "input/squeeze/click", "trackpad"), "menu": _both("input/menu/click")}),
    Profile("/interaction_profiles/hp/mixed_reality_controller",
            "XR_EXT_hp_mixed_reality_controller", {
        **_common(False, "input/squeeze/value", "thumbstick"), **_face(("x", "y"), ("a", "b")),
        "menu": _both("input/menu/click")}),
    Profile("/interaction_profiles/microsoft/motion_controller", None, {
        **_common(False, "input/squeeze/click", "thumbstick"),
        "menu": _both("input/menu/click")}),
    Profile("/interaction_profiles/bytedance/pico4_controller", "XR_BD_controller_interaction", {
        **_common(False, "input/squeeze/value", "thumbstick"), **_face(("x", "y"), ("a", "b")),
        "menu": ("input/menu/click", None)}),
)
PROFILE_PATHS = {p.path.removeprefix("/interaction_profiles/"): p for p in PROFILES}


@dataclass(frozen=True, slots=True)
class Rebinding:
    """A scene's binding of ``action`` under ``profile`` (short form, e.g.
    ``oculus/touch_controller``) to the full input ``path``; it replaces that action's
    suggestion on the path's hand."""

    action: str
    profile: str
    path: str

    def problem(self) -> str | None:
        """What is wrong with it: the scene's own check of a ``Bind`` block."""
        from engine.scene.factory import binding_problem

        return binding_problem(self.action, self.profile, self.path)


def suggestions(extensions: set[str] | frozenset[str], rebinding: tuple[Rebinding, ...] = ()
                ) -> dict[str, list[tuple[str, str]]]:
    """Per profile path the suggested (action, binding path) pairs: every profile whose
    extension the runtime enabled, with the scene's rebindings in place.

    >>> pairs = suggestions(set())["/interaction_profiles/oculus/touch_controller"]
    >>> [(a, p) for a, p in pairs if a == "a"]
    [('a', '/user/hand/right/input/a/click')]
    """
    out: dict[str, list[tuple[str, str]]] = {}
    for profile in PROFILES:
        if profile.extension is not None and profile.extension not in extensions:
            continue
        short = profile.path.removeprefix("/interaction_profiles/")
        mine = [r for r in rebinding if r.profile == short]
        replaced = {(r.action, r.path.startswith(RIGHT + "/")) for r in mine}
        pairs = []
        for action, per_hand in profile.components.items():
            for hand, component in zip(_BOTH, per_hand, strict=True):
                if component is not None and (action, hand == RIGHT) not in replaced:
                    pairs.append((action, f"{hand}/{component}"))
        pairs.extend((r.action, r.path) for r in mine)
        out[profile.path] = pairs
    return out


def profile_extensions() -> frozenset[str]:
    """The extensions that bring a profile (enabled where the runtime offers them)."""
    return frozenset(p.extension for p in PROFILES if p.extension is not None)
