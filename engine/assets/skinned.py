"""Skinned models: a glTF 2.0 file's node hierarchy, skins and animation clips as plain
arrays (:class:`SkinnedModel`), for avatars.

Read with pygltflib, the maintained reference data model of glTF 2.0: it parses the JSON
and the GLB container exactly as the specification writes them and keeps every field
(``JOINTS_1``, extras), where trimesh flattens a file into static triangles and drops skins
and animations. Accessors (strides, sparse, normalised integers), buffers (GLB chunk,
data URIs, files beside the model) and images are decoded here with numpy and Pillow.

Everything stays in glTF's frame (Y up, front +Z, metres); the avatar places it in the
engine's frame (:data:`AVATAR_AXES`). Problems that leave the model usable — more than 4
influences, weights that do not sum to 1, a missing texture, a clip with keyframe times out
of order — are repaired or left out and listed in :attr:`SkinnedModel.warnings`; a model
that cannot be read at all raises, and the asset layer tells it at the scene line.
"""

from __future__ import annotations

import base64
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from engine.assets.registry import built_in_loader
from engine.assets.types import WHITE, vertex_normals
from engine.confine import Confinement

#: glTF (Y up, front +Z) to the engine's avatar frame (Z up, front +Y): a proper rotation.
AVATAR_AXES = np.array([[-1.0, 0, 0, 0], [0, 0, 1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])

#: Joint influences a vertex keeps (linear-blend skinning on the GPU reads four).
MAX_INFLUENCES = 4

PATHS = ("translation", "rotation", "scale")
INTERPOLATIONS = ("LINEAR", "STEP", "CUBICSPLINE")

_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
           5125: np.uint32, 5126: np.float32}
_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_NORMALISE = {np.int8: 127.0, np.uint8: 255.0, np.int16: 32767.0, np.uint16: 65535.0}
#: How far a vertex's weights may sum from 1 before it is told (quantised weights round).
WEIGHT_TOLERANCE = 2e-3
#: Required extensions whose data this reader cannot decode: without them the meshes would
#: be read as zeros (their accessors have no buffer view), so the file is refused.
UNREADABLE_EXTENSIONS = {"KHR_draco_mesh_compression": "Draco-compressed meshes",
                         "EXT_meshopt_compression": "meshopt-compressed buffers"}
#: Required extensions read as glTF 2.0 data (integer accessors, normalised or not).
READ_EXTENSIONS = frozenset({"KHR_mesh_quantization"})


@dataclass(frozen=True, slots=True)
class SkinnedPart:
    """One primitive in its bind pose (glTF frame). ``joints`` ``(N, 4)`` index
    :attr:`SkinnedModel.palette_nodes`; ``weights`` ``(N, 4)`` sum to 1; ``uv`` as
    :class:`~engine.assets.types.MeshPart`'s (v up from the image's bottom row)."""

    vertices: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    uv: np.ndarray | None = None
    colors: np.ndarray | None = None
    color: tuple[float, float, float, float] = WHITE
    texture: np.ndarray | None = None
    name: str = ""


@dataclass(frozen=True, slots=True)
class Channel:
    """One animated property of one node. ``values`` is ``(K, d)``; for CUBICSPLINE
    ``(K, 3, d)``: in-tangent, value, out-tangent. Rotations are ``(w, x, y, z)``."""

    node: int
    path: str
    interpolation: str
    times: np.ndarray
    values: np.ndarray


@dataclass(frozen=True, slots=True)
class AnimationClip:
    """A named animation: its channels, played from 0 to ``duration`` seconds."""

    name: str
    duration: float
    channels: tuple[Channel, ...]


@dataclass(frozen=True, slots=True)
class SkinnedModel:
    """A glTF scene's nodes (parents before children), skins and clips.

    ``palette_nodes[j]`` is the node whose global transform, times ``inverse_bind[j]``,
    moves the vertices that name palette entry ``j``: every skin's joints, plus one entry
    per mesh without a skin (moved rigidly by its own node).
    """

    path: Path
    node_names: tuple[str, ...]
    parents: np.ndarray
    rest_translation: np.ndarray
    rest_rotation: np.ndarray
    rest_scale: np.ndarray
    palette_nodes: np.ndarray
    inverse_bind: np.ndarray
    parts: tuple[SkinnedPart, ...]
    clips: tuple[AnimationClip, ...]
    skin_count: int
    warnings: tuple[str, ...] = ()

    def clip(self, name: str) -> AnimationClip | None:
        return next((c for c in self.clips if c.name == name), None)

    @property
    def clip_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.clips)

    def node(self, name: str) -> int | None:
        """Index of the node called ``name`` (None if there is none)."""
        return self.node_names.index(name) if name in self.node_names else None


@built_in_loader("skin", ".glb", ".gltf", ".vrm")
def load_skinned(path: Path) -> SkinnedModel:
    """Read a ``.glb``/``.gltf`` as a :class:`SkinnedModel` (raises ValueError with a
    reason on a file that cannot be used)."""
    import pygltflib

    try:
        gltf = pygltflib.GLTF2().load(str(path))
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ValueError(f"not a glTF 2.0 file pygltflib can read ({exc})") from None
    if gltf is None:
        raise ValueError("not a glTF 2.0 file")
    return _Reader(gltf, path).model()


class _Reader:
    """One file's decoding: buffers read once, accessors on demand, warnings collected."""

    def __init__(self, gltf: Any, path: Path) -> None:
        self.gltf = gltf
        self.path = path
        self.warnings: list[str] = []
        self._buffers: dict[int, bytes] = {}

    # -- raw data ----------------------------------------------------------------
    def _beside(self, uri: str, what: str) -> Path:
        """The file a URI of the model names: in the model's folder or below it (as
        trimesh reads the files a model names), never outside: content stays in its
        folder (:mod:`engine.confine`)."""
        file = self.path.parent / _unquote(uri)
        if not Confinement.of(self.path.parent).allows(file):
            raise ValueError(f"{what} names a file outside the model's folder; files a "
                             "model names must lie beside it or below it")
        return file

    def buffer(self, index: int) -> bytes:
        found = self._buffers.get(index)
        if found is not None:
            return found
        buffers = self.gltf.buffers or []
        if not 0 <= index < len(buffers):
            raise ValueError(f"a buffer view names buffer {index}, but the file has "
                             f"{len(buffers)}")
        uri = buffers[index].uri
        if uri is None:
            data = self.gltf.binary_blob()
            if data is None:
                raise ValueError(f"buffer {index} has no uri and the file has no binary chunk")
        elif uri.startswith("data:"):
            try:
                data = base64.b64decode(uri.split(",", 1)[1], validate=False)
            except (ValueError, IndexError) as exc:
                raise ValueError(f"buffer {index}'s data URI is not base64 ({exc})") from None
        else:
            file = self._beside(uri, f"buffer {index}")
            if not file.is_file():
                raise ValueError(f"buffer {index} is the file {uri!r}, which is not there "
                                 f"(looked for {file})")
            data = file.read_bytes()
        need = buffers[index].byteLength or 0
        if len(data) < need:
            raise ValueError(f"buffer {index} holds {len(data)} bytes but declares {need}")
        self._buffers[index] = data
        return data

    def view(self, index: int) -> tuple[bytes, int, int | None, int]:
        """(buffer bytes, offset, stride, length) of buffer view ``index``."""
        views = self.gltf.bufferViews or []
        if not 0 <= index < len(views):
            raise ValueError(f"buffer view {index} does not exist (the file has {len(views)})")
        bv = views[index]
        data = self.buffer(bv.buffer)
        offset, length = bv.byteOffset or 0, bv.byteLength or 0
        if offset + length > len(data):
            raise ValueError(f"buffer view {index} reaches byte {offset + length} of buffer "
                             f"{bv.buffer}, which has {len(data)}")
        return data, offset, bv.byteStride, length

    def accessor(self, index: int | None, what: str) -> np.ndarray:
        """Accessor ``index`` as ``(count, width)`` (float64 when normalised or float)."""
        accessors = self.gltf.accessors or []
        if index is None or not 0 <= index < len(accessors):
            raise ValueError(f"{what}: accessor {index} does not exist")
        acc = accessors[index]
        dtype = _DTYPES.get(acc.componentType)
        width = _WIDTHS.get(acc.type)
        if dtype is None or width is None:
            raise ValueError(f"{what}: accessor {index} has an unknown component type "
                             f"{acc.componentType} or type {acc.type!r}")
        count = int(acc.count or 0)
        item = np.dtype(dtype).itemsize
        if acc.bufferView is None:
            out = np.zeros((count, width), dtype)
        else:
            data, offset, stride, length = self.view(acc.bufferView)
            stride = stride or item * width
            start = offset + (acc.byteOffset or 0)
            end = start + (count - 1) * stride + item * width if count else start
            if end > offset + length:
                raise ValueError(f"{what}: accessor {index} reads past the end of its buffer "
                                 f"view ({end - offset} bytes of {length})")
            out = np.ndarray((count, width), dtype, buffer=data, offset=start,
                             strides=(stride, item)).copy()
        if acc.sparse is not None and acc.sparse.count:
            out = out.copy()
            sp = acc.sparse
            idx_dtype = _DTYPES.get(sp.indices.componentType)
            data, offset, _, _ = self.view(sp.indices.bufferView)
            rows = np.frombuffer(data, idx_dtype, sp.count, offset + (sp.indices.byteOffset or 0))
            data, offset, _, _ = self.view(sp.values.bufferView)
            values = np.frombuffer(data, dtype, sp.count * width,
                                   offset + (sp.values.byteOffset or 0)).reshape(-1, width)
            if rows.size and int(rows.max()) >= count:
                raise ValueError(f"{what}: sparse accessor {index} names element "
                                 f"{int(rows.max())} of {count}")
            out[rows.astype(np.int64)] = values
        if dtype != np.float32 and acc.normalized:
            return np.maximum(out / _NORMALISE[dtype], -1.0)
        return out.astype(np.float64) if dtype == np.float32 else out

    def image(self, index: int) -> np.ndarray | None:
        """RGBA pixels of image ``index``; a missing or unreadable one is told and None."""
        from PIL import Image, UnidentifiedImageError

        from engine.assets.loaders import rgba_pixels

        images = self.gltf.images or []
        if not 0 <= index < len(images):
            self.warnings.append(f"a texture names image {index}, which does not exist; "
                                 "its parts are drawn in their base colour")
            return None
        img = images[index]
        label = repr(img.uri) if img.uri and not img.uri.startswith("data:") else f"image {index}"
        try:
            if img.bufferView is not None:
                data, offset, _, length = self.view(img.bufferView)
                raw = data[offset:offset + length]
            elif img.uri and img.uri.startswith("data:"):
                raw = base64.b64decode(img.uri.split(",", 1)[1])
            elif img.uri:
                file = self._beside(img.uri, f"image {index}")
                if not file.is_file():
                    raise ValueError(f"the file is not there (looked for {file})")
                raw = file.read_bytes()
            else:
                raise ValueError("it has neither a uri nor a buffer view")
            with Image.open(io.BytesIO(raw)) as pil:
                return rgba_pixels(pil)
        except (ValueError, OSError, UnidentifiedImageError) as exc:
            self.warnings.append(f"texture {label} cannot be used ({exc}); its parts are drawn "
                                 "in their base colour")
            return None

    # -- structure -----------------------------------------------------------------
    def required_extensions(self) -> None:
        """Refuse a file whose meshes need a decoder this reader lacks; tell the other
        required extensions it does not read (the model is drawn without them)."""
        for name in self.gltf.extensionsRequired or []:
            what = UNREADABLE_EXTENSIONS.get(str(name))
            if what is not None:
                raise ValueError(f"the file requires {name} ({what}), which is not read here; "
                                 "export it without that compression")
            if name not in READ_EXTENSIONS:
                self.warnings.append(f"the file requires the extension {name}, which is not "
                                     "read here; the model is drawn without it")

    def model(self) -> SkinnedModel:
        gltf = self.gltf
        self.required_extensions()
        order, parents = self.scene_nodes()
        new = {old: i for i, old in enumerate(order)}
        t, r, s = (np.zeros((len(order), 3)), np.tile([1.0, 0, 0, 0], (len(order), 1)),
                   np.ones((len(order), 3)))
        names = []
        for i, old in enumerate(order):
            node = gltf.nodes[old]
            names.append(node.name or f"node{old}")
            t[i], r[i], s[i] = _node_trs(node)
        palette_nodes: list[int] = []
        inverse_bind: list[np.ndarray] = []
        parts: list[SkinnedPart] = []
        skins_used: dict[int, int] = {}  # skin index -> its first palette entry
        for old in order:
            node = gltf.nodes[old]
            if node.mesh is None:
                continue
            if node.skin is not None:
                base = skins_used.get(node.skin)
                if base is None:
                    base = skins_used[node.skin] = len(palette_nodes)
                    joints, ibm = self.skin(node.skin, new)
                    palette_nodes.extend(joints)
                    inverse_bind.extend(ibm)
            else:  # a rigid mesh: one palette entry, its own node
                base = len(palette_nodes)
                palette_nodes.append(new[old])
                inverse_bind.append(np.eye(4))
            parts.extend(self.mesh(node.mesh, base, rigid=node.skin is None))
        if not parts:
            raise ValueError("the file's scene holds no mesh")
        clips = self.animations(new)
        return SkinnedModel(self.path, tuple(names), np.array(parents, np.int64), t, r, s,
                            np.array(palette_nodes, np.int64),
                            np.array(inverse_bind, np.float64).reshape(-1, 4, 4),
                            tuple(parts), tuple(clips), len(skins_used), tuple(self.warnings))

    def scene_nodes(self) -> tuple[list[int], list[int]]:
        """The default scene's nodes, parents before children, and each one's parent
        (as an index into that order; -1 for a root)."""
        gltf = self.gltf
        nodes = gltf.nodes or []
        if gltf.scenes:
            scene = gltf.scenes[gltf.scene or 0] if 0 <= (gltf.scene or 0) < len(
                gltf.scenes) else gltf.scenes[0]
            roots = list(scene.nodes or [])
        else:
            children = {c for n in nodes for c in (n.children or [])}
            roots = [i for i in range(len(nodes)) if i not in children]
        order: list[int] = []
        parents: list[int] = []
        seen: set[int] = set()
        stack = [(root, -1) for root in reversed(roots)]
        while stack:
            old, parent = stack.pop()
            if not 0 <= old < len(nodes):
                raise ValueError(f"the scene names node {old}, which does not exist")
            if old in seen:
                raise ValueError(f"node {old} is reached twice: the node hierarchy is not a "
                                 "tree")
            seen.add(old)
            me = len(order)
            order.append(old)
            parents.append(parent)
            stack.extend((child, me) for child in reversed(nodes[old].children or []))
        return order, parents

    def skin(self, index: int, new: dict[int, int]) -> tuple[list[int], np.ndarray]:
        skins = self.gltf.skins or []
        if not 0 <= index < len(skins):
            raise ValueError(f"a node names skin {index}, which does not exist")
        skin = skins[index]
        missing = [j for j in skin.joints if j not in new]
        if missing:
            raise ValueError(f"skin {index} names joint node {missing[0]}, which is not in "
                             "the scene")
        joints = [new[j] for j in skin.joints]
        if skin.inverseBindMatrices is None:
            ibm = np.tile(np.eye(4), (len(joints), 1, 1))
        else:
            raw = self.accessor(skin.inverseBindMatrices, f"skin {index} inverse bind matrices")
            if len(raw) != len(joints):
                raise ValueError(f"skin {index} has {len(joints)} joints but {len(raw)} "
                                 "inverse bind matrices")
            ibm = raw.reshape(-1, 4, 4).transpose(0, 2, 1)  # glTF matrices are column-major
        if not np.isfinite(ibm).all():
            raise ValueError(f"skin {index} has inverse bind matrices that are not finite")
        return joints, ibm

    def mesh(self, index: int, base: int, rigid: bool) -> list[SkinnedPart]:
        meshes = self.gltf.meshes or []
        if not 0 <= index < len(meshes):
            raise ValueError(f"a node names mesh {index}, which does not exist")
        mesh = meshes[index]
        out = []
        for k, prim in enumerate(mesh.primitives):
            name = f"{mesh.name or f'mesh{index}'}#{k}"
            part = self.primitive(prim, name, base, rigid)
            if part is not None:
                out.append(part)
        return out

    def primitive(self, prim: Any, name: str, base: int, rigid: bool) -> SkinnedPart | None:
        attrs = vars(prim.attributes)
        mode = 4 if prim.mode is None else prim.mode
        if mode not in (4, 5, 6):
            self.warnings.append(f"primitive {name!r} is drawn as points or lines (mode "
                                 f"{mode}); it is left out")
            return None
        if attrs.get("POSITION") is None:
            raise ValueError(f"primitive {name!r} has no POSITION")
        vertices = self.accessor(attrs["POSITION"], f"{name} POSITION").astype(np.float64)
        if not np.isfinite(vertices).all():
            raise ValueError(f"primitive {name!r} has positions that are not finite")
        n = len(vertices)
        indices = (np.arange(n) if prim.indices is None
                   else self.accessor(prim.indices, f"{name} indices").reshape(-1))
        faces = _triangles(indices.astype(np.int64), mode)
        if len(faces) and (faces.min() < 0 or faces.max() >= n):
            raise ValueError(f"primitive {name!r} has indices beyond its {n} vertices")
        normals = (self.accessor(attrs["NORMAL"], f"{name} NORMAL")
                   if attrs.get("NORMAL") is not None else vertex_normals(vertices, faces))
        uv = None
        if attrs.get("TEXCOORD_0") is not None:
            uv = self.accessor(attrs["TEXCOORD_0"], f"{name} TEXCOORD_0")
            if uv.shape == (n, 2):
                uv = uv * (1.0, -1.0) + (0.0, 1.0)  # glTF's v runs down the image; ours up
            else:
                self.warnings.append(f"primitive {name!r}'s TEXCOORD_0 is not two numbers "
                                     f"for each of its {n} vertices; it is drawn in its base "
                                     "colour")
                uv = None
        colors = None
        if attrs.get("COLOR_0") is not None:
            colors = self.accessor(attrs["COLOR_0"], f"{name} COLOR_0").astype(np.float64)
            if colors.shape[1] == 3:
                colors = np.concatenate([colors, np.ones((n, 1))], axis=1)
        if rigid:
            joints = np.zeros((n, MAX_INFLUENCES), np.int64) + base
            weights = np.zeros((n, MAX_INFLUENCES))
            weights[:, 0] = 1.0
        else:
            joints, weights = self.influences(attrs, name, n)
            joints = joints + base
        color, texture = self.material(prim.material)
        if uv is None:  # nothing says where on the image each vertex is
            texture = None
        return SkinnedPart(vertices, normals, faces, joints.astype(np.int32),
                           weights.astype(np.float32), uv, colors, color, texture, name)

    def influences(self, attrs: dict[str, Any], name: str, n: int
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Every JOINTS_k/WEIGHTS_k set, the 4 largest kept per vertex, renormalised; what
        had to be repaired is told."""
        sets = 0
        while attrs.get(f"JOINTS_{sets}") is not None and attrs.get(f"WEIGHTS_{sets}") is not None:
            sets += 1
        if sets == 0:
            raise ValueError(f"primitive {name!r} of a skinned mesh has no JOINTS_0/WEIGHTS_0")
        joints = np.concatenate([self.accessor(attrs[f"JOINTS_{k}"], f"{name} JOINTS_{k}")
                                 for k in range(sets)], axis=1).astype(np.int64)
        weights = np.concatenate([self.accessor(attrs[f"WEIGHTS_{k}"], f"{name} WEIGHTS_{k}")
                                  for k in range(sets)], axis=1).astype(np.float64)
        if len(joints) != n or len(weights) != n:
            raise ValueError(f"primitive {name!r}: JOINTS/WEIGHTS count differs from POSITION")
        if not np.isfinite(weights).all() or (weights < 0).any():
            raise ValueError(f"primitive {name!r} has weights that are negative or not finite")
        given = weights.sum(axis=1)  # as the file has them, before any are dropped
        if weights.shape[1] > MAX_INFLUENCES:
            many = int(((weights > 0).sum(axis=1) > MAX_INFLUENCES).sum())
            if many:
                self.warnings.append(
                    f"primitive {name!r}: {many} vertices have more than {MAX_INFLUENCES} "
                    f"joint influences; the {MAX_INFLUENCES} largest are kept")
            keep = np.argsort(-weights, axis=1, kind="stable")[:, :MAX_INFLUENCES]
            joints = np.take_along_axis(joints, keep, axis=1)
            weights = np.take_along_axis(weights, keep, axis=1)
        elif weights.shape[1] < MAX_INFLUENCES:  # a VEC4 always; this guards odd files
            pad = MAX_INFLUENCES - weights.shape[1]
            joints = np.pad(joints, ((0, 0), (0, pad)))
            weights = np.pad(weights, ((0, 0), (0, pad)))
        total = weights.sum(axis=1)
        empty = total <= 0.0
        off = ~empty & (np.abs(given - 1.0) > WEIGHT_TOLERANCE)
        if off.any():
            self.warnings.append(
                f"primitive {name!r}: the weights of {int(off.sum())} vertices sum to "
                f"{float(given[off].min()):.3g}..{float(given[off].max()):.3g}, not 1; "
                "renormalised")
        if empty.any():
            self.warnings.append(f"primitive {name!r}: {int(empty.sum())} vertices have no "
                                 "joint weight; they follow the skin's first joint")
            weights[empty] = (1.0, 0.0, 0.0, 0.0)
            joints[empty] = 0
            total = weights.sum(axis=1)
        return joints, weights / total[:, None]

    def material(self, index: int | None) -> tuple[tuple[float, float, float, float],
                                                   np.ndarray | None]:
        materials = self.gltf.materials or []
        if index is None or not 0 <= index < len(materials):
            return WHITE, None
        pbr = materials[index].pbrMetallicRoughness
        if pbr is None:
            return WHITE, None
        factor = pbr.baseColorFactor or [1.0, 1.0, 1.0, 1.0]
        color = (float(factor[0]), float(factor[1]), float(factor[2]), float(factor[3]))
        texture = None
        info = pbr.baseColorTexture
        if info is not None:
            textures = self.gltf.textures or []
            source = textures[info.index].source if 0 <= info.index < len(textures) else None
            texture = None if source is None else self.image(source)
        return color, texture

    def animations(self, new: dict[int, int]) -> list[AnimationClip]:
        clips: list[AnimationClip] = []
        taken: set[str] = set()
        for a, anim in enumerate(self.gltf.animations or []):
            name = anim.name or f"animation{a}"
            while name in taken:
                name += "~2"
            taken.add(name)
            try:
                channels = [c for c in (self.channel(anim, ch, new)
                                        for ch in anim.channels) if c is not None]
            except ValueError as exc:
                self.warnings.append(f"animation {name!r} is left out: {exc}")
                continue
            if not channels:
                continue
            duration = max(float(c.times[-1]) for c in channels)
            clips.append(AnimationClip(name, duration, tuple(channels)))
        return clips

    def channel(self, anim: Any, ch: Any, new: dict[int, int]) -> Channel | None:
        path, node = ch.target.path, ch.target.node
        if path not in PATHS or node is None or node not in new:
            return None  # morph weights, pointers, nodes outside the scene
        if not 0 <= ch.sampler < len(anim.samplers):
            raise ValueError(f"a channel names sampler {ch.sampler}, which does not exist")
        sampler = anim.samplers[ch.sampler]
        kind = sampler.interpolation or "LINEAR"
        if kind not in INTERPOLATIONS:
            raise ValueError(f"unknown interpolation {kind!r}")
        times = self.accessor(sampler.input, "keyframe times").reshape(-1).astype(np.float64)
        if not len(times) or not np.isfinite(times).all():
            raise ValueError("keyframe times are missing or not finite")
        back = np.flatnonzero(np.diff(times) <= 0)
        if len(back):
            k = int(back[0])
            raise ValueError(f"keyframe times of node {node} {path} are out of order at key "
                             f"{k + 2} ({times[k + 1]:g} s after {times[k]:g} s)")
        values = self.accessor(sampler.output, "keyframe values").astype(np.float64)
        width = 4 if path == "rotation" else 3
        per_key = 3 if kind == "CUBICSPLINE" else 1
        if values.shape[1] != width or len(values) != per_key * len(times):
            raise ValueError(f"node {node} {path}: {len(values)} values of {values.shape[1]} "
                             f"for {len(times)} keys")
        if not np.isfinite(values).all():
            raise ValueError(f"node {node} {path} has values that are not finite")
        if path == "rotation":
            values = values[:, [3, 0, 1, 2]]  # glTF writes x, y, z, w
            if kind != "CUBICSPLINE":  # unit, as slerp takes them (files round them)
                length = np.linalg.norm(values, axis=1, keepdims=True)
                if (length < 1e-6).any():
                    raise ValueError(f"node {node} rotation key "
                                     f"{int(np.argmax(length[:, 0] < 1e-6)) + 1} is the zero "
                                     "quaternion, which is no rotation")
                values = values / length
        if kind == "CUBICSPLINE":
            values = values.reshape(len(times), 3, width)
        return Channel(new[node], path, kind, times, values)


def _node_trs(node: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A node's rest translation, rotation (w, x, y, z) and scale (a matrix decomposed)."""
    from engine.rotation import matrix_to_quat

    if node.matrix is not None and len(node.matrix) == 16:
        m = np.array(node.matrix, np.float64).reshape(4, 4).T
        scale = np.linalg.norm(m[:3, :3], axis=0)
        if np.linalg.det(m[:3, :3]) < 0:
            scale[0] = -scale[0]
        rot = m[:3, :3] / np.where(scale == 0, 1.0, scale)
        return m[:3, 3].copy(), matrix_to_quat(rot), scale
    t = np.array(node.translation if node.translation is not None else (0, 0, 0), np.float64)
    x, y, z, w = node.rotation if node.rotation is not None else (0, 0, 0, 1)
    s = np.array(node.scale if node.scale is not None else (1, 1, 1), np.float64)
    return t, np.array([w, x, y, z], np.float64), s


def _triangles(indices: np.ndarray, mode: int) -> np.ndarray:
    if mode == 4:
        return indices[: len(indices) // 3 * 3].reshape(-1, 3)
    k = np.arange(max(len(indices) - 2, 0))
    if mode == 5:  # strip: every other triangle flipped to keep the winding
        a, b = np.where(k % 2 == 0, k, k + 1), np.where(k % 2 == 0, k + 1, k)
        return np.stack([indices[a], indices[b], indices[k + 2]], axis=1)
    return np.stack([np.full(len(k), indices[0]), indices[k + 1], indices[k + 2]], axis=1)


def _unquote(uri: str) -> str:
    from urllib.parse import unquote

    return unquote(uri)
