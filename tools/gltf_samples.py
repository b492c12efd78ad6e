"""Skinned glTF files made from code (pygltflib): the avatars the content and the tests use.

``python -m tools.gltf_samples`` writes the shipped ones:

* ``content/avatars/models/walker.glb``: a low-poly figure (17 joints: hips, spine, chest,
  neck, head, arms, legs) with the clips Idle, Walk and Run (root motion: 1.4 and 3.5 m/s),
  CarryWalk (arms held forward), and Wave (cubic-spline rotations, a STEP hand), its shirt
  textured;
* ``content/avatars/models/hound.glb``: a four-legged dog modelled in centimetres (a scene
  gives it Scale 0.01), 32 joints (spine, neck, head, jaw, ears, tail, four joints a leg),
  smooth tubes on them in one primitive with a fur texture, the clips Survey (scale and
  STEP keys among them), Walk and Run, made in place;
* ``tests/avatars/samples/walker_lost_texture.gltf`` + ``.bin``: the walker, its texture file
  missing (as a model copied without its images);
* ``tests/avatars/samples/strip.gltf``: :func:`strip`, a two-joint strip small enough to
  skin by hand, laid out as other tools write files (an embedded buffer, interleaved
  joints and weights, turned joints under a node that is no joint, no normals).

:func:`two_bone` writes the small two-joint bar the tests compute by hand, optionally broken
in the ways real files are (no skin, five influences, weights that do not sum to 1,
keyframes out of order, a missing buffer). Everything is in glTF's frame: Y up, front +Z.
"""

from __future__ import annotations

import base64
import io
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

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

    def interleaved(self, columns: list[tuple[np.ndarray, int]], target: int | None = None
                    ) -> list[int]:
        """One accessor per ``(data, component)``, their elements interleaved in one buffer
        view (``byteStride`` the width of a row of all of them), as many exporters write."""
        arrays = [np.ascontiguousarray(data, {FLOAT: np.float32, USHORT: np.uint16}[component])
                  for data, component in columns]
        offsets = np.cumsum([0] + [a[0].nbytes for a in arrays])
        rows = np.concatenate([a.view(np.uint8).reshape(len(a), -1) for a in arrays], axis=1)
        while len(self.blob) % 4:
            self.blob.append(0)
        self.gltf.bufferViews.append(gl.BufferView(
            buffer=0, byteOffset=len(self.blob), byteLength=rows.nbytes,
            byteStride=int(offsets[-1]), target=target))
        self.blob.extend(rows.tobytes())
        made = []
        for arr, offset, (_, component) in zip(arrays, offsets, columns, strict=False):
            self.gltf.accessors.append(gl.Accessor(
                bufferView=len(self.gltf.bufferViews) - 1, byteOffset=int(offset),
                componentType=component, count=len(arr), type=_TYPES[arr.shape[1]]))
            made.append(len(self.gltf.accessors) - 1)
        return made

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

    def save(self, path: Path, external_bin: bool | None = None, write_bin: bool = True,
             embedded: bool = False) -> Path:
        """A .glb (one file), a .gltf with its buffer in a .bin beside it, or (``embedded``)
        a .gltf carrying its buffer as a base64 data URI."""
        path.parent.mkdir(parents=True, exist_ok=True)
        if embedded:
            data = base64.b64encode(bytes(self.blob)).decode()
            self.gltf.buffers = [gl.Buffer(byteLength=len(self.blob),
                                           uri=f"data:application/gltf-buffer;base64,{data}")]
            self.gltf.save_json(str(path))
            return path
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


def _quat_y(deg: np.ndarray) -> np.ndarray:
    h = np.radians(np.asarray(deg, np.float64)) / 2
    return np.stack([0 * h, np.sin(h), 0 * h, np.cos(h)], axis=-1)


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation ``b`` then ``a`` (glTF quaternions, x y z w, key by key)."""
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz],
                    axis=-1)


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
    attributes, indices = _bar_mesh(w, influences, weight_scale, skinned)
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
    g.animations = _bar_clips(w, interpolation, times_out_of_order)
    if missing_buffer:
        return w.save(path.with_suffix(".gltf"), write_bin=False)
    return w.save(path)


def _bar_mesh(w: _Writer, influences: int, weight_scale: float,
              skinned: bool) -> tuple[dict[str, int], int]:
    """:func:`two_bone`'s bar: rings of 4 at y = 0 .. 2, their attributes' accessors and
    the triangles' (made in this order: the file's accessors are numbered by it)."""
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
    return attributes, w.accessor(np.array(faces).reshape(-1), USHORT, target=34963)


def _bar_clips(w: _Writer, interpolation: str, times_out_of_order: bool) -> list[Any]:
    """:func:`two_bone`'s clips: Bend (the tip about Z, 0 to 90 degrees in 1 s) and Lift
    (the root up 1 m in 2 s)."""
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
    return [
        gl.Animation(name="Bend", samplers=[gl.AnimationSampler(
            input=w.accessor(bend_times, minmax=True), output=w.accessor(bend_values),
            interpolation=interpolation)],
            channels=[gl.AnimationChannel(sampler=0, target=gl.AnimationChannelTarget(
                node=2, path="rotation"))]),
        gl.Animation(name="Lift", samplers=[gl.AnimationSampler(
            input=lift[0], output=lift[1], interpolation="LINEAR")],
            channels=[gl.AnimationChannel(sampler=0, target=gl.AnimationChannelTarget(
                node=1, path="translation"))])]


def strip(path: Path) -> Path:
    """A flat strip (ten vertices, five rows at y = 0.5 ... 2.5, x = 0.75 and 1.25) on two
    joints under a node that is no joint: ``rig`` at (0, 0.5, 0), its child ``base`` at
    (1, 0, 0) turned 90° about Z (so it lies at (1, 0.5, 0) and its X axis points up), and
    ``base``'s child ``tip`` at (1, 0, 0) in ``base``'s frame, i.e. at (1, 1.5, 0): inverse
    bind matrices with a rotation in them. Row by row up the strip the weight on ``tip`` is
    0, 0.25, 0.5, 0.75, 1. Clip ``Sway`` turns ``tip`` about its Z (the world's Z) through
    0, 30, 75, 75, -40, 0 degrees at 0, 0.5, 1, 2, 2.5, 3 s (LINEAR). The joints and
    weights are interleaved in one strided buffer view, the buffer is a data URI in the
    .gltf, and there are no normals (the reader makes them)."""
    w = _Writer()
    g = w.gltf
    g.asset = gl.Asset(version="2.0", generator="colosseum tools/gltf_samples.py")
    ys = np.array([0.5, 1.0, 1.5, 2.0, 2.5])
    vertices = np.array([[x, y, 0.0] for y in ys for x in (0.75, 1.25)])
    faces = [f for i in range(0, 8, 2) for f in ((i, i + 1, i + 3), (i, i + 3, i + 2))]
    tip_weight = np.repeat(np.linspace(0.0, 1.0, 5), 2)
    weights = np.stack([1.0 - tip_weight, tip_weight, 0 * tip_weight, 0 * tip_weight], 1)
    joints, weights_at = w.interleaved([(np.tile([0, 1, 0, 0], (10, 1)), USHORT),
                                        (weights, FLOAT)], target=34962)
    attributes = gl.Attributes(POSITION=w.accessor(vertices, minmax=True, target=34962),
                               JOINTS_0=joints, WEIGHTS_0=weights_at)
    g.meshes = [gl.Mesh(name="strip", primitives=[gl.Primitive(
        attributes=attributes, indices=w.accessor(np.ravel(faces), USHORT, target=34963))])]
    turn = _quat_z(np.array(90.0)).tolist()
    g.nodes = [gl.Node(name="strip", mesh=0, skin=0),
               gl.Node(name="rig", translation=[0.0, 0.5, 0.0], children=[2]),
               gl.Node(name="base", translation=[1.0, 0.0, 0.0], rotation=turn, children=[3]),
               gl.Node(name="tip", translation=[1.0, 0.0, 0.0])]
    g.scenes = [gl.Scene(nodes=[0, 1])]
    g.scene = 0
    base = np.eye(4)
    base[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    base[:3, 3] = (1.0, 0.5, 0.0)
    along = np.eye(4)
    along[0, 3] = 1.0
    ibm = np.linalg.inv(np.stack([base, base @ along]))
    g.skins = [gl.Skin(name="strip", joints=[2, 3], skeleton=1, inverseBindMatrices=w.accessor(
        ibm.transpose(0, 2, 1).reshape(2, 16)))]
    times = np.array([0.0, 0.5, 1.0, 2.0, 2.5, 3.0])
    g.animations = [gl.Animation(name="Sway", samplers=[gl.AnimationSampler(
        input=w.accessor(times, minmax=True),
        output=w.accessor(_quat_z(np.array([0.0, 30.0, 75.0, 75.0, -40.0, 0.0]))),
        interpolation="LINEAR")], channels=[gl.AnimationChannel(
            sampler=0, target=gl.AnimationChannelTarget(node=3, path="rotation"))])]
    return w.save(path.with_suffix(".gltf"), embedded=True)


# -- figures made of tubes on a skeleton ---------------------------------------------------
#: A skeleton: (name, parent, translation from the parent) per joint, parents first; joints
#: carry no rest rotation, so each inverse bind matrix is a translation.
Skeleton = tuple[tuple[str, str | None, tuple[float, float, float]], ...]
#: A tube drawn: bone, where it ends (from the bone's joint, in bind axes), radius.
Tube = tuple[str, tuple[float, float, float], float]
#: An animation channel: joint, path, key times, values, interpolation.
ChannelKeys = tuple[str, str, np.ndarray, np.ndarray, str]


def _bind_positions(skeleton: Skeleton) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name, parent, t in skeleton:
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


def _primitive(w: _Writer, pieces: list[tuple[np.ndarray, ...]], material: int) -> gl.Primitive:
    """One primitive of ``pieces`` (vertices, normals, uvs, faces, joints, weights each)."""
    offsets = np.cumsum([0] + [len(a[0]) for a in pieces[:-1]])
    v, n, uv, f, j, wt = (np.concatenate([a[i] + (o if i == 3 else 0)
                                          for a, o in zip(pieces, offsets, strict=True)])
                          for i in range(6))
    attrs = gl.Attributes(POSITION=w.accessor(v, minmax=True, target=34962),
                          NORMAL=w.accessor(n, target=34962),
                          TEXCOORD_0=w.accessor(uv, target=34962),
                          JOINTS_0=w.accessor(j, USHORT, target=34962),
                          WEIGHTS_0=w.accessor(wt, target=34962))
    return gl.Primitive(attributes=attrs, indices=w.accessor(f.reshape(-1), USHORT,
                                                             target=34963), material=material)


def _tubes(w: _Writer, skeleton: Skeleton, tubes: tuple[Tube, ...], material: int
           ) -> gl.Primitive:
    """One primitive of ``tubes``, each from its bone's joint (see :func:`_limb`)."""
    bind = _bind_positions(skeleton)
    names = [name for name, _, _ in skeleton]
    parents = {name: parent for name, parent, _ in skeleton}
    pieces = []
    for bone, end, radius in tubes:
        parent = parents[bone]
        start = bind[bone]
        pieces.append(_limb(start, start + np.asarray(end), radius, names.index(bone),
                            names.index(parent) if parent else -1))
    return _primitive(w, pieces, material)


def _rig(w: _Writer, name: str, skeleton: Skeleton) -> None:
    """Node 0 draws mesh 0 with skin 0, whose joints are nodes 1... in ``skeleton``'s
    order; the scene holds both."""
    g = w.gltf
    names = [joint for joint, _, _ in skeleton]
    bind = _bind_positions(skeleton)
    g.nodes = [gl.Node(name=name, mesh=0, skin=0)]
    for joint, _, t in skeleton:
        g.nodes.append(gl.Node(name=joint, translation=list(map(float, t))))
    for i, (_, parent, _) in enumerate(skeleton):
        if parent is not None:
            g.nodes[names.index(parent) + 1].children.append(i + 1)
    ibm = np.tile(np.eye(4), (len(names), 1, 1))
    ibm[:, :3, 3] = -np.array([bind[n] for n in names])
    g.skins = [gl.Skin(name=name, joints=list(range(1, len(names) + 1)), skeleton=1,
                       inverseBindMatrices=w.accessor(ibm.transpose(0, 2, 1).reshape(-1, 16)))]
    g.scenes = [gl.Scene(nodes=[0, 1])]
    g.scene = 0


def _animations(w: _Writer, skeleton: Skeleton, clips: dict[str, list[ChannelKeys]]) -> None:
    """``clips`` as glTF animations of :func:`_rig`'s joint nodes."""
    idx = {name: i + 1 for i, (name, _, _) in enumerate(skeleton)}  # node 0 is the mesh node
    for name, channels in clips.items():
        anim = gl.Animation(name=name)
        for node, path_, t, values, kind in channels:
            anim.samplers.append(gl.AnimationSampler(input=w.accessor(t, minmax=True),
                                                     output=w.accessor(values),
                                                     interpolation=kind))
            anim.channels.append(gl.AnimationChannel(sampler=len(anim.samplers) - 1,
                                                     target=gl.AnimationChannelTarget(
                                                         node=idx[node], path=path_)))
        w.gltf.animations.append(anim)


# -- the walker ----------------------------------------------------------------------------
#: In glTF axes, metres: +X is the figure's left.
SKELETON: Skeleton = (
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
#: Limbs drawn: bone, child point (where the segment ends, in the bone's frame), radius.
_LIMBS: tuple[Tube, ...] = (
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


def _walker_mesh(w: _Writer, texture_source: int | None) -> None:
    g = w.gltf
    g.materials = [
        gl.Material(name="skin", pbrMetallicRoughness=gl.PbrMetallicRoughness(
            baseColorFactor=[0.85, 0.68, 0.55, 1.0], metallicFactor=0.0)),
        gl.Material(name="shirt", pbrMetallicRoughness=gl.PbrMetallicRoughness(
            baseColorFactor=[1.0, 1.0, 1.0, 1.0], metallicFactor=0.0,
            baseColorTexture=None if texture_source is None else gl.TextureInfo(index=0)))]
    g.meshes = [gl.Mesh(name="walker", primitives=[
        _tubes(w, SKELETON, tuple(t for t in _LIMBS if (t[0] in _SHIRT) == shirt), int(shirt))
        for shirt in (False, True)])]


def _walker_clips() -> dict[str, list[ChannelKeys]]:
    """Idle, Walk, Run, CarryWalk (LINEAR), Wave (CUBICSPLINE arm, STEP hand)."""
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
    return clips


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
    _rig(w, "walker", SKELETON)
    _animations(w, SKELETON, _walker_clips())
    if lost_texture:
        return w.save(path.with_suffix(".gltf"))
    return w.save(path)


# -- the hound -----------------------------------------------------------------------------
#: In glTF axes, centimetres (a scene gives it Scale 0.01): +X is the dog's left, +Z its
#: front. 32 joints: root, pelvis, three spine joints, chest, two neck joints, head, jaw,
#: ears, four tail joints, and four joints down each leg.
HOUND: Skeleton = (
    ("root", None, (0.0, 0.0, 0.0)),
    ("pelvis", "root", (0.0, 52.0, -24.0)),
    ("spine1", "pelvis", (0.0, 1.0, 12.0)),
    ("spine2", "spine1", (0.0, 1.0, 12.0)),
    ("spine3", "spine2", (0.0, 0.0, 12.0)),
    ("chest", "spine3", (0.0, 0.0, 10.0)),
    ("neck1", "chest", (0.0, 7.0, 8.0)),
    ("neck2", "neck1", (0.0, 8.0, 5.0)),
    ("head", "neck2", (0.0, 5.0, 4.0)),
    ("jaw", "head", (0.0, -5.0, 5.0)),
    ("ear.L", "head", (4.0, 6.0, -2.0)),
    ("ear.R", "head", (-4.0, 6.0, -2.0)),
    ("tail1", "pelvis", (0.0, 2.0, -6.0)),
    ("tail2", "tail1", (0.0, 2.0, -8.0)),
    ("tail3", "tail2", (0.0, 0.0, -9.0)),
    ("tail4", "tail3", (0.0, -2.0, -9.0)),
    ("upper_arm.L", "chest", (8.0, -8.0, 2.0)),
    ("forearm.L", "upper_arm.L", (0.0, -16.0, -2.0)),
    ("front_foot.L", "forearm.L", (0.0, -21.0, 1.0)),
    ("front_toe.L", "front_foot.L", (0.0, -6.0, 3.0)),
    ("upper_arm.R", "chest", (-8.0, -8.0, 2.0)),
    ("forearm.R", "upper_arm.R", (0.0, -16.0, -2.0)),
    ("front_foot.R", "forearm.R", (0.0, -21.0, 1.0)),
    ("front_toe.R", "front_foot.R", (0.0, -6.0, 3.0)),
    ("thigh.L", "pelvis", (9.0, -4.0, 2.0)),
    ("shin.L", "thigh.L", (0.0, -18.0, 6.0)),
    ("hind_foot.L", "shin.L", (0.0, -15.0, -7.0)),
    ("hind_toe.L", "hind_foot.L", (0.0, -12.0, 3.0)),
    ("thigh.R", "pelvis", (-9.0, -4.0, 2.0)),
    ("shin.R", "thigh.R", (0.0, -18.0, 6.0)),
    ("hind_foot.R", "shin.R", (0.0, -15.0, -7.0)),
    ("hind_toe.R", "hind_foot.R", (0.0, -12.0, 3.0)),
)


#: A point of a chain: a joint, an offset from it (bind axes) and the radius there.
ChainPoint = tuple[str, tuple[float, float, float], float]
_AT = (0.0, 0.0, 0.0)
#: The bands of the fur texture, top to bottom: a tan coat with a dark saddle and a cream
#: belly round each tube, legs that darken into paws along them, a tail that ends cream,
#: dark ears.
_FUR_BANDS = ("coat", "leg", "tail", "dark")
#: The hound's skin: chains of tubes, each with its band and the axis its texture's u = 0
#: (the saddle) faces: "up" (+Y) or "front" (+Z, for what hangs down).
_HOUND_CHAINS: tuple[tuple[str, str, tuple[ChainPoint, ...]], ...] = (
    ("coat", "up", (("pelvis", (0.0, 0.0, -7.0), 6.0), ("pelvis", _AT, 10.0),
                    ("spine1", _AT, 11.0), ("spine2", _AT, 11.5), ("spine3", _AT, 11.5),
                    ("chest", _AT, 11.0), ("chest", (0.0, 3.0, 10.0), 7.0))),
    ("coat", "up", (("neck1", (0.0, -3.0, -3.0), 7.5), ("neck1", _AT, 7.0),
                    ("neck2", _AT, 6.5), ("head", _AT, 7.0), ("head", (0.0, -1.5, 7.0), 5.0),
                    ("head", (0.0, -3.0, 13.0), 2.5))),
    ("coat", "up", (("jaw", (0.0, 0.0, -2.0), 3.0), ("jaw", (0.0, 1.0, 8.0), 1.5))),
    ("tail", "up", (("tail1", _AT, 3.5), ("tail2", _AT, 3.2), ("tail3", _AT, 2.8),
                    ("tail4", _AT, 2.3), ("tail4", (0.0, -3.0, -8.0), 1.0))),
    *(("dark", "front", ((f"ear.{side}", _AT, 2.8), (f"ear.{side}", (x, 8.0, -1.0), 0.8)))
      for side, x in (("L", 1.0), ("R", -1.0))),
    *(("leg", "front", ((f"{upper}.{side}", (0.0, 6.0, 0.0), 0.8 * top),  # inside the body
                        (f"{upper}.{side}", _AT, top), (f"{lower}.{side}", _AT, 0.65 * top),
                        (f"{foot}.{side}", _AT, 3.0), (f"{toe}.{side}", _AT, 3.0),
                        (f"{toe}.{side}", (0.0, -1.0, 6.0), 2.5)))
      for side in "LR" for upper, lower, foot, toe, top in (
          ("upper_arm", "forearm", "front_foot", "front_toe", 5.5),
          ("thigh", "shin", "hind_foot", "hind_toe", 7.0))),
)
#: The fur texture's side in pixels.
FUR_SIZE = 128


def _chain(skeleton: Skeleton, points: tuple[ChainPoint, ...], band: tuple[float, float],
           facing: str, sides: int = 12, spacing: float = 3.0) -> tuple[np.ndarray, ...]:
    """One smooth tube through ``points``, closed at both ends: the stretch from a point to
    the next follows the first one's joint, blending half and half with the joint on the
    other side where two meet. Rings are about ``spacing`` apart; texture u runs round it
    from ``facing`` (a seam column repeats u = 0 at u = 1), v along it over ``band``."""
    bind = _bind_positions(skeleton)
    names = [name for name, _, _ in skeleton]
    at = np.array([bind[joint] + np.asarray(offset) for joint, offset, _ in points])
    drive = [names.index(joint) for joint, _, _ in points]
    ref = np.array([0.0, 1.0, 0.0]) if facing == "up" else np.array([0.0, 0.0, 1.0])
    rings = _rings(points, at, drive, spacing)
    columns = sides + 1
    verts, normals, uvs, joints, weights = [], [], [], [], []
    for centre, radius, d, own, other, w, s in rings:
        u = ref - (ref @ d) * d
        u /= np.linalg.norm(u)
        v = np.cross(d, u)
        for k in range(columns):
            a = 2 * math.pi * k / sides
            n = math.cos(a) * u + math.sin(a) * v
            verts.append(centre + n * radius)
            normals.append(n)
            uvs.append((k / sides, band[0] + s * (band[1] - band[0])))
            joints.append((own, other, 0, 0))
            weights.append((1.0 - w, w, 0.0, 0.0))
    faces = []
    for r in range(len(rings) - 1):
        for k in range(sides):
            a = r * columns + k
            faces += [(a, a + 1, a + columns), (a + 1, a + 1 + columns, a + columns)]
    base = len(verts)
    for cap, ring in enumerate((rings[0], rings[-1])):
        centre, _, d, own, *_ = ring
        verts.append(centre)
        normals.append(-d if cap == 0 else d)
        uvs.append((0.5, band[cap]))
        joints.append((own, own, 0, 0))
        weights.append((1.0, 0.0, 0.0, 0.0))
        ring0 = 0 if cap == 0 else (len(rings) - 1) * columns
        for k in range(sides):
            a, b = ring0 + k, ring0 + k + 1
            faces.append((base + cap, b, a) if cap == 0 else (base + cap, a, b))
    return (np.array(verts), np.array(normals), np.array(uvs), np.array(faces),
            np.array(joints), np.array(weights))


def _rings(points: tuple[ChainPoint, ...], at: np.ndarray, drive: list[int],
           spacing: float) -> list[tuple[Any, ...]]:
    """The tube's rings about ``spacing`` apart: centre, radius, direction, the joint it
    follows and the one it blends with (and that one's weight), fraction of the length."""
    lengths = np.linalg.norm(np.diff(at, axis=0), axis=1)
    along = np.diff(at, axis=0) / lengths[:, None]
    travelled = np.concatenate([[0.0], np.cumsum(lengths)]) / lengths.sum()
    rings = []
    for k, length in enumerate(lengths):
        steps = max(2, round(length / spacing))
        last = k == len(lengths) - 1
        for r in range(steps + (1 if last else 0)):
            f = r / steps
            d = along[k] + (along[k - 1] if f == 0 and k > 0 else 0)
            own, other, w = drive[k], drive[k], 0.0
            if f < 0.3 and k > 0 and drive[k - 1] != own:
                other, w = drive[k - 1], 0.5 * (1 - f / 0.3)
            elif f > 0.7 and drive[k + 1] != own:
                other, w = drive[k + 1], 0.5 * (f - 0.7) / 0.3
            rings.append((at[k] + f * (at[k + 1] - at[k]),
                          points[k][2] + f * (points[k + 1][2] - points[k][2]),
                          d / np.linalg.norm(d), own, other, w,
                          travelled[k] + f * (travelled[k + 1] - travelled[k])))
    return rings


def _fur() -> np.ndarray:
    """The hound's texture, :data:`_FUR_BANDS` from the top, with a little noise as fur."""
    band = FUR_SIZE // len(_FUR_BANDS)
    tan, dark, cream = np.array([200, 130, 60]), np.array([80, 50, 30]), np.array([240, 225, 195])
    up = np.cos(2 * np.pi * (np.arange(FUR_SIZE) + 0.5) / FUR_SIZE)[:, None]
    belly = np.clip((-up - 0.1) / 0.5, 0.0, 1.0)
    saddle = np.clip((up - 0.5) / 0.3, 0.0, 1.0)
    coat = (tan * (1 - belly) + cream * belly) * (1 - saddle) + dark * saddle
    s = ((np.arange(band) + 0.5) / band)[:, None, None]  # along the tube
    paw = np.clip((s - 0.72) / 0.1, 0.0, 1.0)
    tip = np.clip((s - 0.7) / 0.15, 0.0, 1.0)
    rgb = np.concatenate([np.broadcast_to(coat, (band, FUR_SIZE, 3)),
                          np.broadcast_to(tan * (1 - paw) + dark * paw, (band, FUR_SIZE, 3)),
                          np.broadcast_to(tan * (1 - tip) + cream * tip, (band, FUR_SIZE, 3)),
                          np.broadcast_to(dark * 1.0, (band, FUR_SIZE, 3))])
    rgb = rgb + np.random.default_rng(0).normal(0.0, 6.0, rgb.shape)
    rgba = np.full((FUR_SIZE, FUR_SIZE, 4), 255, np.uint8)
    rgba[:, :, :3] = np.clip(rgb, 0, 255).astype(np.uint8)
    return rgba


def _gait(period: float, phases: dict[str, float], swing: float, flex: float,
          bob: float, bobs: int, back: float, sway: float, tail: tuple[float, float],
          ears: float, keys: int = 17) -> list[ChannelKeys]:
    """A gait cycle of the hound in place: each leg swinging at its phase of the cycle,
    the back flexing and swaying, the tail wagging, the ears held."""
    pelvis = np.array(HOUND[1][2])
    t = np.linspace(0.0, period, keys)
    cycle = 2 * math.pi * t / period
    hips = pelvis + np.outer(-bob * (1 + np.cos(bobs * cycle)) / 2, (0.0, 1.0, 0.0))
    out: list[ChannelKeys] = [("pelvis", "translation", t, hips, "LINEAR")]
    for leg, phase in phases.items():
        front, side = leg.split(".")
        ph = cycle - 2 * math.pi * phase
        lift = np.maximum(0.0, np.cos(ph))  # while the leg swings forward
        upper, lower, foot, toe = (("upper_arm", "forearm", "front_foot", "front_toe")
                                   if front == "fore" else
                                   ("thigh", "shin", "hind_foot", "hind_toe"))
        bends = ((upper, -swing * np.sin(ph)), (lower, flex * lift),
                 (foot, (0.5 if front == "fore" else -0.9) * flex * lift),
                 (toe, 0.4 * flex * lift))
        out += [(f"{joint}.{side}", "rotation", t, _quat_x(deg), "LINEAR")
                for joint, deg in bends]
    for spine in ("spine1", "spine2", "spine3"):
        out.append((spine, "rotation", t, _quat_mul(_quat_y(sway * np.sin(cycle)),
                                                    _quat_x(back * np.sin(cycle))), "LINEAR"))
    out.append(("neck1", "rotation", t, _quat_x(-back * np.sin(cycle) + 2 * np.sin(2 * cycle)),
                "LINEAR"))
    lift_deg, wag = tail
    for k, joint in enumerate(("tail1", "tail2", "tail3", "tail4")):
        out.append((joint, "rotation", t, _quat_mul(_quat_y(wag * np.sin(cycle - 0.6 * k)),
                                                    _quat_x(lift_deg / (k + 1) + 0 * t)),
                    "LINEAR"))
    if ears:
        out += [(f"ear.{side}", "rotation", t, _quat_x(ears + 0 * t), "LINEAR")
                for side in "LR"]
    return out


def _hound_clips() -> dict[str, list[ChannelKeys]]:
    """Survey (4 s: the head turns left and right, the tail wags, the chest breathes by
    scale, the ears twitch in STEP keys), Walk (0.8 s, the legs one after another: left
    hind, left fore, right hind, right fore) and Run (0.45 s, a gallop: the hind legs
    together then the fore, the back flexing), all in place (a scene gives their
    GroundSpeed)."""
    t = np.linspace(0.0, 4.0, 41)
    look = np.sin(2 * math.pi * t / 4.0)
    wag = 2 * math.pi * t / 0.8
    breath = 0.03 * (1 - np.cos(2 * math.pi * t / 2.0)) / 2
    survey: list[ChannelKeys] = [
        ("neck1", "rotation", t, _quat_y(35.0 * look), "LINEAR"),
        ("neck2", "rotation", t, _quat_x(-8.0 * look ** 2), "LINEAR"),
        ("chest", "scale", t, np.stack([1 + breath, 1 + breath, 1 + 0 * t], 1), "LINEAR"),
        *((f"tail{k + 1}", "rotation", t, _quat_mul(_quat_y(20.0 * np.sin(wag - 0.7 * k)),
                                                    _quat_x(15.0 / (k + 1) + 0 * t)), "LINEAR")
          for k in range(4))]
    twitch = np.array([0.0, 1.0, 1.3, 2.6, 2.8, 4.0])
    survey += [("ear.L", "rotation", twitch, _quat_x(np.array([0.0, -25, 0, -25, 0, 0])), "STEP"),
               ("ear.R", "rotation", twitch, _quat_z(np.array([0.0, 0, 20, 20, 0, 0])), "STEP")]
    return {
        "Survey": survey,
        "Walk": _gait(0.8, {"hind.L": 0.0, "fore.L": 0.25, "hind.R": 0.5, "fore.R": 0.75},
                     swing=22.0, flex=40.0, bob=1.0, bobs=2, back=0.0, sway=3.0,
                     tail=(20.0, 8.0), ears=0.0),
        "Run": _gait(0.45, {"hind.L": 0.0, "hind.R": 0.1, "fore.L": 0.5, "fore.R": 0.6},
                    swing=40.0, flex=70.0, bob=4.0, bobs=1, back=8.0, sway=0.0,
                    tail=(5.0, 4.0), ears=-30.0)}


def hound(path: Path) -> Path:
    """The hound (see :data:`HOUND`): one textured primitive of smooth tubes on 32 joints, about
    0.75 m tall and 1.1 m from nose to tail tip at Scale 0.01, its clips Survey, Walk and
    Run."""
    w = _Writer()
    g = w.gltf
    g.asset = gl.Asset(version="2.0", generator="colosseum tools/gltf_samples.py")
    source = w.image(_fur())
    g.samplers = [gl.Sampler(magFilter=9729, minFilter=9987, wrapT=33071)]  # v clamped
    g.textures = [gl.Texture(sampler=0, source=source)]
    g.materials = [gl.Material(name="fur", pbrMetallicRoughness=gl.PbrMetallicRoughness(
        baseColorFactor=[1.0, 1.0, 1.0, 1.0], metallicFactor=0.0, roughnessFactor=0.9,
        baseColorTexture=gl.TextureInfo(index=0)))]
    margin = 1.0 / FUR_SIZE  # a texel inside each band: mipmaps do not bleed the next one
    count = len(_FUR_BANDS)
    g.meshes = [gl.Mesh(name="hound", primitives=[_primitive(w, [
        _chain(HOUND, points, ((i := _FUR_BANDS.index(band)) / count + margin,
                               (i + 1) / count - margin), facing)
        for band, facing, points in _HOUND_CHAINS], 0)])]
    _rig(w, "hound", HOUND)
    _animations(w, HOUND, _hound_clips())
    return w.save(path)


def write_shipped(root: Path) -> list[Path]:
    """The shipped avatar models, under the repository root ``root``."""
    return [walker(root / "content/avatars/models/walker.glb"),
            walker(root / "tests/avatars/samples/walker_lost_texture.gltf", lost_texture=True),
            strip(root / "tests/avatars/samples/strip.gltf"),
            hound(root / "content/avatars/models/hound.glb")]


if __name__ == "__main__":
    for made in write_shipped(Path(sys.argv[1] if len(sys.argv) > 1 else ".")):
        print(f"wrote {made} ({made.stat().st_size} bytes)")
