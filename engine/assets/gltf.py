"""glTF 2.0 files read as a document of named nodes: the JSON, its buffers and accessors,
the node tree with world matrices, and the meshes of chosen nodes as a model.

The whole-file model loader (trimesh, :mod:`engine.assets.loaders`) draws a file as one
thing; an importer needs more: which node is where, which mesh a node holds, its
extensions and extras. :class:`GltfDocument` is that, read once per file through the
asset cache (``Assets.document``). :meth:`GltfDocument.node_model` is what a scene's
``Geometry { File "room.glb" Nodes ["Door"] }`` draws or collides with: those nodes' own
meshes, placed as in the file relative to the first node, its scale baked in.

Everything here is in glTF's frame (+Y up) except what :meth:`node_model` returns, which
is turned +Z up like every model the engine loads (:data:`Y_UP_TO_Z_UP`). A file that
lies (an accessor past its buffer, a missing buffer, NaN in a matrix) raises
``ValueError`` with the reason when that part is used, so an importer can skip that node
and go on with the rest.
"""

from __future__ import annotations

import base64
import binascii
import json
import math
import struct
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from engine.assets.loaders import rgba_pixels
from engine.assets.registry import built_in_loader
from engine.assets.types import WHITE, MeshPart, ModelAsset, vertex_normals
from engine.rotation import compose

#: glTF is +Y up, the engine +Z up: (x, y, z) -> (x, -z, y), a quarter turn about X.
Y_UP_TO_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

#: What a file may hold before it is refused outright (not a model, or not one to draw).
MAX_FILE_BYTES = 2 * 1024 * 1024 * 1024
MAX_JSON_BYTES = 256 * 1024 * 1024
MAX_NODES = 1_000_000
MAX_ACCESSOR_BYTES = 1024 * 1024 * 1024

_GLB_MAGIC = b"glTF"
_CHUNK_JSON, _CHUNK_BIN = 0x4E4F534A, 0x004E4942
_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
               5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_TRIANGLES, _STRIP, _FAN = 4, 5, 6
_ORIGIN, _NO_TURN, _UNIT = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0), (1.0, 1.0, 1.0)


@dataclass(frozen=True, slots=True)
class Frame:
    """A 4x4 matrix taken apart: ``translation``, a proper ``rotation`` (3x3), per-axis
    ``scale`` (negative for a mirrored axis) and whether parents' non-uniform scale
    sheared it (then rotation times scale is only the nearest such transform)."""

    translation: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray
    sheared: bool

    def unscaled(self) -> np.ndarray:
        """The 4x4 rigid transform (rotation and translation, no scale)."""
        m = np.eye(4)
        m[:3, :3] = self.rotation
        m[:3, 3] = self.translation
        return m


def decompose(matrix: np.ndarray) -> Frame:
    """``matrix`` as translation, rotation and scale (columns' lengths, one negated for a
    mirror). Zero scale on an axis keeps that axis of the nearest rotation."""
    t, r, s, sheared = decompose_many(np.asarray(matrix, np.float64)[None])
    return Frame(t[0], r[0], s[0], bool(sheared[0]))


def decompose_many(matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                 np.ndarray]:
    """:func:`decompose` of ``(N, 4, 4)`` matrices at once: translations ``(N, 3)``,
    rotations ``(N, 3, 3)``, scales ``(N, 3)`` and whether each is sheared ``(N,)``."""
    basis = matrices[:, :3, :3]
    u, s, vt = np.linalg.svd(basis)
    rotation = u @ vt
    mirrored = np.linalg.det(rotation) < 0
    if mirrored.any():
        u[mirrored, :, -1] *= -1
        rotation[mirrored] = u[mirrored] @ vt[mirrored]
    scale = np.einsum("nij,nij->nj", rotation, basis)  # diag(R^T B): signed column lengths
    error = np.abs(rotation * scale[:, None, :] - basis).max(axis=(1, 2))
    sheared = error > 1e-6 * np.maximum(1.0, s.max(axis=1))
    return matrices[:, :3, 3].copy(), rotation, scale, sheared


def to_z_up(matrix: np.ndarray) -> np.ndarray:
    """A glTF-frame transform (or ``(N, 4, 4)`` of them) as the engine's: ``C M C^-1``
    (its local axes turned too, so a node upright in glTF is upright here)."""
    return _C4 @ np.asarray(matrix, np.float64) @ _C4.T


_C4 = np.eye(4)
_C4[:3, :3] = Y_UP_TO_Z_UP


def node_matrix(node: dict[str, Any]) -> np.ndarray:
    """A node's local 4x4 matrix from ``matrix`` or translation/rotation/scale; raises
    ValueError naming what is not finite or not the right size."""
    if "matrix" in node:
        values = _numbers(node["matrix"], 16, "matrix")
        return np.array(values, np.float64).reshape(4, 4).T  # glTF stores columns
    t = _numbers(node.get("translation", _ORIGIN), 3, "translation")
    q = _numbers(node.get("rotation", _NO_TURN), 4, "rotation")
    s = _numbers(node.get("scale", _UNIT), 3, "scale")
    if not any(q):
        raise ValueError("its rotation quaternion is all zeros")
    return compose(np.array(t), _wxyz(np.array(q)), np.array(s))


def _wxyz(q: np.ndarray) -> np.ndarray:
    """glTF's quaternions ``[x y z w]`` in the engine's order ``(w, x, y, z)``."""
    return np.asarray(q)[..., [3, 0, 1, 2]]


def _numbers(values: Any, count: int, what: str) -> list[float]:
    if not isinstance(values, list | tuple) or len(values) != count or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        raise ValueError(f"its {what} is not {count} numbers")
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"its {what} holds a value that is not a finite number "
                         f"({', '.join(str(v) for v in values if not math.isfinite(v))})")
    return [float(v) for v in values]


class GltfDocument:
    """One glTF file: JSON, buffers (read when first used), node tree and meshes."""

    def __init__(self, path: Path, document: dict[str, Any], binary: bytes | None) -> None:
        if not isinstance(document, dict):
            raise ValueError("not a glTF file: its JSON is not an object")
        version = str(document.get("asset", {}).get("version", "")) if isinstance(
            document.get("asset"), dict) else ""
        if not version.startswith("2"):
            raise ValueError(f"not a glTF 2.0 file (asset.version is {version or 'missing'})")
        self.path = path
        self.json = document
        self._binary = binary
        self._buffers: dict[int, bytes] = {}
        self._parts: dict[int, tuple[MeshPart, ...]] = {}
        self._textures: dict[int, np.ndarray | None] = {}
        self._node_models: dict[tuple, ModelAsset] = {}
        self.nodes: list[dict[str, Any]] = _list(document, "nodes")
        if len(self.nodes) > MAX_NODES:
            raise ValueError(f"it has {len(self.nodes)} nodes, more than {MAX_NODES}; "
                             f"not read (split the scene)")
        self.meshes: list[dict[str, Any]] = _list(document, "meshes")
        #: Node index -> why it cannot be used (a bad transform, a cycle, two parents).
        self.bad_nodes: dict[int, str] = {}
        self.parents = np.full(len(self.nodes), -1, np.int64)
        self.children: list[list[int]] = [[] for _ in self.nodes]
        self._tree()
        self.world = self._world_matrices()

    # -- reading -----------------------------------------------------------------
    @staticmethod
    def read(path: Path) -> GltfDocument:
        """The loader: a ``.gltf`` (JSON) or ``.glb`` (binary container) file."""
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise ValueError(f"it is {size} bytes, more than {MAX_FILE_BYTES}; not read")
        data = path.read_bytes()
        if data[:4] == _GLB_MAGIC:
            document, binary = _split_glb(data)
        else:
            if len(data) > MAX_JSON_BYTES:
                raise ValueError(f"its JSON is {len(data)} bytes, more than {MAX_JSON_BYTES}")
            document, binary = _json(data), None
        return GltfDocument(path, document, binary)

    def buffer(self, index: int) -> bytes:
        """Buffer ``index``'s bytes: the GLB chunk, a data URI or a file beside this one."""
        found = self._buffers.get(index)
        if found is not None:
            return found
        buffers = _list(self.json, "buffers")
        if not 0 <= index < len(buffers):
            raise ValueError(f"buffer {index} does not exist (the file has {len(buffers)})")
        spec = buffers[index]
        uri = spec.get("uri")
        if uri is None:
            if self._binary is None:
                raise ValueError(f"buffer {index} has no uri and the file has no binary chunk")
            data = self._binary
        else:
            data = self._uri(str(uri), f"buffer {index}")
        length = spec.get("byteLength")
        if not isinstance(length, int) or length < 0 or length > len(data):
            raise ValueError(f"buffer {index} claims {length} bytes but holds {len(data)}")
        self._buffers[index] = data
        return data

    def _uri(self, uri: str, what: str) -> bytes:
        if uri.startswith("data:"):
            _, _, payload = uri.partition(",")
            try:
                return base64.b64decode(payload, validate=True)
            except (binascii.Error, ValueError):
                raise ValueError(f"{what}'s data URI is not valid base64") from None
        from urllib.parse import unquote

        target = self.path.parent / unquote(uri)
        if not target.is_file():
            raise ValueError(f"{what} is missing: {uri} (looked for {target})")
        return target.read_bytes()

    def accessor(self, index: int) -> np.ndarray:
        """Accessor ``index`` as an array (count, width), sparse values applied;
        normalized integers scaled to 0..1 (or -1..1)."""
        try:
            return self._accessor(index)
        except (TypeError, AttributeError, KeyError, IndexError, OverflowError) as exc:
            # a field of the wrong JSON type (a list for a number, a number for an object)
            raise ValueError(f"accessor {index} is malformed ({type(exc).__name__}: "
                             f"{exc})") from None

    def _accessor(self, index: int) -> np.ndarray:
        accessors = _list(self.json, "accessors")
        if not isinstance(index, int) or not 0 <= index < len(accessors):
            raise ValueError(f"accessor {index} does not exist")
        spec = accessors[index]
        dtype = _COMPONENTS.get(spec.get("componentType"))
        width = _WIDTH.get(spec.get("type"))
        count = spec.get("count")
        if dtype is None or width is None or not isinstance(count, int) or count < 0:
            raise ValueError(f"accessor {index} has a bad componentType, type or count")
        item = np.dtype(dtype).itemsize * width
        if count * item > MAX_ACCESSOR_BYTES:
            raise ValueError(f"accessor {index} claims {count} items ({count * item} bytes), "
                             f"more than {MAX_ACCESSOR_BYTES}")
        if "bufferView" in spec:
            values = self._view(spec["bufferView"], int(spec.get("byteOffset", 0)), dtype,
                                width, count, f"accessor {index}")
        else:
            values = np.zeros((count, width), dtype)
        sparse = spec.get("sparse")
        if sparse is not None:
            values = values.copy()
            n = int(sparse.get("count", 0))
            ind, val = sparse.get("indices", {}), sparse.get("values", {})
            idx_type = _COMPONENTS.get(ind.get("componentType"))
            if idx_type is None:
                raise ValueError(f"accessor {index}'s sparse indices have a bad componentType")
            where = self._view(ind.get("bufferView"), int(ind.get("byteOffset", 0)), idx_type,
                               1, n, f"accessor {index} sparse indices").reshape(-1)
            if n and int(where.max()) >= count:
                raise ValueError(f"accessor {index}'s sparse indices pass its count")
            values[where] = self._view(val.get("bufferView"), int(val.get("byteOffset", 0)),
                                       dtype, width, n, f"accessor {index} sparse values")
        if spec.get("normalized") and dtype is not np.float32:
            info = np.iinfo(dtype)
            values = np.maximum(values.astype(np.float64) / info.max, -1.0)
        return values

    def _view(self, view_index: Any, offset: int, dtype: Any, width: int, count: int,
              what: str) -> np.ndarray:
        views = _list(self.json, "bufferViews")
        if not isinstance(view_index, int) or not 0 <= view_index < len(views):
            raise ValueError(f"{what} names bufferView {view_index}, which does not exist")
        view = views[view_index]
        data = self.buffer(int(view.get("buffer", -1)))
        start = int(view.get("byteOffset", 0)) + offset
        length = int(view.get("byteLength", 0))
        item = np.dtype(dtype).itemsize * width
        stride = int(view.get("byteStride", 0)) or item
        needed = (count - 1) * stride + item if count else 0
        if start < 0 or needed > length - offset or start + needed > len(data):
            raise ValueError(f"{what} reads past the end of its buffer ({count} items from "
                             f"byte {start}, the view has {length} bytes)")
        if count == 0:
            return np.zeros((0, width), dtype)
        if stride == item:
            raw = np.frombuffer(data, dtype, count * width, start)
            return raw.reshape(count, width)
        rows = np.lib.stride_tricks.as_strided(
            np.frombuffer(data, np.uint8, needed, start), (count, item), (stride, 1))
        return np.ascontiguousarray(rows).view(dtype).reshape(count, width)

    # -- the node tree -----------------------------------------------------------
    def _tree(self) -> None:
        n = len(self.nodes)
        for i, node in enumerate(self.nodes):
            if not isinstance(node, dict):
                self.bad_nodes[i] = "it is not a JSON object"
                self.nodes[i] = {}
                continue
            for child in node.get("children", ()):
                if not isinstance(child, int) or not 0 <= child < n:
                    self.bad_nodes[i] = f"it names child node {child}, which does not exist"
                elif self.parents[child] >= 0 or child == i:
                    self.bad_nodes[child] = "it has more than one parent (or is its own)"
                else:
                    self.parents[child] = i
                    self.children[i].append(child)

    def _local_matrices(self) -> tuple[np.ndarray, dict[int, str]]:
        """Every node's local matrix, and why the ones that cannot be made are not.

        The translations, rotations and scales of all nodes become matrices in one numpy
        pass; a node with a ``matrix``, or a value that is not plain numbers, takes
        :func:`node_matrix`, which says exactly what is wrong."""
        n = len(self.nodes)
        local = np.repeat(np.eye(4)[None], n, axis=0)
        broken: dict[int, str] = {}
        plain = [i for i, node in enumerate(self.nodes) if "matrix" not in node]
        try:
            t = np.array([self.nodes[i].get("translation", _ORIGIN) for i in plain], float)
            q = np.array([self.nodes[i].get("rotation", _NO_TURN) for i in plain], float)
            s = np.array([self.nodes[i].get("scale", _UNIT) for i in plain], float)
            if t.shape != (len(plain), 3) or q.shape != (len(plain), 4) or s.shape != (
                    len(plain), 3):
                raise ValueError("not all nodes hold 3, 4 and 3 numbers")
        except (ValueError, TypeError):  # some node is odd: each on its own
            plain = []
        if plain:
            good = np.isfinite(t).all(1) & np.isfinite(q).all(1) & np.isfinite(s).all(1) & (
                np.abs(q).sum(1) > 0)
            with np.errstate(invalid="ignore", over="ignore"):  # the bad rows are redone
                local[np.array(plain)] = compose(t, _wxyz(q), s)
            slow = [i for i, ok in zip(plain, good, strict=True) if not ok]
        else:
            slow = list(range(n))
        for i in slow + [i for i, node in enumerate(self.nodes) if "matrix" in node]:
            try:
                local[i] = node_matrix(self.nodes[i])
            except ValueError as exc:
                broken[i] = str(exc)
        return local, broken

    def _world_matrices(self) -> np.ndarray:
        """Every node's world matrix (glTF frame); a bad node's subtree is marked bad."""
        n = len(self.nodes)
        local, unusable = self._local_matrices()
        world = np.repeat(np.eye(4)[None], n, axis=0)
        done = np.zeros(n, bool)
        roots = [i for i in range(n) if self.parents[i] < 0]
        stack: list[tuple[int, np.ndarray | None, str | None]] = [
            (r, None, None) for r in reversed(roots)]  # a root's world is its own matrix
        while stack:
            i, parent, broken = stack.pop()
            done[i] = True
            if broken is None and i not in self.bad_nodes:
                if i in unusable:
                    broken = f"node '{self.name(i)}': {unusable[i]}"
                    self.bad_nodes[i] = unusable[i]
                else:
                    world[i] = local[i] if parent is None else parent @ local[i]
            elif broken is not None:
                self.bad_nodes.setdefault(i, f"its ancestor is unusable ({broken})")
            stack.extend((c, world[i], broken) for c in reversed(self.children[i]))
        for i in np.flatnonzero(~done):  # in a cycle: no root above them
            self.bad_nodes.setdefault(int(i), "it is part of a cycle of nodes")
        return world

    def name(self, index: int) -> str:
        """A node's name as the file gives it (``node<index>`` when it has none)."""
        return self._names[index]

    @cached_property
    def _names(self) -> list[str]:
        """Every node's name, worked out once (an import asks each node's many times)."""
        out = []
        for i, node in enumerate(self.nodes):
            name = node.get("name")
            out.append(name if isinstance(name, str) and name else f"node{i}")
        return out

    def mesh_name(self, index: int) -> str:
        """A mesh's name as the file gives it (``mesh<index>`` when it has none)."""
        name = self.meshes[index].get("name") if isinstance(self.meshes[index], dict) else None
        return name if isinstance(name, str) and name else f"mesh{index}"

    @cached_property
    def _by_name(self) -> dict[str, list[int]]:
        return _by_name(self._names)

    @cached_property
    def _mesh_by_name(self) -> dict[str, list[int]]:
        return _by_name([self.mesh_name(i) for i in range(len(self.meshes))])

    def node_ref(self, index: int) -> str:
        """How a scene names node ``index``: its name, or ``#index`` when another node
        has the same name."""
        return self._node_refs[index]

    @cached_property
    def _node_refs(self) -> list[str]:
        by_name = self._by_name
        return [_ref(by_name, name, i) for i, name in enumerate(self._names)]

    def mesh_ref(self, index: int) -> str:
        """How a scene names mesh ``index`` (as :meth:`node_ref` names a node)."""
        return _ref(self._mesh_by_name, self.mesh_name(index), index)

    def find_node(self, ref: str) -> int:
        """The node a scene names (see :meth:`node_ref`); ValueError if none, or several."""
        return _find(self._by_name, ref, len(self.nodes), "node")

    def find_mesh(self, ref: str) -> int:
        """The mesh a scene names (see :meth:`mesh_ref`)."""
        return _find(self._mesh_by_name, ref, len(self.meshes), "mesh")

    @cached_property
    def scene_nodes(self) -> list[int]:
        """The default scene's nodes, parents before children (all roots if none is named)."""
        scenes = _list(self.json, "scenes")
        index = self.json.get("scene", 0)
        if scenes and isinstance(index, int) and 0 <= index < len(scenes):
            roots = [r for r in scenes[index].get("nodes", ())
                     if isinstance(r, int) and 0 <= r < len(self.nodes)]
        else:
            roots = [i for i in range(len(self.nodes)) if self.parents[i] < 0]
        order, stack = [], list(reversed(roots))
        while stack:
            i = stack.pop()
            order.append(i)
            stack.extend(reversed(self.children[i]))
        return order

    # -- meshes ------------------------------------------------------------------
    def mesh_parts(self, mesh: int) -> tuple[MeshPart, ...]:
        """Mesh ``mesh``'s triangle primitives in its own space (glTF frame), one part each."""
        found = self._parts.get(mesh)
        if found is None:
            if not isinstance(mesh, int) or not 0 <= mesh < len(self.meshes):
                raise ValueError(f"mesh {mesh} does not exist (the file has "
                                 f"{len(self.meshes)})")
            spec = _object(self.meshes[mesh], f"mesh {mesh}")
            parts = []
            for k, prim in enumerate(_list(spec, "primitives")):
                what = f"mesh {spec.get('name') or mesh} primitive {k}"
                part = self._primitive(_object(prim, what), what)
                if part is not None:
                    parts.append(part)
            found = self._parts[mesh] = tuple(parts)
        return found

    def _primitive(self, prim: dict[str, Any], what: str) -> MeshPart | None:
        mode = prim.get("mode", _TRIANGLES)
        if mode not in (_TRIANGLES, _STRIP, _FAN):
            return None  # points and lines have no surface to draw or collide with
        attributes = _object(prim.get("attributes", {}), f"{what}'s attributes")
        if "POSITION" not in attributes:
            raise ValueError(f"{what} has no POSITION")
        if "extensions" in prim and "KHR_draco_mesh_compression" in prim["extensions"]:
            raise ValueError(f"{what} is Draco-compressed, which is not read here")
        vertices = self.accessor(attributes["POSITION"]).astype(np.float64)
        if vertices.shape[1] != 3:
            raise ValueError(f"{what}'s POSITION is not VEC3")
        if not np.isfinite(vertices).all():
            raise ValueError(f"{what} has vertices that are not finite numbers")
        if "indices" in prim:
            indices = self.accessor(prim["indices"]).reshape(-1).astype(np.int64)
        else:
            indices = np.arange(len(vertices), dtype=np.int64)
        faces = _faces(indices, mode)
        if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise ValueError(f"{what} has indices past its {len(vertices)} vertices")
        normals = (self.accessor(attributes["NORMAL"]).astype(np.float64)
                   if "NORMAL" in attributes else None)
        if normals is None or normals.shape != vertices.shape or not np.isfinite(normals).all():
            normals = vertex_normals(vertices, faces)
        uv = colors = None
        if "TEXCOORD_0" in attributes:
            uv = self.accessor(attributes["TEXCOORD_0"]).astype(np.float64)
            # glTF's v runs down the image, a MeshPart's up (as trimesh gives whole files)
            uv = uv * (1.0, -1.0) + (0.0, 1.0) if uv.shape == (len(vertices), 2) else None
        if "COLOR_0" in attributes:
            raw = self.accessor(attributes["COLOR_0"]).astype(np.float64)
            if len(raw) == len(vertices) and raw.shape[1] in (3, 4):
                colors = raw if raw.shape[1] == 4 else np.hstack([raw, np.ones((len(raw), 1))])
        color, texture = self._material(prim.get("material"), uv is not None)
        return MeshPart(vertices, faces, normals, uv, colors, color, texture, what)

    def _material(self, index: Any, has_uv: bool) -> tuple[tuple[float, ...], np.ndarray | None]:
        materials = _list(self.json, "materials")
        if not isinstance(index, int) or not 0 <= index < len(materials):
            return WHITE, None
        material = materials[index]
        pbr = material.get("pbrMetallicRoughness") if isinstance(material, dict) else None
        if not isinstance(pbr, dict):  # no colour said, or said in no way that reads
            return WHITE, None
        factor = pbr.get("baseColorFactor", WHITE)
        try:
            color = tuple(_numbers(factor, 4, "baseColorFactor"))
        except ValueError:
            color = WHITE
        texture = None
        if has_uv and isinstance(pbr.get("baseColorTexture"), dict):
            texture = self._texture(pbr["baseColorTexture"].get("index"))
        return color, texture

    def _texture(self, index: Any) -> np.ndarray | None:
        """A texture's RGBA pixels (rows top to bottom), or None if it cannot be read (the
        part is then drawn in its base colour)."""
        if index in self._textures:
            return self._textures[index]
        pixels = None
        textures, images = _list(self.json, "textures"), _list(self.json, "images")
        try:
            source = textures[index].get("source")
            image = images[source]
            if "bufferView" in image:
                view = _list(self.json, "bufferViews")[image["bufferView"]]
                data = self.buffer(view["buffer"])
                start = int(view.get("byteOffset", 0))
                raw = data[start:start + int(view["byteLength"])]
            else:
                raw = self._uri(str(image["uri"]), f"image {source}")
            import io

            from PIL import Image

            with Image.open(io.BytesIO(raw)) as img:
                pixels = rgba_pixels(img)
        except Exception:  # a texture that cannot be read leaves the base colour
            pixels = None
        self._textures[index] = pixels
        return pixels

    # -- what a scene draws --------------------------------------------------------
    def node_model(self, refs: tuple[str, ...]) -> ModelAsset:
        """The meshes of the nodes ``refs`` names (each node's own mesh, not its
        children's), placed as in the file relative to the first node's position and
        rotation (its scale and the others' transforms baked in), turned +Z up."""
        if not refs:
            raise ValueError("no nodes named")
        indices = [self.find_node(ref) for ref in refs]
        for i in indices:
            if i in self.bad_nodes:
                raise ValueError(f"node '{self.name(i)}' cannot be used: {self.bad_nodes[i]}")
        if len(indices) == 1:  # a node alone, as an imported scene draws each: its scale
            i = indices[0]
            placed = [(self.nodes[i]["mesh"], self._own[i])] if self.nodes[i].get(
                "mesh") is not None else []
        else:
            base = np.linalg.inv(self._rigid[indices[0]])
            placed = [(self.nodes[i]["mesh"], base @ self.world[i]) for i in indices
                      if self.nodes[i].get("mesh") is not None]
        # nodes drawing the same meshes the same way share one model (and the renderer
        # one copy of it): a file of 10,000 boxes holds one box
        key = tuple((mesh, np.round(m, 9).tobytes()) for mesh, m in placed)
        found = self._node_models.get(key)
        if found is not None:
            return found
        parts = [_placed(p, m) for mesh, m in placed for p in self.mesh_parts(mesh)]
        if not parts:
            names = ", ".join(f"'{self.name(i)}'" for i in indices)
            raise ValueError(f"node{'s' if len(indices) > 1 else ''} {names} hold no triangles")
        model = ModelAsset(Path(f"{self.path}#{json.dumps(list(refs))}"), tuple(parts))
        self._node_models[key] = model
        return model

    @cached_property
    def _rigid(self) -> np.ndarray:
        """Every node's world frame without its scale: ``(N, 4, 4)``."""
        t, r, _, _ = decompose_many(self.world)
        out = np.repeat(np.eye(4)[None], len(self.nodes), axis=0)
        out[:, :3, :3] = r
        out[:, :3, 3] = t
        return out

    @cached_property
    def _own(self) -> np.ndarray:
        """Every node's world matrix in its own rigid frame (its scale and shear):
        ``(N, 4, 4)``, for all nodes at once (an inverse each was most of drawing a file
        of 10,000 bodies)."""
        rigid = self._rigid
        inverse = np.zeros_like(rigid)
        turn = np.transpose(rigid[:, :3, :3], (0, 2, 1))
        inverse[:, :3, :3] = turn
        inverse[:, :3, 3] = -np.einsum("nij,nj->ni", turn, rigid[:, :3, 3])
        inverse[:, 3, 3] = 1.0
        return inverse @ np.asarray(self.world, np.float64)


    def mesh_model(self, ref: str) -> ModelAsset:
        """The mesh ``ref`` names, in its own space, turned +Z up."""
        index = self.find_mesh(ref)
        parts = tuple(_placed(p, np.eye(4)) for p in self.mesh_parts(index))
        if not parts:
            raise ValueError(f"mesh {ref!r} holds no triangles")
        return ModelAsset(Path(f"{self.path}#mesh{json.dumps([ref])}"), parts)


def _by_name(names: list[str]) -> dict[str, list[int]]:
    found: dict[str, list[int]] = {}
    for i, name in enumerate(names):
        found.setdefault(name, []).append(i)
    return found


def _ref(by_name: dict[str, list[int]], name: str, index: int) -> str:
    return name if len(by_name[name]) == 1 else f"#{index}"


def _find(by_name: dict[str, list[int]], ref: str, count: int, what: str) -> int:
    found = by_name.get(ref)
    if found is not None and len(found) == 1:
        return found[0]
    if found:
        plural = what + ("es" if what.endswith("sh") else "s")
        raise ValueError(f"{len(found)} {plural} are named {ref!r}; name one as '#INDEX' "
                         f"(#{', #'.join(map(str, found))})")
    if ref.startswith("#") and ref[1:].isdigit() and int(ref[1:]) < count:
        return int(ref[1:])
    raise ValueError(f"it has no {what} {ref!r}")


def _placed(part: MeshPart, matrix: np.ndarray) -> MeshPart:
    """``part`` moved by ``matrix`` (glTF frame) then turned +Z up."""
    linear = Y_UP_TO_Z_UP @ matrix[:3, :3]
    vertices = part.vertices @ linear.T + Y_UP_TO_Z_UP @ matrix[:3, 3]
    normal_matrix = np.linalg.inv(linear).T if abs(np.linalg.det(linear)) > 1e-300 else linear
    normals = part.normals @ normal_matrix.T
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    faces = part.faces if np.linalg.det(linear) >= 0 else part.faces[:, ::-1]
    return MeshPart(vertices, faces, normals, part.uv, part.colors, part.color, part.texture,
                    part.name)


def _faces(indices: np.ndarray, mode: int) -> np.ndarray:
    if mode == _TRIANGLES:
        return indices[: len(indices) // 3 * 3].reshape(-1, 3)
    if len(indices) < 3:
        return np.zeros((0, 3), np.int64)
    k = np.arange(len(indices) - 2)
    if mode == _STRIP:  # every other triangle flips to keep the winding
        even = k % 2 == 0
        a = indices[k]
        b = np.where(even, indices[k + 1], indices[k + 2])
        c = np.where(even, indices[k + 2], indices[k + 1])
        return np.stack([a, b, c], axis=1)
    return np.stack([np.full_like(k, indices[0]), indices[k + 1], indices[k + 2]], axis=1)


def _list(document: dict[str, Any], key: str) -> list[Any]:
    found = document.get(key, [])
    if not isinstance(found, list):
        raise ValueError(f"its '{key}' is not a list")
    return found


def _object(value: Any, what: str) -> dict[str, Any]:
    """``value`` if it is a JSON object; ValueError naming ``what`` if not."""
    if not isinstance(value, dict):
        raise ValueError(f"{what} is not a JSON object")
    return value


def _json(data: bytes) -> dict[str, Any]:
    try:
        return json.loads(data)
    except (ValueError, UnicodeDecodeError) as exc:
        raise ValueError(f"not a glTF file: it is not JSON ({exc})") from None
    except RecursionError:
        raise ValueError("not a glTF file: its JSON is nested too deeply") from None


def _split_glb(data: bytes) -> tuple[dict[str, Any], bytes | None]:
    """A GLB container's JSON and binary chunks, every length checked against the file."""
    if len(data) < 20:
        raise ValueError("not a GLB file: shorter than its header")
    _, version, length = struct.unpack_from("<4sII", data, 0)
    if version != 2:
        raise ValueError(f"GLB version {version}; only version 2 is read")
    if length > len(data):
        raise ValueError(f"the GLB header claims {length} bytes but the file has {len(data)} "
                         f"(cut short?)")
    chunks: dict[int, bytes] = {}
    pos = 12
    while pos + 8 <= length:
        size, kind = struct.unpack_from("<II", data, pos)
        if pos + 8 + size > length:
            raise ValueError(f"a GLB chunk claims {size} bytes, past the end of the file")
        if kind == _CHUNK_JSON and size > MAX_JSON_BYTES:
            raise ValueError(f"its JSON chunk is {size} bytes, more than {MAX_JSON_BYTES}")
        chunks.setdefault(kind, data[pos + 8:pos + 8 + size])
        pos += 8 + size + (-size % 4)
    if _CHUNK_JSON not in chunks:
        raise ValueError("not a GLB file: it has no JSON chunk")
    return _json(chunks[_CHUNK_JSON]), chunks.get(_CHUNK_BIN)


built_in_loader("document", ".gltf", ".glb")(GltfDocument.read)
