"""The ``Avatar`` block (and its ``Clip`` and ``Hold``), declared beside the Avatar
component: a skinned glTF figure, its clips, bones and path checked against its model,
resuming from an ``AvatarState`` a saved state wrote (issue 32)."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from components.avatar import Avatar, ClipSpec, Hold
from components.blocks import BlockDeclaration, BuildContext, Key, declare
from components.script import Script
from components.transform import Transform
from components.user import UserOwned
from components.visual import Visual

if TYPE_CHECKING:
    from components.avatar_saved import SavedAvatar, SavedGroup, SavedRequest

#: name, the key it was written at, the item of that key (None: the whole value), where
#: -> whether the model has it (a name it lacks is told there).
Check = Callable[[str, str, "int | None", BuildContext], bool]


def _floats(values: Any) -> tuple[float, ...]:
    return tuple(float(x) for x in values)


def _opt(value: Any) -> float | None:
    return None if value is None else float(value)


def _below(parents: Any, node: int | None, ancestor: int | None) -> bool:
    """Whether ``node`` lies in the subtree under ``ancestor`` (not ``ancestor`` itself)."""
    if node is None or ancestor is None:
        return False
    node = int(parents[node])
    while node >= 0:
        if node == ancestor:
            return True
        node = int(parents[node])
    return False


def _checks(model: Any, file: str, ctx: BuildContext) -> tuple[Check, Check]:
    """The clip and bone checks of ``model``: a name it lacks is told (did-you-mean)."""
    def clip(name: str, key: str, item: int | None, at: BuildContext) -> bool:
        if model.clip(name) is not None:
            return True
        names = ", ".join(model.clip_names) or "none"
        at.problem(key, f'model "{file}" has no clip "{name}"'
                   f"{ctx.suggest(name, model.clip_names)} (its clips: {names}); it is not "
                   "played", item=item)
        return False

    def bone(name: str, key: str, item: int | None, at: BuildContext) -> bool:
        if model.node(name) is not None:
            return True
        at.problem(key, f'model "{file}" has no bone "{name}"'
                   f"{ctx.suggest(name, model.node_names)}", item=item)
        return False
    return clip, bone


def _weights(v: Mapping[str, Any], at: BuildContext, key: str, clip: Check
             ) -> list[tuple[str, float]]:
    """Clips named by ``key`` with their ``Weights`` (1 each by default); clips the model
    lacks are told and left out."""
    names, weights = v[key], v["Weights"] or (1.0,) * len(v[key])
    if len(weights) != len(names):
        at.error("Weights" if at.given("Weights") else key, f"Weights has {len(weights)} "
                 f"numbers for {len(names)} {key} clips")
    return [(n, float(w)) for i, (n, w) in enumerate(zip(names, weights, strict=False))
            if clip(n, key, i, at)]


def _points(v: Mapping[str, Any], at: BuildContext, key: str
            ) -> list[tuple[float, float, float]]:
    """A path: ``v[key]`` as points [x y z ...], each within the world."""
    if not at.given(key):
        return []
    at.within_world(key, points=True)
    flat = _floats(v[key])
    if len(flat) % 3:
        at.error(key, f"{key} is points [x y z ...], got {len(flat)} numbers")
    return [(flat[k], flat[k + 1], flat[k + 2]) for k in range(0, len(flat) - 2, 3)]


def _legs(v: Mapping[str, Any], ctx: BuildContext, model: Any, file: str, bone: Check
          ) -> list[tuple[str, str, str]]:
    """FootIK's bone triples (hip, knee, ankle), each below the one before."""
    if not ctx.given("FootIK"):
        return []
    bones, legs = v["FootIK"], []
    if len(bones) % 3:
        ctx.error("FootIK", f"FootIK names bones in threes (hip, knee, ankle), got "
                  f"{len(bones)}")
    for k in range(0, len(bones) - len(bones) % 3, 3):
        if not all([bone(bones[k + j], "FootIK", k + j, ctx) for j in range(3)]):
            continue
        hip, knee, ankle = (model.node(bones[k + j]) for j in range(3))
        for upper, lower, j in ((hip, knee, 1), (knee, ankle, 2)):
            if not _below(model.parents, lower, upper):
                ctx.problem("FootIK", f'"{bones[k + j]}" does not hang below '
                            f'"{bones[k + j - 1]}" in model "{file}": a leg is hip, knee, '
                            "ankle, each below the one before; that leg is left out",
                            item=k + j)
                break
        else:
            legs.append((bones[k], bones[k + 1], bones[k + 2]))
    return legs


def _plays(v: Mapping[str, Any], ctx: BuildContext, clip: Check) -> dict[str, Any]:
    """What it plays: its first clip, blend, queue and Clip blocks (those its model has)."""
    first = v["Animation"] if ctx.given("Animation") and clip(
        v["Animation"], "Animation", None, ctx) else None
    blend = dict(_weights(v, ctx, "Blend", clip)) if ctx.given("Blend") else {}
    queue = [n for i, n in enumerate(v["Queue"] or ()) if clip(n, "Queue", i, ctx)]
    clips = [ClipSpec(c["Name"], float(c["Speed"]), bool(c["Loop"]), _opt(c["GroundSpeed"]))
             for c, at in ctx.inner("Clip") if clip(c["Name"], "Name", None, at)]
    return {"clip": first, "blend": blend, "queue": queue, "clips": clips}


def _capsule(v: Mapping[str, Any], ctx: BuildContext) -> tuple[float, float] | None:
    """Capsule [diameter length] as (radius, length); every size told if not positive."""
    for key in ("Scale", "Speed", "Fade", "StepHeight", "Smoothing", "TurnRate"):
        if v[key] is not None and (v[key] < 0 or (key == "Scale" and v[key] == 0)):
            ctx.error(key, f"{key} must be positive, got {v[key]}")
    if not ctx.given("Capsule"):
        return None
    diameter, length = _floats(v["Capsule"])
    if diameter <= 0 or length < 0:
        ctx.error("Capsule", "Capsule is [diameter length], positive")
    return diameter / 2, length


def build_avatar(v: Mapping[str, Any], ctx: BuildContext) -> list[Any] | None:
    """An ``Avatar`` block: left out (told) when its model cannot be read or has no skin;
    names of clips and bones the model lacks are told and ignored."""
    aid, file = ctx.owner, v["Model"]
    model = ctx.skinned_model("Model", f"avatar '{aid}' is left out")
    if model is None:
        return None
    if not model.skin_count:
        ctx.problem("Model", f'model "{file}" has no skin (no joints to animate); use it in '
                    f"an Object instead; avatar '{aid}' is left out")
        return None
    for warning in model.warnings:
        ctx.problem("Model", f'model "{file}": {warning}', warning=True)
    clip, bone = _checks(model, file, ctx)
    plays, legs = _plays(v, ctx, clip), _legs(v, ctx, model, file, bone)
    ctx.within_world("Position")
    path = _points(v, ctx, "Path")
    holds = [Hold(h["Bone"], h["Object"], _floats(h["Offset"]), at.orientation())
             for h, at in ctx.inner("Hold") if bone(h["Bone"], "Bone", None, at)]
    capsule, scale = _capsule(v, ctx), float(v["Scale"])
    state = ctx.saved("AvatarState", aid)
    avatar = Avatar(model=file, scale=scale, loop=None if v["Loop"] is None else bool(v["Loop"]),
                    speed=_opt(v["Speed"]), fade=float(v["Fade"]),
                    ground_follow=bool(v["GroundFollow"]), step_height=float(v["StepHeight"]),
                    smoothing=float(v["Smoothing"]), foot_ik=legs, path=path,
                    path_loop=bool(v["PathLoop"]), turn_rate=math.radians(float(v["TurnRate"])),
                    capsule=capsule, holds=holds, saved=None if state is None else
                    _saved_avatar(*state, clip, bone), **plays)
    color = _floats(v["Color"])
    visual = Visual(model=file, scale=(scale,) * 3,
                    color=color if len(color) == 4 else (*color, 1.0),
                    shader_state=v["ShaderState"], shadower=bool(v["Shadower"]),
                    shadowed=bool(v["Shadowed"]))
    made: list[Any] = [Transform(_floats(v["Position"]), ctx.orientation()), visual, avatar]
    if ctx.given("User"):
        made.append(UserOwned(v["User"]))
    if ctx.given("Script"):
        made.append(Script(file=v["Script"], saved=ctx.saved_script(aid)))
    return made


def _not_negative(v: Mapping[str, Any], at: BuildContext, *keys: str) -> None:
    for key in keys:
        if v[key] is not None and not v[key] >= 0:
            at.error(key, f"{key} must not be negative, got {v[key]}")


def _saved_groups(s: BuildContext, clip: Check) -> tuple[SavedGroup, ...]:
    from components.avatar_saved import SavedGroup, SavedLayer

    groups = []
    for g, at in s.inner("Group"):
        if not 0.0 <= g["Phase"] <= 1.0:
            at.error("Phase", f"Phase is 0..1, got {g['Phase']}")
        layers = []
        for c, lat in at.inner("Layer"):
            _not_negative(c, lat, "Speed", "Weight", "FadeFrom", "FadeTo", "FadeTime",
                          "FadeLength")
            if clip(c["Clip"], "Clip", None, lat):
                layers.append(SavedLayer(c["Clip"], float(c["Speed"]), float(c["Weight"]),
                                         float(c["FadeFrom"]), float(c["FadeTo"]),
                                         float(c["FadeTime"]), float(c["FadeLength"])))
        if layers:
            groups.append(SavedGroup(tuple(layers), float(g["Phase"]), bool(g["Loop"]),
                                     bool(g["Ended"]), bool(g["Current"])))
    return tuple(groups)


def _saved_queue(s: BuildContext, clip: Check) -> tuple[SavedRequest, ...]:
    from components.avatar_saved import SavedRequest

    queue = []
    for q, at in s.inner("Queued"):
        _not_negative(q, at, "Fade", "Speed")
        weights = _weights(q, at, "Clips", clip)
        if weights:
            queue.append(SavedRequest(tuple(weights), float(q["Fade"]), _opt(q["Speed"]),
                                      None if q["Loop"] is None else bool(q["Loop"])))
    return tuple(queue)


def _saved_avatar(r: Mapping[str, Any], s: BuildContext, clip: Check, bone: Check
                  ) -> SavedAvatar:
    """An ``AvatarState`` as its avatar resumes from it. Clips and bones its model lacks
    are told and left out; numbers out of range are errors."""
    from components.avatar_saved import SavedAvatar, SavedDrive, SavedHold

    groups, queue = _saved_groups(s, clip), _saved_queue(s, clip)
    path = _points(r, s, "Path")
    if not 0 <= r["Waypoint"] <= len(path):
        s.error("Waypoint", f"Waypoint is a point of Path (0 to {len(path)}), got "
                f"{r['Waypoint']}")
    holds = tuple(SavedHold(Hold(h["Bone"], h["Object"], _floats(h["Offset"]),
                                 at.quaternion("Quaternion")),
                            None if h["Last"] is None else _floats(h["Last"]))
                  for h, at in s.inner("Hold") if bone(h["Bone"], "Bone", None, at))
    drives = tuple(SavedDrive(d["Bone"], _floats(d["Position"]), at.quaternion("Quaternion"))
                   for d, at in s.inner("Drive") if bone(d["Bone"], "Bone", None, at))
    capsule = None
    if s.given("CapsulePosition"):
        turn = s.quaternion("CapsuleQuaternion") if s.given("CapsuleQuaternion") \
            else (1.0, 0.0, 0.0, 0.0)
        capsule = (_floats(r["CapsulePosition"]), turn)
    return SavedAvatar(groups, queue, tuple(path), bool(r["PathLoop"]), int(r["Waypoint"]),
                       _opt(r["Ground"]), None if r["GroundAt"] is None
                       else _floats(r["GroundAt"]), float(r["StepOffset"]), holds, drives,
                       capsule)


def _values_only(values: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A block whose values the block around it reads (it builds nothing itself)."""
    return []


AVATAR_BLOCK = declare(BlockDeclaration(
    "Avatar", inside=("Scene",), build=build_avatar,
    doc="a skinned, animated figure (glTF)", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this avatar",
            example='"guide"'),
        Key("User", "string", None, "the user (colosseum join --user NAME) it stands for — an "
            "avatar, a wheelchair, hands: a server takes it out of the world --leave-after s "
            "after that user's node leaves, unless the user comes back"),
        Key("Model", "asset", None, ".glb or .gltf with a skin (Blender, Maya, Mixamo "
            "exports)", required=True, example='"models/walker.glb"'),
        Key("Position", "vec3", (0.0, 0.0, 0.0), "where its feet stand", unit="m"),
        Key("Orientation", "vec3", (0.0, 0.0, 0.0), "Euler degrees; unturned it faces +Y"),
        Key("Quaternion", "vector", None, "exact orientation [w x y z]; wins over Orientation",
            lengths=(4,), example="[0.7071 0 0 0.7071]"),
        Key("Scale", "float", 1.0, "uniform scale of the model"),
        Key("Animation", "string", None, "clip played first", example='"Walk"'),
        Key("Loop", "bool", None, "1: the first clip loops, 0: it does not (default: as its "
            "Clip block says, else 1)"),
        Key("Speed", "float", None, "playback rate of the first clip (default: its Clip "
            "block's Speed, else 1)"),
        Key("Blend", "stringvector", None, "clips played at once from the start (with "
            "Weights)", example='["Walk" "Run"]'),
        Key("Weights", "vector", None, "weight of each Blend clip", example="[0.7 0.3]"),
        Key("Queue", "stringvector", None, "clips played in turn when the first one ends",
            example='["Wave" "Idle"]'),
        Key("Fade", "float", 0.2, "default crossfade between clips", unit="s"),
        Key("GroundFollow", "bool", 0, "keep the feet on the ground below (ray casts)"),
        Key("StepHeight", "float", 0.5, "highest step it walks up", unit="m"),
        Key("Smoothing", "float", 0.1, "how fast a step up or down is taken", unit="s"),
        Key("FootIK", "stringvector", None, "bone triples [hip knee ankle ...] whose feet "
            "meet slopes and steps",
            example='["thigh.L" "shin.L" "foot.L" "thigh.R" "shin.R" "foot.R"]'),
        Key("Path", "vector", None, "points [x y z x y z ...] walked in turn", unit="m",
            example="[0 0 0  4 0 0  4 4 0]"),
        Key("PathLoop", "bool", 1, "after the last point, walk back to the first"),
        Key("TurnRate", "float", 180.0, "how fast it turns toward the next point",
            unit="deg/s"),
        Key("Capsule", "vector", None, "[diameter length] m: a kinematic body dynamic objects "
            "bump into", lengths=(2,), example="[0.4 1.0]"),
        Key("Color", "vector", (1.0, 1.0, 1.0, 1.0), "RGB or RGBA, 0..1, times the model's",
            lengths=(3, 4)),
        Key("ShaderState", "ref", None, "the shader state it is drawn with", ref="ShaderState",
            example='"toon"'),
        Key("Shadower", "bool", 1, "casts shadows"),
        Key("Shadowed", "bool", 1, "receives shadows"),
        Key("Script", "asset", None, "Lua script attached to this avatar",
            example='"scripts/guide.lua"'),
    )))
CLIP_BLOCK = declare(BlockDeclaration(
    "Clip", inside=("Avatar",), build=_values_only, repeat=True, doc="how one clip plays",
    keys=(
        Key("Name", "string", None, "the clip's name in the model", required=True,
            example='"Walk"'),
        Key("Speed", "float", 1.0, "playback rate"),
        Key("Loop", "bool", 1, "1: the clip starts again when it ends; 0: it holds its last "
            "pose"),
        Key("GroundSpeed", "float", None, "m/s it walks at speed 1 (default: measured from "
            "the clip's root motion)"),
    )))
HOLD_BLOCK = declare(BlockDeclaration(
    "Hold", inside=("Avatar",), build=_values_only, repeat=True,
    doc="an object carried by a bone", keys=(
        Key("Object", "ref", None, "the object carried", required=True, ref="Object",
            example='"crate"'),
        Key("Bone", "string", None, "the bone (node name) holding it", required=True,
            example='"hand.R"'),
        Key("Offset", "vec3", (0.0, 0.0, 0.0), "in the bone's frame", unit="m"),
        Key("Orientation", "vec3", (0.0, 0.0, 0.0), "Euler degrees, in the bone's frame"),
    )))
