"""Skinned glTF files made from code (pygltflib): the avatars the content and the tests use.

``python -m tools.gltf_samples`` writes the shipped ones:

* ``content/avatars/models/walker.glb``: a low-poly figure (17 joints: hips, spine, chest,
  neck, head, arms, legs) with the clips Idle, Walk and Run (root motion: 1.4 and 3.5 m/s),
  CarryWalk (arms held forward), and Wave (cubic-spline rotations, a STEP hand), its shirt
  textured;
* ``tests/avatars/samples/walker_lost_texture.gltf`` + ``.bin``: the same, its texture file
  missing (as a model copied without its images).

:func:`two_bone` writes the small two-joint bar the tests compute by hand, optionally broken
in the ways real files are (no skin, five influences, weights that do not sum to 1,
keyframes out of order, a missing buffer). Everything is in glTF's frame: Y up, front +Z.
"""

from __future__ import annotations

import io
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pygltflib as gl

FLOAT, USHORT, UINT = 5126, 5123, 5125
#: The weights of :func:`two_bone` with ``influences=5``: joints root, tip, root, tip, tip.
FIVE_INFLUENCES = (0.3, 0.25, 0.2, 0.15, 0.1)
_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}


@dataclass
class _Writer:
    """Accessors appended to one binary buffer."""

    gltf: gl.GLTF2 = field(default_factory=gl.GLTF2)
    blob: bytearray = field(default_factory=bytearray)

    def accessor(self, data: np.ndarray, component: int = FLOAT, minmax: bool = False,
                 target: int | None = None) -> int:
        dtype = {FLOAT: np.float32, USHORT: np.uint16, UINT: np.uint32}[component]
        arr = np.ascontiguousarray(data, dtype)
        width = 1 if arr.ndim == 1 else arr.shape[1]
        while len(self.blob) % 4:
            self.blob.append(0)
        view = gl.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=arr.nbytes,
                             target=target)
        self.blob.extend(arr.tobytes())
        self.gltf.bufferViews.append(view)
        acc = gl.Accessor(bufferView=len(self.gltf.bufferViews) - 1, componentType=component,
                          count=len(arr), type=_TYPES[width])
        if minmax:
            flat = arr.reshape(len(arr), -1)
            acc.min, acc.max = flat.min(axis=0).tolist(), flat.max(axis=0).tolist()
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1

    def image(self, rgba: np.ndarray) -> int:
        from PIL import Image

        out = io.BytesIO()
        Image.fromarray(rgba, "RGBA").save(out, format="PNG")
        while len(self.blob) % 4:
            self.blob.append(0)
        self.gltf.bufferViews.append(gl.BufferView(buffer=0, byteOffset=len(self.blob),
                                                   byteLength=len(out.getvalue())))
        self.blob.extend(out.getvalue())
        self.gltf.images.append(gl.Image(bufferView=len(self.gltf.bufferViews) - 1,
                                         mimeType="image/png"))
        return len(self.gltf.images) - 1

    def save(self, path: Path, external_bin: bool | None = None, write_bin: bool = True) -> Path:
        """A .glb (one file) or a .gltf with its buffer in a .bin beside it."""
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".glb" and not external_bin:
            self.gltf.buffers = [gl.Buffer(byteLength=len(self.blob))]
            self.gltf.set_binary_blob(bytes(self.blob))
            self.gltf.save_binary(str(path))
            return path
        bin_name = path.with_suffix(".bin").name
        self.gltf.buffers = [gl.Buffer(byteLength=len(self.blob), uri=bin_name)]
        if write_bin:
            path.with_suffix(".bin").write_bytes(bytes(self.blob))
        self.gltf.save_json(str(path))
        return path


def _quat_x(deg: np.ndarray) -> np.ndarray:
    """glTF rotations (x, y, z, w) about X by ``deg``."""
    h = np.radians(np.asarray(deg, np.float64)) / 2
    return np.stack([np.sin(h), 0 * h, 0 * h, np.cos(h)], axis=-1)


def _quat_z(deg: np.ndarray) -> np.ndarray:
    h = np.radians(np.asarray(deg, np.float64)) / 2
    return np.stack([0 * h, 0 * h, np.sin(h), np.cos(h)], axis=-1)


# -- the two-bone bar ------------------------------------------------------------------
def two_bone(path: Path, interpolation: str = "LINEAR", influences: int = 4,
             weight_scale: float = 1.0, times_out_of_order: bool = False,
             missing_buffer: bool = False, skinned: bool = True) -> Path:
    """A bar 2 m tall along +Y made of two joints, ``root`` at the origin and ``tip`` at
    (0, 1, 0); vertices above y = 1 follow ``tip``, below follow ``root``, the middle ring
    half each. Clip ``Bend`` turns ``tip`` about Z from 0° (t = 0) to 90° (t = 1 s);
    clip ``Lift`` moves ``root`` up 1 m over 2 s. A ``.glb`` unless ``missing_buffer``
    (then a ``.gltf`` whose ``.bin`` is not written)."""
    w = _Writer()
    g = w.gltf
    g.asset = gl.Asset(version="2.0", generator="colosseum tools/gltf_samples.py")
    ys = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    ring = np.array([[0.1, 0.0], [0.0, 0.1], [-0.1, 0.0], [0.0, -0.1]])
    vertices = np.array([[x, y, z] for y in ys for x, z in ring])
    faces = []
    for i in range(len(ys) - 1):
        for k in range(4):
            a, b = i * 4 + k, i * 4 + (k + 1) % 4
            faces += [[a, b, a + 4], [b, b + 4, a + 4]]
    tip_weight = np.repeat(np.clip(ys - 0.5, 0.0, 1.0), 4)  # 0, 0, .5, 1, 1
    weights = np.zeros((len(vertices), 4))
    weights[:, 0] = 1.0 - tip_weight
    weights[:, 1] = tip_weight
    joints = np.tile([0, 1, 0, 0], (len(vertices), 1))
    attributes = {"POSITION": w.accessor(vertices, minmax=True, target=34962)}
    if skinned:
        attributes["JOINTS_0"] = w.accessor(joints, USHORT)
        attributes["WEIGHTS_0"] = w.accessor(weights * weight_scale)
        if influences > 4:  # every vertex: five influences, the fifth (0.1) the smallest
            n = len(vertices)
            extra = np.zeros((n, 4))
            extra[:, 0] = 0.1
            attributes["JOINTS_0"] = w.accessor(np.tile([0, 1, 0, 1], (n, 1)), USHORT)
            attributes["WEIGHTS_0"] = w.accessor(np.tile(FIVE_INFLUENCES[:4], (n, 1)))
            attributes["JOINTS_1"] = w.accessor(np.tile([1, 0, 0, 0], (n, 1)), USHORT)
            attributes["WEIGHTS_1"] = w.accessor(extra)
    indices = w.accessor(np.array(faces).reshape(-1), USHORT, target=34963)
    g.meshes = [gl.Mesh(name="bar", primitives=[gl.Primitive(
        attributes=gl.Attributes(**attributes), indices=indices)])]
    g.nodes = [gl.Node(name="bar", mesh=0, skin=0 if skinned else None),
               gl.Node(name="root", children=[2]),
               gl.Node(name="tip", translation=[0.0, 1.0, 0.0])]
    g.scenes = [gl.Scene(nodes=[0, 1])]
    g.scene = 0
    if skinned:
        ibm = np.stack([np.eye(4), np.eye(4)])
        ibm[1, 1, 3] = -1.0  # inverse of the tip's bind translation (0, 1, 0)
        g.skins = [gl.Skin(joints=[1, 2], inverseBindMatrices=w.accessor(
            ibm.transpose(0, 2, 1).reshape(2, 16)))]
    bend_times = np.array([0.0, 0.5, 1.0])
    if times_out_of_order:
        bend_times = np.array([0.0, 1.0, 0.5])
    if interpolation == "CUBICSPLINE":  # zero tangents: an ease-in, ease-out turn
        values = np.zeros((3, 3, 4))
        values[:, 1] = _quat_z(np.array([0.0, 45.0, 90.0]))
        bend_values = values.reshape(-1, 4)
    else:
        bend_values = _quat_z(np.array([0.0, 45.0, 90.0]))
    lift = [w.accessor(np.array([0.0, 2.0])), w.accessor(np.array([[0, 0, 0], [0, 1.0, 0]]))]
    g.animations = [
        gl.Animation(name="Bend", samplers=[gl.AnimationSampler(
            input=w.accessor(bend_times, minmax=True), output=w.accessor(bend_values),
            interpolation=interpolation)],
            channels=[gl.AnimationChannel(sampler=0, target=gl.AnimationChannelTarget(
                node=2, path="rotation"))]),
        gl.Animation(name="Lift", samplers=[gl.AnimationSampler(
            input=lift[0], output=lift[1], interpolation="LINEAR")],
            channels=[gl.AnimationChannel(sampler=0, target=gl.AnimationChannelTarget(
                node=1, path="translation"))])]
    if missing_buffer:
        return w.save(path.with_suffix(".gltf"), write_bin=False)
    return w.save(path)


# -- the walker ----------------------------------------------------------------------------
#: (name, parent, translation from the parent) in glTF axes: +X is the figure's left.
SKELETON = (
    ("hips", None, (0.0, 0.95, 0.0)),
    ("spine", "hips", (0.0, 0.15, 0.0)),
    ("chest", "spine", (0.0, 0.25, 0.0)),
    ("neck", "chest", (0.0, 0.22, 0.0)),
    ("head", "neck", (0.0, 0.1, 0.0)),
    ("upper_arm.L", "chest", (0.2, 0.18, 0.0)),
    ("forearm.L", "upper_arm.L", (0.0, -0.28, 0.0)),
    ("hand.L", "forearm.L", (0.0, -0.26, 0.0)),
    ("upper_arm.R", "chest", (-0.2, 0.18, 0.0)),
    ("forearm.R", "upper_arm.R", (0.0, -0.28, 0.0)),
    ("hand.R", "forearm.R", (0.0, -0.26, 0.0)),
    ("thigh.L", "hips", (0.1, -0.05, 0.0)),
    ("shin.L", "thigh.L", (0.0, -0.42, 0.0)),
    ("foot.L", "shin.L", (0.0, -0.42, 0.0)),
    ("thigh.R", "hips", (-0.1, -0.05, 0.0)),
    ("shin.R", "thigh.R", (0.0, -0.42, 0.0)),
    ("foot.R", "shin.R", (0.0, -0.42, 0.0)),
)
NAMES = tuple(s[0] for s in SKELETON)
#: Limbs drawn: bone, child point (where the segment ends, in the bone's frame), radius.
_LIMBS = (
    ("hips", (0.0, 0.15, 0.0), 0.14), ("spine", (0.0, 0.25, 0.0), 0.15),
    ("chest", (0.0, 0.22, 0.0), 0.17), ("neck", (0.0, 0.1, 0.0), 0.05),
    ("head", (0.0, 0.24, 0.0), 0.11),
    ("upper_arm.L", (0.0, -0.28, 0.0), 0.05), ("forearm.L", (0.0, -0.26, 0.0), 0.045),
    ("hand.L", (0.0, -0.12, 0.0), 0.04),
    ("upper_arm.R", (0.0, -0.28, 0.0), 0.05), ("forearm.R", (0.0, -0.26, 0.0), 0.045),
    ("hand.R", (0.0, -0.12, 0.0), 0.04),
    ("thigh.L", (0.0, -0.42, 0.0), 0.07), ("shin.L", (0.0, -0.42, 0.0), 0.055),
    ("foot.L", (0.0, -0.04, 0.16), 0.045),
    ("thigh.R", (0.0, -0.42, 0.0), 0.07), ("shin.R", (0.0, -0.42, 0.0), 0.055),
    ("foot.R", (0.0, -0.04, 0.16), 0.045),
)
_SHIRT = ("spine", "chest", "upper_arm.L", "upper_arm.R")


def _bind_positions() -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name, parent, t in SKELETON:
        out[name] = np.asarray(t) + (out[parent] if parent else 0.0)
    return out


def _limb(start: np.ndarray, end: np.ndarray, radius: float, bone: int, parent: int,
          sides: int = 8, rings: int = 5) -> tuple[np.ndarray, ...]:
    """A tube from ``start`` to ``end`` (closed by flat caps' centres), weighted to
    ``bone`` and, in its first fifth, blended with ``parent``."""
    axis = end - start
    length = float(np.linalg.norm(axis))
    d = axis / length
    helper = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 0, 1.0])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    verts, normals, uvs, joints, weights = [], [], [], [], []
    for r in range(rings + 1):
        f = r / rings
        taper = radius * (1.0 - 0.25 * abs(2 * f - 1) ** 2)
        w_parent = 0.5 * max(0.0, 1.0 - f / 0.2) if parent >= 0 else 0.0
        for k in range(sides):
            a = 2 * math.pi * k / sides
            n = math.cos(a) * u + math.sin(a) * v
            verts.append(start + axis * f + n * taper)
            normals.append(n)
            uvs.append((k / sides, f))
            joints.append((bone, max(parent, 0), 0, 0))
            weights.append((1.0 - w_parent, w_parent, 0.0, 0.0))
    faces = []
    for r in range(rings):
        for k in range(sides):
            a, b = r * sides + k, r * sides + (k + 1) % sides
            faces += [(a, b, a + sides), (b, b + sides, a + sides)]
    base = len(verts)
    for cap, (centre, n) in enumerate(((start, -d), (end, d))):  # caps
        verts.append(centre)
        normals.append(n)
        uvs.append((0.5, float(cap)))
        joints.append((bone, max(parent, 0), 0, 0))
        weights.append((1.0, 0.0, 0.0, 0.0))
        ring0 = 0 if cap == 0 else rings * sides
        for k in range(sides):
            a, b = ring0 + k, ring0 + (k + 1) % sides
            faces.append((base + cap, b, a) if cap == 0 else (base + cap, a, b))
    return (np.array(verts), np.array(normals), np.array(uvs), np.array(faces),
            np.array(joints), np.array(weights))


def _walker_mesh(w: _Writer, texture_source: int | None) -> None:
    bind = _bind_positions()
    parts: dict[bool, list[tuple[np.ndarray, ...]]] = {True: [], False: []}
    parents = {name: parent for name, parent, _ in SKELETON}
    for bone, end, radius in _LIMBS:
        parent = parents[bone]
        p = NAMES.index(parent) if parent else -1
        start = bind[bone]
        parts[bone in _SHIRT].append(_limb(start, start + np.asarray(end), radius,
                                           NAMES.index(bone), p))
    g = w.gltf
    g.materials = [
        gl.Material(name="skin", pbrMetallicRoughness=gl.PbrMetallicRoughness(
            baseColorFactor=[0.85, 0.68, 0.55, 1.0], metallicFactor=0.0)),
        gl.Material(name="shirt", pbrMetallicRoughness=gl.PbrMetallicRoughness(
            baseColorFactor=[1.0, 1.0, 1.0, 1.0], metallicFactor=0.0,
            baseColorTexture=None if texture_source is None else gl.TextureInfo(index=0)))]
    primitives = []
    for shirt in (False, True):
        arrays = parts[shirt]
        offsets = np.cumsum([0] + [len(a[0]) for a in arrays[:-1]])
        v, n, uv, f, j, wt = (np.concatenate([a[i] + (o if i == 3 else 0)
                                              for a, o in zip(arrays, offsets, strict=True)])
                              for i in range(6))
        attrs = gl.Attributes(POSITION=w.accessor(v, minmax=True, target=34962),
                              NORMAL=w.accessor(n, target=34962),
                              TEXCOORD_0=w.accessor(uv, target=34962),
                              JOINTS_0=w.accessor(j, USHORT, target=34962),
                              WEIGHTS_0=w.accessor(wt, target=34962))
        primitives.append(gl.Primitive(attributes=attrs, indices=w.accessor(
            f.reshape(-1), USHORT, target=34963), material=int(shirt)))
    g.meshes = [gl.Mesh(name="walker", primitives=primitives)]


def _walker_clips(w: _Writer) -> None:
    """Idle, Walk, Run, CarryWalk (LINEAR), Wave (CUBICSPLINE arm, STEP hand)."""
    idx = {name: i + 1 for i, name in enumerate(NAMES)}  # node 0 is the mesh node
    hips_y = SKELETON[0][2][1]

    def gait(period: float, stride: float, swing: float, knee: float, bob: float,
             arm: float | None, keys: int = 17) -> list[tuple[str, str, np.ndarray, np.ndarray]]:
        t = np.linspace(0.0, period, keys)
        ph = 2 * math.pi * t / period
        hips = np.stack([0 * t, hips_y - bob * (1 + np.cos(2 * ph)) / 2, stride * t / period], 1)
        out = [("hips", "translation", t, hips)]
        for side, sign in (("L", 1.0), ("R", -1.0)):
            out.append((f"thigh.{side}", "rotation", t, _quat_x(-swing * sign * np.sin(ph))))
            bend = knee * np.maximum(0.0, np.sin(ph + (0 if sign > 0 else math.pi) + 0.6))
            out.append((f"shin.{side}", "rotation", t, _quat_x(bend)))
            if arm is None:  # carrying: both arms forward, still
                out.append((f"upper_arm.{side}", "rotation", t, _quat_x(-70.0 + 0 * t)))
                out.append((f"forearm.{side}", "rotation", t, _quat_x(-20.0 + 0 * t)))
            else:
                out.append((f"upper_arm.{side}", "rotation", t, _quat_x(arm * sign * np.sin(ph))))
                out.append((f"forearm.{side}", "rotation", t, _quat_x(-15.0 + 0 * t)))
        return out

    t_idle = np.linspace(0.0, 2.0, 9)
    idle = [("chest", "rotation", t_idle, _quat_x(3.0 * np.sin(math.pi * t_idle))),
            ("upper_arm.L", "rotation", t_idle, _quat_z(5.0 + 0 * t_idle)),
            ("upper_arm.R", "rotation", t_idle, _quat_z(-5.0 + 0 * t_idle))]
    clips = {"Idle": [(n, p, t, v, "LINEAR") for n, p, t, v in idle],
             "Walk": [(*c, "LINEAR") for c in gait(1.0, 1.4, 25.0, 40.0, 0.03, 20.0)],
             "Run": [(*c, "LINEAR") for c in gait(0.7, 2.45, 45.0, 80.0, 0.06, 45.0)],
             "CarryWalk": [(*c, "LINEAR") for c in gait(1.0, 1.4, 25.0, 40.0, 0.03, None)]}
    t_wave = np.array([0.0, 0.5, 1.0, 1.5])
    raise_deg = np.array([0.0, 160.0, 160.0, 0.0])
    cubic = np.zeros((4, 3, 4))
    cubic[:, 1] = _quat_z(-raise_deg)  # the right arm up (about -Z for the figure's right)
    wave_hand = _quat_z(np.array([0.0, 30.0, -30.0, 0.0]))
    clips["Wave"] = [("upper_arm.R", "rotation", t_wave, cubic.reshape(-1, 4), "CUBICSPLINE"),
                     ("hand.R", "rotation", t_wave, wave_hand, "STEP")]
    g = w.gltf
    for name, channels in clips.items():
        anim = gl.Animation(name=name)
        for node, path_, t, values, kind in channels:
            anim.samplers.append(gl.AnimationSampler(input=w.accessor(t, minmax=True),
                                                     output=w.accessor(values),
                                                     interpolation=kind))
            anim.channels.append(gl.AnimationChannel(sampler=len(anim.samplers) - 1,
                                                     target=gl.AnimationChannelTarget(
                                                         node=idx[node], path=path_)))
        g.animations.append(anim)


def walker(path: Path, texture: bool = True, lost_texture: bool = False) -> Path:
    """The walking figure (see the module doc); ``lost_texture`` writes a .gltf whose
    shirt texture names a file that is not there."""
    w = _Writer()
    g = w.gltf
    g.asset = gl.Asset(version="2.0", generator="colosseum tools/gltf_samples.py")
    source = None
    if lost_texture:
        g.images = [gl.Image(uri="shirt.png")]
        source = 0
    elif texture:
        stripes = np.zeros((32, 32, 4), np.uint8)
        stripes[:] = (40, 90, 200, 255)
        stripes[::8] = (240, 240, 240, 255)
        stripes[1::8] = (240, 240, 240, 255)
        source = w.image(stripes)
    if source is not None:
        g.samplers = [gl.Sampler(magFilter=9729, minFilter=9987)]
        g.textures = [gl.Texture(sampler=0, source=source)]
    _walker_mesh(w, source)
    bind = _bind_positions()
    g.nodes = [gl.Node(name="walker", mesh=0, skin=0)]
    for name, _, t in SKELETON:
        g.nodes.append(gl.Node(name=name, translation=list(map(float, t))))
    for i, (_, parent, _) in enumerate(SKELETON):
        if parent is not None:
            g.nodes[NAMES.index(parent) + 1].children.append(i + 1)
    ibm = np.tile(np.eye(4), (len(NAMES), 1, 1))
    ibm[:, :3, 3] = -np.array([bind[n] for n in NAMES])
    g.skins = [gl.Skin(name="walker", joints=list(range(1, len(NAMES) + 1)), skeleton=1,
                       inverseBindMatrices=w.accessor(ibm.transpose(0, 2, 1).reshape(-1, 16)))]
    g.scenes = [gl.Scene(nodes=[0, 1])]
    g.scene = 0
    _walker_clips(w)
    if lost_texture:
        return w.save(path.with_suffix(".gltf"))
    return w.save(path)


def write_shipped(root: Path) -> list[Path]:
    """The shipped avatar models, under the repository root ``root``."""
    return [walker(root / "content/avatars/models/walker.glb"),
            walker(root / "tests/avatars/samples/walker_lost_texture.gltf", lost_texture=True)]


if __name__ == "__main__":
    for made in write_shipped(Path(sys.argv[1] if len(sys.argv) > 1 else ".")):
        print(f"wrote {made} ({made.stat().st_size} bytes)")
