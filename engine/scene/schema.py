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


#: Auto-sleep: a body at rest this many steps in a row falls asleep; the rest test
#: averages this many velocity samples (mirrors engine.physics.ode3d._ode).
SLEEP_STEPS = 20
SLEEP_SAMPLES = 5

PRIMITIVES = (ShapeKind.SPHERE, ShapeKind.BOX, ShapeKind.CAPSULE, ShapeKind.CYLINDER,
              ShapeKind.PLANE)
PARSE_METHODS = ("TriangleMesh", "ConvexHull", "Box", "Sphere")
JOINT_TYPES = tuple(SCENE_JOINT_TYPES)
LIGHT_TYPES = ("directional", "point", "spot")
BACKENDS = tuple(BackendName)

SCHEMAS: dict[str, dict[str, Field]] = {
    "Scene": {
        "Object": _f(STRUCT_T, doc="a body and/or visual", repeat=True, struct="Object"),
        "Material": _f(STRUCT_T, doc="surface properties", repeat=True, struct="Material"),
        "MaterialPair": _f(STRUCT_T, doc="contact parameters for two materials", repeat=True,
                           struct="MaterialPair"),
        "Joint": _f(STRUCT_T, doc="a constraint between bodies", repeat=True, struct="Joint"),
        "VertexShader": _f(STRUCT_T, repeat=True, struct="VertexShader"),
        "FragmentShader": _f(STRUCT_T, repeat=True, struct="FragmentShader"),
        "ShaderProgram": _f(STRUCT_T, repeat=True, struct="ShaderProgram"),
        "ShaderState": _f(STRUCT_T, repeat=True, struct="ShaderState"),
        "Sound": _f(STRUCT_T, doc="a sound not attached to an object", repeat=True,
                    struct="Sound"),
        "Camera": _f(STRUCT_T, repeat=True, struct="Camera"),
        "Light": _f(STRUCT_T, repeat=True, struct="Light"),
        "Script": _f(ASSET_T, doc="a Lua script run for the whole scene", repeat=True),
        "Controller": _f(STRUCT_T, repeat=True, struct="Controller"),
        "World": _f(STRUCT_T, doc="dynamics settings", struct="World"),
        "Model": _f(STRUCT_T, doc="a model file (glTF, Collada) whose bodies, joints and "
                    "materials join the scene", repeat=True, struct="Model"),
        "UserData": _f(ANY_T, doc="free-form data for custom systems", repeat=True),
    },
    "Object": {
        "ID": _id("object"),
        "Position": _f(VEC3_T, (0.0, 0.0, 0.0), "m, world frame"),
        "Orientation": _f(VEC3_T, (0.0, 0.0, 0.0), "Euler degrees [rx ry rz]"),
        "Quaternion": _f(VECTOR_T, None, "exact orientation [w x y z]; wins over Orientation",
                         lengths=(4,)),
        "Velocity": _f(VEC3_T, (0.0, 0.0, 0.0), "m/s"),
        "AngularVelocity": _f(VEC3_T, (0.0, 0.0, 0.0), "deg/s about world X, Y, Z"),
        "Dynamic": _f(BOOL_T, 1, "0 makes the body static"),
        "Kinematic": _f(BOOL_T, 0, "moved by scripts/controllers, not by forces"),
        "Size": _f(VECTOR_T, None, "primitive size for every geometry (see module doc)",
                   lengths=(1, 2, 3)),
        "VisualAttributes": _f(STRUCT_T, struct="Visual"),
        "PhysicalAttributes": _f(STRUCT_T, struct="Physical"),
        "Sound": _f(STRUCT_T, doc="sound source on this object", struct="Sound"),
        "Script": _f(ASSET_T, doc="Lua script attached to this object"),
        "Hand": _f(STRUCT_T, struct="Hand"),
        "Controller": _f(STRUCT_T, doc="input bound to this object", struct="Controller"),
        "UserData": _f(ANY_T, repeat=True),
        # Auto-sleep state (written by --save-state so a loaded state sleeps on time).
        "Asleep": _f(BOOL_T, 0, "1: the body starts asleep (until something wakes it)"),
        "IdleSteps": _f(INT_T, 0, f"steps in a row the body has been at rest; it falls "
                        f"asleep after {SLEEP_STEPS}"),
        "VelocitySamples": _f(VECTOR_T, None, "the last velocities auto-sleep averages, "
                              "oldest first: [vx vy vz wx wy wz] per sample, m/s and deg/s "
                              f"of the centre of mass, at most {SLEEP_SAMPLES} samples",
                              lengths=tuple(range(6, 6 * SLEEP_SAMPLES + 1, 6))),
    },
    "Visual": {
        "Geometry": _f(STRUCT_T, repeat=True, struct="Geometry"),
        "ShaderState": _f(REF_T, None, ref="ShaderState"),
        "Shadower": _f(BOOL_T, 1, "casts shadows"),
        "Shadowed": _f(BOOL_T, 1, "receives shadows"),
        "Color": _f(VECTOR_T, (0.8, 0.8, 0.8, 1.0), "RGB or RGBA, 0..1", lengths=(3, 4)),
        "Texture": _f(ASSET_T),
        "Visible": _f(BOOL_T, 1),
    },
    "Physical": {
        "Mass": _f(FLOAT_T, None, "kg; wins over density (default 1 kg when neither is given)"),
        "Density": _f(FLOAT_T, None, "kg/m^3; overrides the material's density"),
        "Material": _f(REF_T, "default", "material ID or number", ref="Material"),
        "Geometry": _f(STRUCT_T, repeat=True, struct="Geometry"),
        "LinearDamping": _f(FLOAT_T, 0.0),
        "AngularDamping": _f(FLOAT_T, 0.0),
        "CanSleep": _f(BOOL_T, 1),
        "Category": _f(INT_T, 1, "collision category bits"),
        "Mask": _f(INT_T, 0xFFFFFFFF, "collides with these category bits"),
        "Gravity": _f(BOOL_T, 1, "0: gravity does not act on this body"),
        "Trigger": _f(BOOL_T, 0, "1: a sensor: nothing collides with it; bodies whose "
                      "Category meets its Mask are told entering and leaving it (Lua: "
                      "on(\"trigger\", fn)); static unless Kinematic"),
    },
    "Geometry": {
        "Primitive": _f(ENUM_T, None, allowed=PRIMITIVES),
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
    },
    "Model": {
        "File": _f(ASSET_T, None, "a .gltf, .glb or .dae file", required=True),
        "Import": _f(BOOL_T, 1, "1: its bodies, joints, materials and extras become the "
                     "scene's, as `colosseum import` writes them; 0: drawn whole, as scenery"),
        "Prefix": _f(STRING_T, "", "put before every ID it declares (to import a model twice)"),
    },
    "Material": {
        "ID": Field(STRING_T, None, "name or number objects use to refer to it", required=True),
        "Friction": _f(FLOAT_T, 0.5, "Coulomb coefficient"),
        "Bounce": _f(FLOAT_T, 0.0, "restitution 0..1"),
        "BounceVelocity": _f(FLOAT_T, 0.1, "m/s below which nothing bounces"),
        "Softness": _f(FLOAT_T, 0.0, "contact softness (0 = hard)"),
        "Density": _f(FLOAT_T, 1000.0, "kg/m^3"),
        "ContactSound": _f(ASSET_T, None, "played on impacts"),
    },
    "MaterialPair": {
        "Material1": _f(REF_T, None, required=True, ref="Material"),
        "Material2": _f(REF_T, None, required=True, ref="Material"),
        "Friction": _f(FLOAT_T),
        "Bounce": _f(FLOAT_T),
        "Softness": _f(FLOAT_T),
        "Collide": _f(BOOL_T, 1),
    },
    "Joint": {
        "ID": _id("joint"),
        "Type": _f(ENUM_T, None, required=True, allowed=JOINT_TYPES),
        "Bodies": _f(STRINGVECTOR_T, None, "one object (jointed to the world) or two",
                     required=True, ref="Object", lengths=(1, 2)),
        "Anchor": _f(VEC3_T, None, "m, world frame, with the bodies at their reference poses "
                     "(default: first body's position)"),
        "Axis": _f(VEC3_T, (0.0, 0.0, 1.0)),
        "Axis2": _f(VEC3_T, (0.0, 1.0, 0.0)),
        "Low": _f(FLOAT_T, None, "lower limit: degrees, or m for a slider"),
        "High": _f(FLOAT_T, None, "upper limit: degrees, or m for a slider"),
        "MotorVelocity": _f(FLOAT_T, 0.0, "deg/s, or m/s for a slider"),
        "MotorMaxForce": _f(FLOAT_T, 0.0, "N*m, or N for a slider"),
        "ReferencePose1": _f(VECTOR_T, None, "[x y z qw qx qy qz] (m, quaternion): the first "
                             "body's pose when the joint was first made; Anchor and axes are "
                             "as they were then (default: the body's own pose)", lengths=(7,)),
        "ReferencePose2": _f(VECTOR_T, None, "the same for the second body", lengths=(7,)),
    },
    "VertexShader": {"ID": _id("vertex shader", True), "File": _f(ASSET_T, required=True)},
    "FragmentShader": {"ID": _id("fragment shader", True), "File": _f(ASSET_T, required=True)},
    "ShaderProgram": {
        "ID": _id("shader program", True),
        "VertexShader": _f(REF_T, None, ref="VertexShader"),
        "FragmentShader": _f(REF_T, None, ref="FragmentShader"),
        "Enable": _f(BOOL_T, 1),
    },
    "ShaderState": {
        "ID": _id("shader state", True),
        "ShaderProgram": _f(REF_T, None, required=True, ref="ShaderProgram"),
        "Uniform": _f(STRUCT_T, repeat=True, struct="Uniform"),
    },
    "Uniform": {
        "ID": _f(STRING_T, None, "uniform name in the GLSL source", required=True),
        "Value": _f(NUMBER_OR_VECTOR_T, None, required=True),
    },
    "Sound": {
        "ID": _id("sound"),
        "File": _f(ASSET_T, None, ".wav or .ogg", required=True),
        "Position": _f(VEC3_T, (0.0, 0.0, 0.0),
                       "m (scene sounds only; without it the sound plays at the listener)"),
        "Loop": _f(BOOL_T, 0),
        "Gain": _f(FLOAT_T, 1.0),
        "Pitch": _f(FLOAT_T, 1.0),
        "RefDistance": _f(FLOAT_T, 1.0, "m"),
        "Rolloff": _f(FLOAT_T, 1.0),
        "MaxDistance": _f(FLOAT_T, 1000.0, "m"),
        "AutoPlay": _f(BOOL_T, 0),
        "Priority": _f(INT_T, 0, "higher keeps its voice when sources run out"),
    },
    "Camera": {
        "ID": _id("camera"),
        "Position": _f(VEC3_T, (0.0, -5.0, 2.0)),
        "LookAt": _f(VEC3_T, (0.0, 0.0, 0.0)),
        "Fov": _f(FLOAT_T, 60.0, "degrees, vertical"),
        "Near": _f(FLOAT_T, 0.05),
        "Far": _f(FLOAT_T, 500.0),
        "Active": _f(BOOL_T, 1),
        "Follow": _f(REF_T, None, "object to follow at Offset", ref="Object"),
        "Offset": _f(VEC3_T, (0.0, 0.0, 0.0)),
        "EyeSeparation": _f(FLOAT_T, 0.0, "m; > 0 renders stereo"),
    },
    "Light": {
        "ID": _id("light"),
        "Type": _f(ENUM_T, "directional", allowed=LIGHT_TYPES),
        "Position": _f(VEC3_T, (0.0, 0.0, 10.0)),
        "Direction": _f(VEC3_T, (0.3, 0.5, -1.0)),
        "Color": _f(VEC3_T, (1.0, 1.0, 1.0)),
        "Intensity": _f(FLOAT_T, 1.0),
        "Cutoff": _f(FLOAT_T, 30.0, "spot cone half-angle, degrees"),
        "Shadows": _f(BOOL_T, 1),
    },
    "Controller": {
        "ID": _id("controller"),
        "Input": _f(STRING_T, None, '"key:Up/Down", "axis:0", "tracker:NAME", "wheel:NAME"',
                    required=True),
        "Target": _f(STRING_T, None, '"motor:JOINT", "force:OBJECT" or "kinematic:OBJECT"',
                     required=True),
        "Gain": _f(FLOAT_T, 1.0),
        "Low": _f(FLOAT_T, None),
        "High": _f(FLOAT_T, None),
    },
    "Hand": {
        "Tracker": _f(STRING_T, "", "tracked device driving the hand"),
        "MaxForce": _f(FLOAT_T, 200.0, "N"),
        "MaxTorque": _f(FLOAT_T, 20.0, "N*m"),
        "DeviationDistance": _f(FLOAT_T, 0.3, "m before the hand is reset to the tracker"),
    },
    "World": {
        "Gravity": _f(VEC3_T, (0.0, 0.0, -9.81), "m/s^2"),
        "TimeStep": _f(FLOAT_T, 0.01, "s, fixed dynamics step"),
        "Dynamics": _f(ENUM_T, "ode", "dynamics backend: ode (3D) or pymunk (2D, X-Z plane)",
                       allowed=BACKENDS),
        "Iterations": _f(INT_T, 20),
        "ERP": _f(FLOAT_T, 0.2, "error reduction per step"),
        "CFM": _f(FLOAT_T, 1e-5, "constraint force mixing"),
        "MaxContacts": _f(INT_T, 4, "per pair of geometries"),
        "AutoSleep": _f(BOOL_T, 1),
        "Time": _f(FLOAT_T, 0.0, "s, simulated time this state was saved at"),
        "SolverSeed": _f(INT_T, None, "the solver's random state when this state was saved"),
    },
}

#: Declarations whose ``ID`` others may reference, by the schema name used in ``Field.ref``.
ID_KINDS = ("Object", "Material", "Joint", "VertexShader", "FragmentShader", "ShaderProgram",
            "ShaderState", "Sound", "Camera", "Light", "Controller")

