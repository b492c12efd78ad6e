"""Visual anomalies of a stroke as a clinician's tool: one vocabulary, and their state in a run.

:data:`ANOMALIES` is the one definition of every anomaly: its name (Lua, events, markers),
its scene block, and its severity parameters with unit, range, default and the value that
has no effect. The scene schema and docs/KEYS.md, the Lua API (``setAnomaly``), the checks
of scene and Lua values and the manual's table (docs/howto/anomalies.md) are all made from
it, so they cannot disagree.

:class:`Anomalies` is a run's anomalies (a resource the anomalies plugin owns): each one
declared (by a scene block, or by its first ``setAnomaly``) is switched on and off, and its
severity set, from the scene, Lua, any input binding or Python. A switch ramps the effect
in over the anomaly's ``Onset`` seconds, and out again when it is switched off: every
severity parameter moves from the value without effect to its set value (smoothstep of the
ramp's progress), so the effect grows monotonically. Once ramped out the anomaly draws
nothing at all. What it draws is the renderer's business (services.render.anomalies).

>>> anomalies = Anomalies()
>>> _ = anomalies.declare("hemianopia", {"Side": "left"}, enabled=False, onset=2.0)
>>> anomalies.switch("hemianopia", True, source="doctest")
>>> anomalies.step(1.0)
>>> round(anomalies.active()[0].values["Depth"], 3)  # halfway through the onset
0.5
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from engine.system import PluginName

if TYPE_CHECKING:
    from engine.events import AnomalySwitched

#: A parameter's value: a number, numbers (a vector) or a word.
Value = float | tuple[float, ...] | str


@dataclass(frozen=True, slots=True)
class Param:
    """One severity parameter: scene key, unit, range and default; ``neutral`` is the value
    with no effect (None: a choice, such as a side, that is not ramped)."""

    key: str
    doc: str
    default: Value
    unit: str = ""
    low: float = 0.0
    high: float = 1.0
    neutral: Value | None = None
    choices: tuple[str, ...] = ()

    @property
    def lua(self) -> str:
        """Its name in Lua: ``Offset`` -> ``offset``."""
        return self.key[0].lower() + self.key[1:]

    @property
    def size(self) -> int:
        """Numbers it holds (1, or a vector's length; 0 for a choice)."""
        if self.choices:
            return 0
        return len(self.default) if isinstance(self.default, tuple) else 1

    def range_text(self) -> str:
        if self.choices:
            return " or ".join(f'"{c}"' for c in self.choices)
        each = " each" if self.size > 1 else ""
        return f"{_num(self.low)} to {_num(self.high)}{' ' + self.unit if self.unit else ''}{each}"


@dataclass(frozen=True, slots=True)
class AnomalyKind:
    """One anomaly: ``name`` in Lua and events, ``block`` in scene files."""

    name: str
    block: str
    doc: str
    params: tuple[Param, ...]

    def param(self, key: str) -> Param:
        for p in self.params:
            if key in (p.key, p.lua):
                return p
        raise KeyError(key)

    def defaults(self) -> dict[str, Value]:
        return {p.key: p.default for p in self.params}


def _num(value: float) -> str:
    return f"{value:g}"


SIDES = ("left", "right")
#: Which eye of a stereo view an anomaly is drawn in (a mono view gets every anomaly).
EYES = ("both", "left", "right")

#: Every anomaly, in the order the renderer applies them: how the view is projected, then
#: what the eye's optics do to the image, then what is lost of the visual field.
ANOMALIES: dict[str, AnomalyKind] = {kind.name: kind for kind in (
    AnomalyKind("perspective", "Perspective",
                "a distorted view: field of view, tilt, aspect and lens-like bending", (
                    Param("Fov", "the field of view times this: above 1 things look smaller "
                          "and farther (micropsia), below 1 larger (macropsia)", 1.0, "x",
                          0.5, 2.0, 1.0),
                    Param("Tilt", "the seen world rolled about the line of sight, "
                          "counter-clockwise", 10.0, "deg", -45.0, 45.0, 0.0),
                    Param("Aspect", "the view stretched sideways by this (things look wider "
                          "above 1, narrower below)", 1.0, "x", 0.5, 2.0, 1.0),
                    Param("Distortion", "radial bending about the centre: barrel above 0 "
                          "(the edges pulled in), pincushion below", 0.0, "", -1.0, 1.0,
                          0.0))),
    AnomalyKind("double_vision", "DoubleVision",
                "diplopia: a second image, displaced and turned, over the first", (
                    Param("Offset", "where the second image is, right and up of the first, "
                          "in degrees of visual angle", (2.0, 0.0), "deg", -20.0, 20.0,
                          (0.0, 0.0)),
                    Param("Rotation", "the second image turned about the centre of view "
                          "(cyclotorsion), counter-clockwise", 0.0, "deg", -45.0, 45.0, 0.0),
                    Param("Mix", "the second image's weight (0.5: both alike)", 0.5, "",
                          0.0, 1.0, 0.0))),
    AnomalyKind("blur", "Blur", "lost acuity (the image blurred) and a smear of motion", (
        Param("Acuity", "the blur's standard deviation in degrees of visual angle (a "
              "Gaussian, so detail finer than about twice this is lost)", 0.3, "deg",
              0.0, 3.0, 0.0),
        Param("Motion", "the share of the previous frame kept in each new one: moving things "
              "and turns of the head smear", 0.5, "", 0.0, 0.95, 0.0))),
    AnomalyKind("contrast_loss", "ContrastLoss",
                "reduced contrast sensitivity: the image fades toward its mean colour", (
                    Param("Loss", "the share of contrast lost: the standard deviation of "
                          "luminance times 1 - Loss", 0.5, "", 0.0, 1.0, 0.0),)),
    AnomalyKind("neglect", "Neglect",
                "unilateral (hemispatial) neglect: one side of the visual field fades", (
                    Param("Side", "the neglected side", "left", choices=SIDES),
                    Param("Start", "where the fading begins: degrees from the line of "
                          "sight toward the neglected side (below 0: across it)", 0.0, "deg",
                          -30.0, 90.0),
                    Param("Width", "degrees over which it fades from nothing to Depth", 20.0,
                          "deg", 0.0, 90.0),
                    Param("Depth", "how far the neglected field fades toward Fill (1: "
                          "entirely)", 0.8, "", 0.0, 1.0, 0.0),
                    Param("Fill", "the colour it fades to (RGB)", (0.0, 0.0, 0.0), "", 0.0,
                          1.0))),
    AnomalyKind("hemianopia", "Hemianopia",
                "homonymous hemianopia: half of the visual field lost in each eye", (
                    Param("Side", "the lost half", "left", choices=SIDES),
                    Param("Sparing", "macular sparing: the radius, in degrees about the "
                          "point looked at, that is still seen (0: none)", 0.0, "deg", 0.0,
                          15.0),
                    Param("Border", "degrees over which seen turns to lost (a soft edge)",
                          1.0, "deg", 0.0, 10.0),
                    Param("Depth", "how completely the half is lost (1: to Fill)", 1.0, "",
                          0.0, 1.0, 0.0),
                    Param("Fill", "what the lost half shows (RGB)", (0.0, 0.0, 0.0), "", 0.0,
                          1.0))),
)}

#: Seconds an anomaly's effect takes to grow or fade unless its Onset says otherwise.
ONSET_DEFAULT = 2.0
ONSET_MAX = 600.0
#: The keys every anomaly block has besides its severity parameters, and what they mean.
COMMON_DOCS = {
    "ID": "the name Lua, events and markers use (default: the anomaly's name; two blocks of "
          "one kind need their own)",
    "Enabled": "1: on from the start; 0: declared, switched on later (Lua, Input)",
    "Onset": f"s the effect takes to grow to its severity when switched on, and to fade "
             f"when switched off (0 to {_num(ONSET_MAX)}; 0: at once)",
    "Eye": "stereo views: the eye(s) it is drawn in, both, left or right (a mono view "
           "always shows it)",
    "Input": "an input that switches it: key:NAME or button:DEVICE/NAME toggles at each "
             "press; key:A/B switches on with A and off with B; any binding controllers "
             "take (axis:DEVICE/NAME past 0.5)",
}


def kind_of(name: str) -> AnomalyKind:
    """The anomaly called ``name``; KeyError says which exist."""
    kind = ANOMALIES.get(name)
    if kind is None:
        close = difflib.get_close_matches(name, ANOMALIES, 1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise KeyError(f"no anomaly {name!r}{hint} (anomalies: {', '.join(ANOMALIES)})")
    return kind


def check_value(kind: AnomalyKind, key: str, value: Any) -> tuple[Value, str | None]:
    """``value`` of parameter ``key`` made valid: clamped into its range (a message says so)
    or, when it cannot be read at all, the default (with a message). ValueError for an
    unknown parameter."""
    try:
        param = kind.param(key)
    except KeyError:
        names = [p.key for p in kind.params]
        close = difflib.get_close_matches(key, names + [p.lua for p in kind.params], 1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ValueError(f"{kind.name} has no parameter {key!r}{hint} "
                         f"(parameters: {', '.join(names)})") from None
    if param.choices:
        if isinstance(value, str) and value.lower() in param.choices:
            return value.lower(), None
        return param.default, (f"{kind.name} {param.key} must be {param.range_text()}, got "
                               f"{value!r}; using {param.default!r}")
    numbers = value if isinstance(value, (tuple, list)) else (value,)
    if len(numbers) != param.size or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in numbers):
        what = f"{param.size} numbers" if param.size > 1 else "a number"
        return param.default, (f"{kind.name} {param.key} must be {what}, got {value!r}; "
                               f"using {_show(param.default)}")
    clamped = tuple(min(max(float(v), param.low), param.high) for v in numbers)
    result: Value = clamped if param.size > 1 else clamped[0]
    if clamped != tuple(float(v) for v in numbers):
        return result, (f"{kind.name} {param.key} {_show(value)} is out of range "
                        f"({param.range_text()}); clamped to {_show(result)}")
    return result, None


def check_onset(value: Any) -> tuple[float, str | None]:
    """An onset time made valid (clamped into 0..ONSET_MAX s, with a message)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(
            value):
        return ONSET_DEFAULT, f"Onset must be a number of seconds, got {value!r}; using " \
                              f"{_num(ONSET_DEFAULT)}"
    clamped = min(max(float(value), 0.0), ONSET_MAX)
    if clamped != value:
        return clamped, (f"Onset {_show(value)} is out of range (0 to {_num(ONSET_MAX)} s); "
                         f"clamped to {_show(clamped)}")
    return clamped, None


def _show(value: Any) -> str:
    if isinstance(value, (tuple, list)):
        return "[" + " ".join(_show(v) for v in value) + "]"
    return _num(value) if isinstance(value, float) else f'"{value}"' if isinstance(
        value, str) else str(value)


@dataclass(frozen=True, slots=True)
class ActiveAnomaly:
    """An anomaly to draw this frame: its severity as ramped now (``values`` by scene key)
    and the eye(s) it is drawn in."""

    id: str
    kind: str
    eye: str
    values: Mapping[str, Value]
    level: float


@dataclass(slots=True)
class AnomalyState:
    """One declared anomaly: what it is set to, and how far its ramp has gone (0..1)."""

    id: str
    kind: AnomalyKind
    values: dict[str, Value]
    enabled: bool = False
    onset: float = ONSET_DEFAULT
    eye: str = "both"
    level: float = 0.0
    order: int = 0

    def ramped(self) -> dict[str, Value]:
        """Every parameter as drawn now: between no effect and its value by the ramp."""
        w = self.level * self.level * (3.0 - 2.0 * self.level)  # smoothstep: eases in, out
        out: dict[str, Value] = {}
        for p in self.kind.params:
            value = self.values[p.key]
            if p.neutral is None or isinstance(value, str):
                out[p.key] = value
            elif isinstance(value, tuple):
                neutral = p.neutral if isinstance(p.neutral, tuple) else (p.neutral,)
                out[p.key] = tuple(n + w * (v - n) for n, v in zip(neutral, value,
                                                                   strict=True))
            else:
                assert isinstance(p.neutral, float)
                out[p.key] = p.neutral + w * (float(value) - p.neutral)
        return out


class Anomalies:
    """The anomalies of a run: declared, switched, set and ramped (see the module doc).

    Every switch and every change of severity calls ``emit`` with an
    :class:`engine.events.AnomalySwitched` (the anomalies plugin puts it on the event bus
    and sends a marker to the Output streams).
    """

    #: The plugin that owns this resource (``requestPlugin``).
    plugin = PluginName.ANOMALIES

    def __init__(self, emit: Callable[[AnomalySwitched], None] | None = None) -> None:
        self.emit = emit
        self.states: dict[str, AnomalyState] = {}

    def declare(self, anomaly_id: str, values: Mapping[str, Value] | None = None,
                kind: str | None = None, enabled: bool = False,
                onset: float = ONSET_DEFAULT, eye: str = "both") -> AnomalyState:
        """Add an anomaly (``kind`` defaults to its ID); values are taken as checked."""
        found = kind_of(kind or anomaly_id)
        state = AnomalyState(anomaly_id, found, {**found.defaults(), **(values or {})},
                             False, onset, eye, 0.0, len(self.states))
        self.states[anomaly_id] = state
        if enabled:
            state.enabled, state.level = True, 1.0  # on from the start, no onset
        return state

    def get(self, anomaly_id: str) -> AnomalyState:
        """The anomaly called ``anomaly_id``, declared on first use when it names a kind;
        KeyError says what exists."""
        state = self.states.get(anomaly_id)
        if state is None:
            if anomaly_id not in ANOMALIES:
                known = sorted({*self.states, *ANOMALIES})
                close = difflib.get_close_matches(anomaly_id, known, 1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise KeyError(f"no anomaly {anomaly_id!r}{hint} (declared: "
                               f"{', '.join(self.states) or 'none'}; anomalies: "
                               f"{', '.join(ANOMALIES)})")
            state = self.declare(anomaly_id)
        return state

    def switch(self, anomaly_id: str, enabled: bool, source: str) -> None:
        """Switch an anomaly on or off; its effect ramps over its onset."""
        self.set(anomaly_id, source, enabled=enabled)

    def set(self, anomaly_id: str, source: str, enabled: bool | None = None,
            values: Mapping[str, Any] | None = None, onset: Any = None,
            eye: str | None = None) -> list[str]:
        """Switch an anomaly and/or set its severity parameters (scene keys or their Lua
        names), onset and eye; one :class:`AnomalySwitched` tells it (none when nothing
        was asked of it). Returns what had to be clamped or replaced: the values used are
        always valid. KeyError for an unknown anomaly, ValueError for an unknown
        parameter (nothing is changed then)."""
        state = self.get(anomaly_id)
        checked = []
        for key, value in (values or {}).items():
            valid, problem = check_value(state.kind, key, value)  # unknown keys raise here
            checked.append((state.kind.param(key).key, valid, problem))
        problems = [problem for _, _, problem in checked if problem]
        for key, value, _ in checked:
            state.values[key] = value
        if onset is not None:
            state.onset, problem = check_onset(onset)
            problems += [problem] if problem else []
        if eye is not None:
            if eye in EYES:
                state.eye = eye
            else:
                problems.append(f"Eye must be {', '.join(EYES)}, got {eye!r}; keeping "
                                f"{state.eye!r}")
        switched = enabled is not None and state.enabled != bool(enabled)
        if enabled is not None:
            state.enabled = bool(enabled)
        if (switched or checked or onset is not None or eye is not None) and \
                self.emit is not None:
            from engine.events import AnomalySwitched  # a scene's check emits none

            self.emit(AnomalySwitched(state.id, state.kind.name, state.enabled, state.onset,
                                      tuple(state.values.items()), source))
        return problems

    def step(self, dt: float) -> None:
        """Move every ramp ``dt`` seconds toward its anomaly's switch."""
        for state in self.states.values():
            target = 1.0 if state.enabled else 0.0
            if state.level == target:
                continue
            rate = math.inf if state.onset <= 0.0 else dt / state.onset
            state.level = min(state.level + rate, 1.0) if target else max(state.level - rate,
                                                                           0.0)

    def active(self) -> list[ActiveAnomaly]:
        """What to draw now: every anomaly on or still fading, in the renderer's order."""
        order = {name: i for i, name in enumerate(ANOMALIES)}
        live = sorted((s for s in self.states.values() if s.level > 0.0),
                      key=lambda s: (order[s.kind.name], s.order))
        return [ActiveAnomaly(s.id, s.kind.name, s.eye, s.ramped(), s.level) for s in live]


@dataclass(frozen=True, slots=True)
class AnomalySpec:
    """An anomaly block of a scene file, checked (values clamped, with warnings)."""

    id: str
    kind: str
    values: dict[str, Value] = field(default_factory=dict)
    enabled: bool = True
    onset: float = ONSET_DEFAULT
    eye: str = "both"
    input: str | None = None
    #: ``file:line`` of its Input (or of the block), for messages at run time.
    origin: str = ""


def table_markdown() -> str:
    """The anomalies and their parameters as a Markdown table (docs/howto/anomalies.md and
    docs/KEYS.md)."""
    rows = ["| anomaly (Lua name) | scene block | parameter | range | default | meaning |",
            "|---|---|---|---|---|---|"]
    for kind in ANOMALIES.values():
        for i, p in enumerate(kind.params):
            first = (f"`{kind.name}`: {kind.doc}", f"`{kind.block}`") if i == 0 else ("", "")
            rows.append(f"| {first[0]} | {first[1]} | `{p.key}` | {p.range_text()} | "
                        f"{_show(p.default)} | {p.doc} |")
    return "\n".join(rows) + "\n"
