"""A screen of a projection wall or CAVE, in world coordinates."""

from __future__ import annotations

from dataclasses import dataclass

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
