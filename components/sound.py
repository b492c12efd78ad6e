"""A sound an entity makes."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from components.transform import Transform


@dataclass(slots=True)
class Sound:
    """A sound source attached to the entity it sits on."""

    file: str = ""
    loop: bool = False
    gain: float = 1.0
    pitch: float = 1.0
    ref_distance: float = 1.0
    rolloff: float = 1.0
    max_distance: float = 1000.0
    auto_play: bool = False
    priority: int = 0
    id: str = ""


def build_sound(s: Mapping[str, Any], ctx: BuildContext) -> list[Any] | None:
    """The ``Sound`` block's component, if its file can be played (else left out, told):
    on an object, the object's sound; at the top level, an entity of its own, placed
    where its Position says (without one it is music or ambience: played at the
    listener, stereo kept)."""
    top = ctx.place == "Scene"
    outcome = f"sound '{ctx.owner}' is left out" if top else \
        f"object '{ctx.owner}' has no sound"
    if ctx.sound_file("File", outcome) is None:
        return None
    placed = [Transform(s["Position"])] if top and ctx.given("Position") else []
    return [*placed, Sound(file=s["File"], loop=bool(s["Loop"]), gain=float(s["Gain"]),
                           pitch=float(s["Pitch"]), ref_distance=float(s["RefDistance"]),
                           rolloff=float(s["Rolloff"]), max_distance=float(s["MaxDistance"]),
                           auto_play=bool(s["AutoPlay"]), priority=int(s["Priority"]),
                           id=s["ID"] or ctx.owner)]


def save_sound(sound: Sound) -> dict[str, Any]:
    """The block that makes ``sound`` again (a server writes a Python system's object
    so for its nodes; engine.scene.objects_text)."""
    return {"File": sound.file, "Loop": bool(sound.loop), "Gain": float(sound.gain),
            "Pitch": float(sound.pitch), "RefDistance": float(sound.ref_distance),
            "Rolloff": float(sound.rolloff), "MaxDistance": float(sound.max_distance),
            "AutoPlay": bool(sound.auto_play), "Priority": int(sound.priority)}


SOUND_BLOCK = declare(BlockDeclaration(
    "Sound", inside=("Scene", "Object"), build=build_sound, save=save_sound,
    doc={"Scene": "a sound not attached to an object", "Object": "sound source on this object"},
    keys=(
        Key("ID", "string", "", "name other declarations use to refer to this sound",
            example='"hum"'),
        Key("File", "asset", None, ".wav or .ogg", required=True,
            example='"sounds/motor_hum.ogg"'),
        Key("Position", "vec3", (0.0, 0.0, 0.0), "scene sounds only; without it the sound "
            "plays at the listener", unit="m"),
        Key("Loop", "bool", 0, "1 repeats the sound"),
        Key("Gain", "float", 1.0, "volume factor, 1 as recorded"),
        Key("Pitch", "float", 1.0, "playback speed factor"),
        Key("RefDistance", "float", 1.0, "", unit="m"),
        Key("Rolloff", "float", 1.0, "how fast it fades with distance"),
        Key("MaxDistance", "float", 1000.0, "", unit="m"),
        Key("AutoPlay", "bool", 0, "1 starts it when the scene starts"),
        Key("Priority", "int", 0, "higher keeps its voice when sources run out"),
    )))
