"""Collada (.dae) files read as a document of named nodes, like :mod:`engine.assets.gltf`:
the node tree with world matrices (pycollada reads the visual scene), the XML for what
pycollada does not read (``<library_physics_*>``), and chosen nodes' or geometries'
triangles as a model.

A Collada file says its up axis and unit (``<asset><up_axis>``, ``<unit meter>``);
:meth:`ColladaDocument.to_z_up` turns its transforms into the engine's metres and +Z up,
and :meth:`node_model` / :meth:`mesh_model` return models already turned.
"""

from __future__ import annotations

import json
import math
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from engine.assets.gltf import decompose
from engine.assets.registry import built_in_loader
from engine.assets.types import WHITE, MeshPart, ModelAsset, vertex_normals

#: A file's axes (right, up, in) -> the engine's (X, Z, -Y), by ``<up_axis>``.
UP_AXES = {
    "Y_UP": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
    "Z_UP": np.eye(3),
    "X_UP": np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]),
}


class ColladaDocument:
    """One Collada file: pycollada's reading of it, its XML, and its nodes in order."""

    def __init__(self, path: Path, dae: Any) -> None:
        self.path = path
        self.dae = dae
        self.xml = dae.xmlnode.getroot()
        up = getattr(dae.assetInfo, "upaxis", None) or "Y_UP"
        self.up_axis = str(up).upper() if str(up).upper() in UP_AXES else "Y_UP"
        #: File axes -> engine axes, times the unit in metres.
        self.axes = UP_AXES[self.up_axis]
        meter = getattr(dae.assetInfo, "unitmeter", None)
        self.meter = float(meter) if meter and math.isfinite(float(meter)) and float(
            meter) > 0 else 1.0
        self.nodes: list[Any] = []
        self.parents: list[int] = []
        self.world: list[np.ndarray] = []
        #: Node index -> why it cannot be used (a transform that is not finite).
        self.bad_nodes: dict[int, str] = {}
        scene = dae.scene
        for root in (scene.nodes if scene is not None else []):
            self._walk(root, -1, np.eye(4), None)

    @staticmethod
    def read(path: Path) -> ColladaDocument:
        """The loader: a .dae file through pycollada (broken references tolerated, told
        when used)."""
        import collada
        from collada.common import DaeBrokenRefError, DaeUnsupportedError

        return ColladaDocument(path, collada.Collada(
            str(path), ignore=[DaeUnsupportedError, DaeBrokenRefError]))

    def _walk(self, node: Any, parent: int, above: np.ndarray, broken: str | None) -> None:
        import collada

        if isinstance(node, collada.scene.NodeNode):  # <instance_node>: the node it names
            node = node.node
        if not isinstance(node, collada.scene.Node):
            return
        index = len(self.nodes)
        self.nodes.append(node)
        self.parents.append(parent)
        matrix = np.asarray(node.matrix, np.float64)
        if broken is None and not np.isfinite(matrix).all():
            broken = f"node '{self.name(index)}'"
            self.bad_nodes[index] = "its transform holds a value that is not a finite number"
        elif broken is not None:
            self.bad_nodes[index] = f"its ancestor is unusable ({broken})"
        world = above @ matrix if broken is None else np.eye(4)
        self.world.append(world)
        for child in node.children:
            self._walk(child, index, world, broken)

    # -- names ---------------------------------------------------------------------
    def name(self, index: int) -> str:
        """A node's name (or id), ``node<index>`` when it has neither."""
        node = self.nodes[index]
        return node.name or node.id or f"node{index}"

    @cached_property
    def _refs(self) -> dict[str, list[int]]:
        found: dict[str, list[int]] = {}
        for i, node in enumerate(self.nodes):
            for key in {node.id, node.name} - {None}:
                found.setdefault(key, []).append(i)
        return found

    def node_ref(self, index: int) -> str:
        """How a scene names node ``index``: its id (or name) when that names it alone,
        else ``#index``."""
        node = self.nodes[index]
        for key in (node.id, node.name):
            if key and self._refs.get(key) == [index]:
                return key
        return f"#{index}"

    def find_node(self, ref: str) -> int:
        found = self._refs.get(ref)
        if found is not None and len(set(found)) == 1:
            return found[0]
        if ref.startswith("#") and ref[1:].isdigit() and int(ref[1:]) < len(self.nodes):
            return int(ref[1:])
        raise ValueError(f"it has no node {ref!r}" if not found else
                         f"several nodes are called {ref!r}")

    def node_index(self, node_id: str) -> int | None:
        """The node whose ``id`` is ``node_id`` (a ``#`` in front allowed), or None."""
        key = node_id.lstrip("#")
        for i, node in enumerate(self.nodes):
            if node.id == key:
                return i
        return None

    # -- frames --------------------------------------------------------------------
    def to_z_up(self, matrix: np.ndarray) -> np.ndarray:
        """A transform of the file's as the engine's: axes turned Z up, units metres."""
        c = np.eye(4)
        c[:3, :3] = self.axes * self.meter
        return c @ np.asarray(matrix, np.float64) @ np.linalg.inv(c)

    # -- models ----------------------------------------------------------------------
    def geometry_parts(self, geometry: Any, materials: Any = None) -> list[MeshPart]:
        """A pycollada geometry's triangles in its own space (file axes and units)."""
        import collada

        colors = {}
        for m in materials or []:
            effect = getattr(getattr(m, "target", None), "effect", None)
            diffuse = getattr(effect, "diffuse", None)
            if isinstance(diffuse, tuple) and len(diffuse) >= 3:
                colors[m.symbol] = tuple(float(x) for x in (*diffuse[:3], 1.0))
        parts = []
        for prim in geometry.primitives:
            if hasattr(prim, "triangleset"):
                prim = prim.triangleset()
            if not isinstance(prim, collada.triangleset.TriangleSet) or prim.vertex is None:
                continue
            vertices = np.asarray(prim.vertex, np.float64).reshape(-1, 3)
            faces = np.asarray(prim.vertex_index, np.int64).reshape(-1, 3)
            if not np.isfinite(vertices).all():
                raise ValueError(f"geometry {geometry.id!r} has vertices that are not finite")
            if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
                raise ValueError(f"geometry {geometry.id!r} has indices past its vertices")
            parts.append(MeshPart(vertices, faces, vertex_normals(vertices, faces),
                                  color=colors.get(prim.material, WHITE),
                                  name=str(geometry.id)))
        return parts

    def geometry(self, geometry_id: str) -> Any:
        """The ``<geometry>`` whose id is ``geometry_id`` (``#`` allowed in front)."""
        found = self.dae.geometries.get(geometry_id.lstrip("#"))
        if found is None:
            raise ValueError(f"it has no geometry {geometry_id!r}")
        return found

    def node_model(self, refs: tuple[str, ...]) -> ModelAsset:
        """The geometry the nodes ``refs`` name hold themselves (not their children's),
        placed relative to the first node's position and rotation, Z up, metres."""
        import collada

        indices = [self.find_node(ref) for ref in refs]
        for i in indices:
            if i in self.bad_nodes:
                raise ValueError(f"node '{self.name(i)}' cannot be used: {self.bad_nodes[i]}")
        base = np.linalg.inv(decompose(self.to_z_up(self.world[indices[0]])).unscaled())
        parts = []
        for i in indices:
            relative = base @ self.to_z_up(self.world[i])
            unit = np.eye(4)
            unit[:3, :3] = self.axes * self.meter
            for child in self.nodes[i].children:
                if isinstance(child, collada.scene.GeometryNode):
                    parts += [_placed(p, relative @ unit) for p in
                              self.geometry_parts(child.geometry, child.materials)]
        if not parts:
            raise ValueError(f"nodes {list(refs)} hold no triangles")
        return ModelAsset(Path(f"{self.path}#{json.dumps(list(refs))}"), tuple(parts))

    def mesh_model(self, ref: str) -> ModelAsset:
        """The geometry ``ref`` (its id) in its own space, Z up, metres."""
        unit = np.eye(4)
        unit[:3, :3] = self.axes * self.meter
        parts = tuple(_placed(p, unit) for p in self.geometry_parts(self.geometry(ref)))
        if not parts:
            raise ValueError(f"geometry {ref!r} holds no triangles")
        return ModelAsset(Path(f"{self.path}#mesh{json.dumps([ref])}"), parts)


def _placed(part: MeshPart, matrix: np.ndarray) -> MeshPart:
    """``part`` moved by ``matrix`` (already the engine's axes)."""
    linear = matrix[:3, :3]
    vertices = part.vertices @ linear.T + matrix[:3, 3]
    faces = part.faces if np.linalg.det(linear) >= 0 else part.faces[:, ::-1]
    return MeshPart(vertices, faces, vertex_normals(vertices, faces), part.uv, part.colors,
                    part.color, part.texture, part.name)


built_in_loader("document", ".dae")(ColladaDocument.read)
