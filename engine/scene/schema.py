"""Schema: every key a scene file may hold, with its type, default and meaning.

Units and axes, once for the whole format: lengths in metres, masses in
kilograms, times in seconds, angles in degrees (angular rates in degrees per
second), Z is up. Orientation is Euler angles ``[rx ry rz]`` in degrees, applied
about X, then Y, then Z (extrinsic), unless ``Quaternion [w x y z]`` is given.

Sizes of primitives (``Size`` on a Geometry, or on the Object for all its
geometries): box ``[x y z]`` full extents (or ``[s]`` for a cube), sphere
``[diameter]``, capsule and cylinder ``[diameter length]`` along local Z. A
plane is the object's local XY plane through its Position (static only).

Keys starting with a lower-case letter are the author's own variables (usable in
later expressions); keys starting with a capital are checked against this schema.
``UserData { ... }`` holds free-form data for custom systems and is not checked.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from components.joint import SCENE_JOINT_TYPES
from components.shape import ShapeKind
from engine.physics.backend import BackendName

# Field types.
INT_T = "int"
FLOAT_T = "float"
BOOL_T = "bool"
STRING_T = "string"
ASSET_T = "asset"  # a file name, relative to the scene file's folder
VEC3_T = "vec3"
VECTOR_T = "vector"  # numbers; ``lengths`` lists the counts allowed
STRINGVECTOR_T = "stringvector"
STRUCT_T = "struct"
ENUM_T = "enum"
REF_T = "ref"  # the ID of another declaration, of kind ``ref``
NUMBER_OR_VECTOR_T = "number_or_vector"
ANY_T = "any"


@dataclass(frozen=True, slots=True)
class Field:
    type: str
    default: Any = None
    doc: str = ""
    repeat: bool = False
    required: bool = False
    allowed: tuple[str, ...] = ()
    ref: str | None = None
    struct: str | None = None
    lengths: tuple[int, ...] = ()


def _f(type_: str, default: Any = None, doc: str = "", **kw: Any) -> Field:
    return Field(type_, default, doc, **kw)


def _id(kind: str, required: bool = False) -> Field:
    return Field(STRING_T, "", f"name other declarations use to refer to this {kind}",
                 required=required)


PRIMITIVES = (ShapeKind.SPHERE, ShapeKind.BOX, ShapeKind.CAPSULE, ShapeKind.CYLINDER,
              ShapeKind.PLANE)
PARSE_METHODS = ("TriangleMesh", "ConvexHull", "Box", "Sphere")
JOINT_TYPES = tuple(SCENE_JOINT_TYPES)
BACKENDS = tuple(BackendName)

SCHEMAS: dict[str, dict[str, Field]] = {
    "Scene": {
        "Object": _f(STRUCT_T, doc="a body and/or visual", repeat=True, struct="Object"),
        "Model": _f(STRUCT_T, doc="a model file (glTF, Collada) whose bodies, joints and "
                    "materials join the scene", repeat=True, struct="Model"),
        "UserData": _f(ANY_T, doc="free-form data for custom systems", repeat=True),
        "Content": _f(STRING_T, None, "the content folder a saved state continues (relative "
                      "to this file): its file names are relative to that folder, its "
                      "systems/ and scripts/ are the ones used"),
        "ScriptState": _f(STRUCT_T, doc="where a script stood when this state was saved "
                          "(written by --save-state): it resumes instead of starting",
                          repeat=True, struct="ScriptState"),
        "AvatarState": _f(STRUCT_T, doc="where an avatar stood when this state was saved "
                          "(written by --save-state): it resumes instead of starting",
                          repeat=True, struct="AvatarState"),
    },
    "Object": {
        "ID": _id("object"),
        "Position": _f(VEC3_T, (0.0, 0.0, 0.0), "m, world frame"),
        "Orientation": _f(VEC3_T, (0.0, 0.0, 0.0), "Euler degrees [rx ry rz]"),
        "Quaternion": _f(VECTOR_T, None, "exact orientation [w x y z]; wins over Orientation",
                         lengths=(4,)),
        "Velocity": _f(VEC3_T, (0.0, 0.0, 0.0), "m/s"),
        "AngularVelocity": _f(VEC3_T, (0.0, 0.0, 0.0), "deg/s about world X, Y, Z"),
        "Spin": _f(VEC3_T, None, "exact angular velocity, rad/s about world X, Y, Z; wins "
                   "over AngularVelocity (a saved state writes it where degrees cannot hold "
                   "the value to the bit)"),
        "Dynamic": _f(BOOL_T, 1, "0 makes the body static"),
        "Kinematic": _f(BOOL_T, 0, "moved by scripts/controllers, not by forces"),
        "Size": _f(VECTOR_T, None, "primitive size for every geometry (see module doc)",
                   lengths=(1, 2, 3)),
        "VisualAttributes": _f(STRUCT_T, None,
                               "how it looks (no block: drawn as its physical shapes)",
                               struct="Visual"),
        "PhysicalAttributes": _f(STRUCT_T, None,
                                 "its body and collision shapes (no block: not simulated)",
                                 struct="Physical"),
        "UserData": _f(ANY_T, None, "free-form data for custom systems", repeat=True),
        # The sleep rule's state (engine.physics.sleep; written by --save-state so a
        # loaded state falls asleep when the uninterrupted run would).
        "Asleep": _f(BOOL_T, 0, "1: the body starts asleep (until something wakes it)"),
        "SleepVelocity": _f(VECTOR_T, None, "the smoothed velocity of a calm body "
                            "[vx vy vz wx wy wz] (centre of mass; m/s, deg/s)", lengths=(6,)),
        "SleepTimer": _f(FLOAT_T, 0.0, "s the body has been quiet (slow and steady); it "
                         "falls asleep, with what it touches, at the World's SleepTime"),
        "SleepReference": _f(VECTOR_T, None, "the smoothed velocity its quiet stretch began "
                             "with [vx vy vz wx wy wz] (m/s, deg/s)", lengths=(6,)),
        # Its standing with the resting warm start (ODE; World WarmStart).
        "RestSteps": _f(INT_T, 0, "steps (0 to 2) the body has been held up at rest by its "
                        "contacts; at 2 its weight is carried over"),
        "RestSlid": _f(BOOL_T, 0, "1: it slid while its weight was carried over, and has been "
                       "pushed sideways since"),
        "RestForce": _f(VEC3_T, None, "N, the force its contacts hold it with, averaged"),
        "RestPreloaded": _f(BOOL_T, 0, "1: its weight was carried over at the last step (it "
                            "stays so up to a faster drift than it may start at)"),
    },
    "Visual": {
        "Geometry": _f(STRUCT_T, None,
                       "a primitive or model to draw", repeat=True, struct="Geometry"),
        "ShaderState": _f(REF_T, None,
                          "the ShaderState it is drawn with (default: the lit material)",
                          ref="ShaderState"),
        "Shadower": _f(BOOL_T, 1, "casts shadows"),
        "Shadowed": _f(BOOL_T, 1, "receives shadows"),
        "Color": _f(VECTOR_T, (0.8, 0.8, 0.8, 1.0), "RGB or RGBA, 0..1", lengths=(3, 4)),
        "Texture": _f(ASSET_T, None, "image file mapped with the model's texture coordinates "
                      "(or \"generated:marker-ball\", the hands' marker checker, made not read)"),
        "Visible": _f(BOOL_T, 1, "0 hides it"),
    },
    "Physical": {
        "Mass": _f(FLOAT_T, None, "kg; wins over density (default 1 kg when neither is given)"),
        "Density": _f(FLOAT_T, None, "kg/m^3; overrides the material's density"),
        "Material": _f(REF_T, "default", "material ID or number", ref="Material"),
        "Geometry": _f(STRUCT_T, None,
                       "a collision shape (default: one box of the object's Size)", repeat=True,
                       struct="Geometry"),
        "LinearDamping": _f(FLOAT_T, 0.0, "fraction of linear velocity lost per second"),
        "AngularDamping": _f(FLOAT_T, 0.0, "fraction of angular velocity lost per second"),
        "CanSleep": _f(BOOL_T, 1, "0 keeps the body awake even at rest"),
        "Category": _f(INT_T, 1, "collision category bits"),
        "Mask": _f(INT_T, 0xFFFFFFFF, "collides with these category bits"),
        "Gravity": _f(BOOL_T, 1, "0: gravity does not act on this body"),
        "GravityFactor": _f(FLOAT_T, 1.0, "gravity on this body times this (0.5: half; "
                            "-0.5: it rises at half g; KHR's gravityFactor)"),
        "Trigger": _f(BOOL_T, 0, "1: a sensor: nothing collides with it; bodies whose "
                      "Category meets its Mask are told entering and leaving it (Lua: "
                      "on(\"trigger\", fn)); static unless Kinematic"),
        "CenterOfMass": _f(VEC3_T, None, "m, in the object's frame: where its mass is "
                           "centred (default: its shapes' centroid; given alone, the shapes' "
                           "inertia about their centroid moves there)"),
        "Inertia": _f(VEC3_T, None, "kg*m^2, its principal moments of inertia about the "
                      "centre of mass; 0 is infinite: it never turns about that axis "
                      "(default: its shapes' at their density, scaled to Mass)"),
        "InertiaOrientation": _f(VEC3_T, (0.0, 0.0, 0.0), "Euler degrees, in the object's "
                                 "frame: turns its X Y Z onto the axes of Inertia's moments"),
    },
    "Geometry": {
        "Primitive": _f(ENUM_T, None, "shape kind (default box)", allowed=PRIMITIVES),
        "File": _f(ASSET_T, None, "model file (loaded with trimesh)"),
        "Nodes": _f(STRINGVECTOR_T, None, "only these nodes of the File (glTF, Collada): "
                    "their own meshes, placed as in the file relative to the first node "
                    "(its scale included); a name, or #INDEX for an unnamed or repeated one"),
        "Mesh": _f(STRING_T, None, "only this mesh of the File (glTF), in its own space: a "
                   "name, or #INDEX"),
        "Scale": _f(VEC3_T, (1.0, 1.0, 1.0), "model scale"),
        "Size": _f(VECTOR_T, None, "primitive size (see module doc)", lengths=(1, 2, 3)),
        "Offset": _f(VEC3_T, (0.0, 0.0, 0.0), "m, in the object's frame"),
        "Orientation": _f(VEC3_T, (0.0, 0.0, 0.0), "Euler degrees, in the object's frame"),
        "ParseMethod": _f(ENUM_T, None, "physics shape derived from the model",
                          allowed=PARSE_METHODS),
        "Category": _f(INT_T, None, "physics: this shape's own collision category bits "
                       "(default: the object's Category)"),
        "Mask": _f(INT_T, None, "physics: the category bits this shape collides with "
                   "(default: the object's Mask)"),
    },
    "Model": {
        "File": _f(ASSET_T, None, "a .gltf, .glb or .dae file", required=True),
        "Import": _f(BOOL_T, 1, "1: its bodies, joints, materials and extras become the "
                     "scene's, as `colosseum import` writes them; 0: drawn whole, as scenery"),
        "Prefix": _f(STRING_T, "", "put before every ID it declares (to import a model twice)"),
    },
    "Uniform": {
        "ID": _f(STRING_T, None, "uniform name in the GLSL source", required=True),
        "Value": _f(NUMBER_OR_VECTOR_T, None,
                    "a number, or up to 4 numbers (vec2..vec4)", required=True),
    },
    "ScriptState": {
        "Owner": _f(STRING_T, None, "the object whose script this is, or the scene script's "
                    "name by its place (script0, script1, ...)", required=True),
        "Globals": _f(STRING_T, "{}", "the script's global variables, a Lua table "
                      "constructor of data (objects as object('ID'))"),
        "Locals": _f(STRING_T, "{}", "the file's local variables its functions use, the "
                     "same way (a second local of one name is 'name#2')"),
        "Timer": _f(STRUCT_T, None,
                    "a pending after/every timer", repeat=True, struct="ScriptTimer"),
        "Handler": _f(STRUCT_T, None,
                      "an on(event, fn) handler registered while running", repeat=True,
                      struct="ScriptHandler"),
    },
    "ScriptTimer": {
        "Function": _f(STRING_T, None, "the name of the function it calls", required=True),
        "Due": _f(FLOAT_T, None, "s, the simulated time it fires at", required=True),
        "Period": _f(FLOAT_T, 0.0, "s between calls (every); 0 fires once (after)"),
    },
    "ScriptHandler": {
        "Event": _f(STRING_T, None, "the custom event's name (on(name, fn))", required=True),
        "Function": _f(STRING_T, None, "the name of the function it calls", required=True),
    },
    # -- saved avatars (written by --save-state; engine.scene.snapshot) --
    "AvatarState": {
        "Owner": _f(REF_T, None, "the avatar (its ID) this is the state of; its clips, queue, "
                    "path and held objects come from here, not from its block",
                    required=True, ref="Avatar"),
        "Group": _f(STRUCT_T, None, "clips started together (a play, queue or blend), oldest "
                    "first", repeat=True, struct="AnimationGroup"),
        "Queued": _f(STRUCT_T, None, "clips to start when what plays now ends, in turn",
                     repeat=True, struct="AnimationRequest"),
        "Path": _f(VECTOR_T, None, "m, the points [x y z ...] it walks now (no Path: it "
                   "does not walk)"),
        "PathLoop": _f(BOOL_T, 1, "after the last point, walk back to the first"),
        "Waypoint": _f(INT_T, 0, "the point of Path it walks to now (0: the first; the "
                       "number of points: it has arrived)"),
        "Ground": _f(FLOAT_T, None, "m, the ground height under its root last frame "
                     "(ground following; none: not found yet)"),
        "GroundAt": _f(VECTOR_T, None, "[x y] m, where its root stood over that ground",
                       lengths=(2,)),
        "StepOffset": _f(FLOAT_T, 0.0, "m, the height of a step still to be taken (smoothed "
                         "away over the avatar's Smoothing)"),
        "Hold": _f(STRUCT_T, None, "an object it carries", repeat=True, struct="HeldState"),
        "Drive": _f(STRUCT_T, None, "a bone held at a world pose (a tracked hand)",
                    repeat=True, struct="BoneDrive"),
        "CapsulePosition": _f(VEC3_T, None, "m, where its capsule's body is"),
        "CapsuleQuaternion": _f(VECTOR_T, None, "its capsule's orientation [w x y z]",
                                lengths=(4,)),
    },
    "AnimationGroup": {
        "Phase": _f(FLOAT_T, 0.0, "how far through its clips, 0..1 (a clip's time is this "
                    "times its length)"),
        "Loop": _f(BOOL_T, 1, "1: it starts again at its end; 0: it ends there"),
        "Ended": _f(BOOL_T, 0, "1: it reached its end (onAnimationEnd was called)"),
        "Current": _f(BOOL_T, 0, "1: what the avatar plays now (the other groups fade out)"),
        "Layer": _f(STRUCT_T, None, "one of its clips", repeat=True, struct="AnimationLayer"),
    },
    "AnimationLayer": {
        "Clip": _f(STRING_T, None, "the clip's name in the model", required=True),
        "Speed": _f(FLOAT_T, 1.0, "playback rate"),
        "Weight": _f(FLOAT_T, 1.0, "its weight in the blend now"),
        "FadeFrom": _f(FLOAT_T, 1.0, "the weight its fade started at"),
        "FadeTo": _f(FLOAT_T, 1.0, "the weight its fade ends at (0: fading out)"),
        "FadeTime": _f(FLOAT_T, 0.0, "s of its fade gone"),
        "FadeLength": _f(FLOAT_T, 0.0, "s its fade takes (0: none)"),
    },
    "AnimationRequest": {
        "Clips": _f(STRINGVECTOR_T, None, "the clips it starts together", required=True),
        "Weights": _f(VECTOR_T, None, "the weight of each clip (default: 1 each)"),
        "Fade": _f(FLOAT_T, 0.0, "s, the crossfade it starts with"),
        "Speed": _f(FLOAT_T, None, "playback rate (default: each clip's)"),
        "Loop": _f(BOOL_T, None, "1 or 0 (default: the first clip's)"),
    },
    "HeldState": {
        "Object": _f(REF_T, None, "the object carried", required=True, ref="Object"),
        "Bone": _f(STRING_T, None, "the bone (node name) holding it", required=True),
        "Offset": _f(VEC3_T, (0.0, 0.0, 0.0), "m, in the bone's frame"),
        "Quaternion": _f(VECTOR_T, (1.0, 0.0, 0.0, 0.0), "its orientation in the bone's "
                         "frame [w x y z]", lengths=(4,)),
        "Last": _f(VEC3_T, None, "m, where it was put last frame (a dynamic object moves on "
                   "at the hand's velocity)"),
    },
    "BoneDrive": {
        "Bone": _f(STRING_T, None, "the bone held", required=True),
        "Position": _f(VEC3_T, None, "m, world frame", required=True),
        "Quaternion": _f(VECTOR_T, None, "world orientation [w x y z]", required=True,
                         lengths=(4,)),
    },
}

#: Declarations whose ``ID`` others may reference, by the schema name used in ``Field.ref``.
ID_KINDS = ("Object", "Material", "Joint", "VertexShader", "FragmentShader", "ShaderProgram",
            "ShaderState", "Sound", "Camera", "Light", "Controller", "Avatar")

