"""The input layer: devices on real transports, typed events, one latest-state table.

Devices (:mod:`~services.input.osc`, :mod:`~services.input.lsl`,
:mod:`~services.input.serial_line`, :mod:`~services.input.openxr`,
:mod:`~services.input.desktop`) receive on their own threads; the input plugin's one
INPUT-phase system drains them through the :class:`InputHub` each frame, which
calibrates, filters and publishes to the event bus and to :class:`InputState`
(``engine.resource(InputState).tracker("hand_r")``). Everything a frame receives can
be recorded and replayed bit-identically (:mod:`~services.input.record`; the file format
is in docs/input-format.md).

Its names load on first use (:mod:`engine.lazy`): a system that reads the latest-state
table alone does not load the devices, the hub and the recorder with it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.lazy import lazy_exports

if TYPE_CHECKING:
    from services.input.calibration import Calibration, openxr_to_engine
    from services.input.config import make_device, merge_devices, parse_input_option
    from services.input.device import BadMessage, DeviceError, DeviceStatus, InputDevice
    from services.input.events import (
        AnyInput,
        Axis,
        Button,
        DeviceFound,
        DeviceLost,
        Key,
        Pointer,
        TrackerPose,
        WheelCount,
    )
    from services.input.hub import InputHub
    from services.input.record import ReplayError, read_recording
    from services.input.replay import InputRecorder, InputReplayer
    from services.input.state import Binding, InputState, TrackerState, WheelState, parse_binding
    from services.input.wheel import WheelRate

__all__ = [
    "AnyInput",
    "Axis",
    "BadMessage",
    "Binding",
    "Button",
    "Calibration",
    "DeviceError",
    "DeviceFound",
    "DeviceLost",
    "DeviceStatus",
    "InputDevice",
    "InputHub",
    "InputRecorder",
    "InputReplayer",
    "InputState",
    "Key",
    "Pointer",
    "ReplayError",
    "TrackerPose",
    "TrackerState",
    "WheelCount",
    "WheelRate",
    "WheelState",
    "make_device",
    "merge_devices",
    "openxr_to_engine",
    "parse_binding",
    "parse_input_option",
    "read_recording",
]

__getattr__, __dir__ = lazy_exports(__name__, {
    "services.input.calibration": ("Calibration", "openxr_to_engine"),
    "services.input.config": ("make_device", "merge_devices", "parse_input_option"),
    "services.input.device": ("BadMessage", "DeviceError", "DeviceStatus", "InputDevice"),
    "services.input.events": ("AnyInput", "Axis", "Button", "DeviceFound", "DeviceLost", "Key",
                              "Pointer", "TrackerPose", "WheelCount"),
    "services.input.hub": ("InputHub",),
    "services.input.record": ("ReplayError", "read_recording"),
    "services.input.replay": ("InputRecorder", "InputReplayer"),
    "services.input.state": ("Binding", "InputState", "TrackerState", "WheelState",
                             "parse_binding"),
    "services.input.wheel": ("WheelRate",)})
