"""The renderer: objects (a Visual at a pose) drawn with instancing, shadows, user shader
states, a post-processing chain, a HUD line and screenshots.

It works on plain data so it can be driven without the engine (tests, tools): ``add`` an
object with a ``components.Visual``, move objects with ``set_poses`` (one numpy batch per
frame), set the camera and lights, and ``render``. Parts that share a mesh, texture and shader
state are drawn with one instanced draw call; colours and flags travel per instance.
"""

from __future__ import annotations

import hashlib
import logging
import math
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine.anomalies import ActiveAnomaly
from engine.assets import AssetError, Assets, SkinnedModel
from engine.assets.skinned import AVATAR_AXES
from services.render import glsl, math3d, meshes
from services.render.anomalies import adjust_eye, eye_geometry
from services.render.camera import CameraView, Eye
from services.render.context import libgl
from services.render.culling import (
    LOD_PIXELS,
    SHADOW_LEVEL,
    frustum_planes,
    in_frustum,
    lod_levels,
    pixels_per_unit,
    sphere_segments,
    world_radii,
)
from services.render.hud import Hud
from services.render.lights import DEFAULT_AMBIENT, DEFAULT_LIGHT, KIND_CODES, LightInfo
from services.render.materials import checker_image
from services.render.postprocess import PostChain, PostPass
from services.render.shaders import ShaderLibrary, ShaderManager, UniformValue, write_uniform
from services.render.shadows import ShadowMap
from services.render.skinning import Skinning

log = logging.getLogger("colosseum.render")

#: Per-instance floats: model matrix 16, colour 4, flags 4 (shadower, shadowed, -, -).
INSTANCE_FLOATS = 24
_INSTANCE_FORMAT = "16f 4f 4f/i"
_INSTANCE_ATTRS = ("i_model", "i_color", "i_flags")
_PLACEHOLDER = "<placeholder>"
_WHITE = "<white>"
_EYE4 = np.eye(4)
#: Primitives drawn as shared unit meshes scaled per instance.
_UNIT_KINDS = ("box", "sphere", "cylinder", "capsule")
#: The instance-buffer slot of the shadow pass (eyes use 0 and 1).
_SHADOW_SLOT = 2
#: The slot of both eyes drawn in one pass (each part's row read twice: glsl.LIT_VERTEX_STEREO).
_STEREO_SLOT = 3
#: GL_CLIP_DISTANCE0: the single stereo pass clips each eye at the middle of the target.
_CLIP_DISTANCE0 = 0x3000
#: The smallest share of the output's resolution the view may be drawn at.
MIN_RENDER_SCALE = 0.25


@dataclass(slots=True)
class _GpuMesh:
    vbo: Any
    ibo: Any
    radius: float  # bounding radius about the local origin
    is_plane: bool
    closed: bool  # a closed primitive: back faces can be culled
    #: Coarser versions of this mesh (levels 1, 2, ...), drawn when it looks small.
    lods: tuple[str, ...] = ()


@dataclass(slots=True)
class _Part:
    row: int  # the object's row in the pose arrays
    mesh: str
    texture: str
    state: str | None
    local: np.ndarray
    color: tuple[float, float, float, float]
    shadower: bool
    shadowed: bool
    overlay: bool = False


@dataclass(slots=True)
class _Batch:
    """Parts ``start:stop`` (in draw order) that share a mesh, texture, shader state and
    overlay flag: one instanced draw per level of detail and view."""

    key: tuple[str, str, str | None, bool]
    start: int
    stop: int
    levels: tuple[str, ...] = ()  # the mesh of each level of detail, finest first
    #: (level, slot) -> instance buffer; a slot is an eye (0, 1) or the shadow pass.
    buffers: dict[tuple[int, int], Any] = field(default_factory=dict)
    vaos: dict[tuple[int, int, int], Any] = field(default_factory=dict)

    def release(self) -> None:
        for vao in self.vaos.values():
            vao.release()
        for buffer in self.buffers.values():
            buffer.release()
        self.vaos.clear()
        self.buffers.clear()


@dataclass(slots=True)
class _Run:
    """One draw: ``parts`` (indices, in the order written) of a batch at a level of detail."""

    batch: _Batch
    level: int
    parts: np.ndarray


@dataclass(slots=True)
class _Posed:
    """The parts' world matrices, bounding radii and instance rows, and the object poses
    they were made from (rows in part order); ``version`` counts the frames any changed."""

    position: np.ndarray
    orientation: np.ndarray
    world: np.ndarray
    radii: np.ndarray
    inst: np.ndarray
    version: int = 0


@dataclass(slots=True)
class FrameStats:
    """What the last frame cost: draw calls by pass, instances drawn and left out, and
    milliseconds by stage (CPU time, unless :attr:`Renderer.profile` waits for the GPU at
    the end of each stage, which puts the GPU's time in its stage too)."""

    draw_calls: int = 0
    shadow_draw_calls: int = 0
    instances: int = 0
    #: Parts outside every eye's view frustum, not drawn (summed over eyes).
    culled: int = 0
    #: Parts whose shadow came from the cached map of resting casters.
    shadow_cached: int = 0
    #: Times the cached shadow map of resting casters was redrawn this frame (0 or 1).
    shadow_rebakes: int = 0
    batches: int = 0
    frame_ms: float = 0.0
    #: The render system bringing the renderer up to date with the world (visuals that
    #: came, went or changed; poses, camera, lights), before drawing.
    scene_ms: float = 0.0
    #: World matrices, culling, levels of detail and instance buffer writes.
    upload_ms: float = 0.0
    shadow_ms: float = 0.0
    #: The eyes' draw calls.
    draw_ms: float = 0.0
    #: CPU time of this thread inside the GL driver's draws and clears (ms): on a software
    #: rasteriser (llvmpipe) the vertex stage runs there, where a GPU would run it.
    driver_ms: float = 0.0
    post_ms: float = 0.0
    #: Copy to the screen, HUD and buffer swap.
    present_ms: float = 0.0


@dataclass(frozen=True, slots=True)
class _Frame:
    """What every pass of one frame draws with: the eyes, the lights and the shadow."""

    eyes: list[Any]
    lights: list[Any]
    shadow_index: int
    light_vp: Any
    single: bool  # both eyes in one instanced pass
    world: Any


class Renderer:
    """Draws objects into a render target (see :mod:`services.render.context`)."""

    def __init__(self, target: Any, root: str | Path = ".", shadow_size: int = 1024,
                 instancing: bool = True, assets: Assets | None = None) -> None:
        self.target = target
        self._instancing = instancing
        self.ctx = target.ctx
        self.root = Path(root)
        #: Where model and texture files come from (the run's shared cache).
        self.assets = assets if assets is not None else Assets(self.root)
        self.background = (0.55, 0.62, 0.72)
        self.ambient = DEFAULT_AMBIENT
        self.camera = CameraView()
        self.lights: list[LightInfo] = []
        self.errors: list[str] = []
        self.stats = FrameStats()
        self.time = 0.0
        self.shaders = ShaderManager(self.ctx, self.root)
        self.post = PostChain(self.ctx, self.root)
        self.hud = Hud(self.ctx)
        self._lit_programs: dict[tuple[tuple[int, ...], int, bool], Any] = {}
        self._depth = self.ctx.program(vertex_shader=glsl.DEPTH_VERTEX,
                                       fragment_shader=glsl.DEPTH_FRAGMENT)
        self._init_parts()
        self._shadows = ShadowMap(self.ctx, shadow_size)
        #: The visual anomalies to draw this frame, ramped (the render system sets them from
        #: the run's engine.anomalies.Anomalies).
        self.anomalies: list[ActiveAnomaly] = []
        #: Leave out what no eye can see (False draws everything: the test's reference).
        self.culling = True
        #: Draw the two eyes of a stereo view in one pass (False: one pass an eye, the
        #: benchmark's reference).
        self.single_pass = True
        #: Draw small-looking spheres, cylinders and capsules with fewer triangles.
        self.lod = True
        #: Wait for the GPU at the end of each stage, so FrameStats' stage times include
        #: the GPU's work (the benchmark's breakdown; slower, as nothing overlaps).
        self.profile = False
        #: Called between a frame drawn and finished on the GPU (``ctx.finish()``) and its
        #: swap: a swap barrier (None: swap at once, the GPU finishing on its own).
        self.before_present: Callable[[], None] | None = None
        self._init_targets()
        self._texture_for(_WHITE)
        self._skinning = Skinning(self.ctx)
        self._skinned: dict[int, list[str]] = {}  # object -> the skin groups it is in
        self._group_keys: dict[str, int] = {}  # skin group -> its internal object key
        self._group_parts: dict[str, _Part] = {}  # skin group -> the part that draws it
        self._part_mesh: list[str] = []
        self._skinned_parts = np.zeros(0, np.int64)  # part indices drawing skin groups

    def _init_parts(self) -> None:
        """The objects' parts and their per-part tables (filled by _rebuild)."""
        self._meshes: dict[str, _GpuMesh] = {}
        self._textures: dict[str, Any] = {}
        self._objects: dict[int, list[_Part]] = {}
        self._rows: dict[int, int] = {}
        self._free_rows: list[int] = []
        self._pos = np.zeros((0, 3))
        self._quat = np.zeros((0, 4))
        self._batches: list[_Batch] = []
        self._dirty = True
        self._pose_keys: np.ndarray | None = None
        self._pose_rows: np.ndarray | None = None
        self._warned_states: set[str] = set()
        self._rows_version = 0  # bumped when objects come and go; invalidates _pose_rows
        self._pose_rows_version = -1
        self._part_obj = np.zeros(0, np.int64)
        self._part_local = np.zeros((0, 4, 4))
        self._part_extra = np.zeros((0, 8), np.float32)
        self._part_radius = np.zeros(0)
        self._part_casts = np.zeros(0, bool)
        self._part_batch = np.zeros(0, np.int64)
        self._part_coarsest = np.zeros(0, np.int8)  # each part's coarsest level of detail
        self._posed: _Posed | None = None  # the parts' world matrices as last worked out
        #: Each eye slot's last draws, with what they were made from (see _eye_runs).
        self._eye_cache: dict[int, tuple[tuple, int, list[_Run]]] = {}

    def _init_targets(self) -> None:
        """The offscreen targets, made when a frame first needs them."""
        self._scene_size: tuple[int, int] | None = None
        self._scene_tex: Any = None
        self._scene_depth: Any = None
        self._scene_fbo: Any = None
        self._render_scale = 1.0
        self._scaled: tuple[Any, Any] | None = None  # the post chain's output when scaled
        self._upscale: tuple[Any, Any] | None = None  # program and vertex array

    @property
    def instancing(self) -> bool:
        """False draws every part with its own draw call (the benchmark's reference)."""
        return self._instancing

    @instancing.setter
    def instancing(self, value: bool) -> None:
        self._instancing = bool(value)
        self._dirty = True

    @property
    def render_scale(self) -> float:
        """The share of the output's resolution the view is drawn at (1: all of it; less
        draws fewer pixels, and the frame is scaled up, filtered, to the output; the HUD
        stays sharp). A software rasteriser's cost is mostly per pixel, so 0.75 draws
        about 0.56 of the pixels. Off (1) unless asked for: ``--render-scale``."""
        return self._render_scale

    @render_scale.setter
    def render_scale(self, value: float) -> None:
        value = float(value)
        if not MIN_RENDER_SCALE <= value <= 1.0:
            raise ValueError(f"render scale must be {MIN_RENDER_SCALE:g} to 1, got {value:g}")
        self._render_scale = value

    def view_size(self, size: tuple[int, int]) -> tuple[int, int]:
        """The size the view is drawn at for an output of ``size`` pixels."""
        if self._render_scale >= 1.0:
            return size
        return (max(1, round(size[0] * self._render_scale)),
                max(1, round(size[1] * self._render_scale)))

    @property
    def shadow_cache(self) -> bool:
        """Draw shadow casters that rest into a cached map once (False: every caster every
        frame, the benchmark's reference); see :mod:`services.render.shadows`."""
        return self._shadows.caching

    @shadow_cache.setter
    def shadow_cache(self, value: bool) -> None:
        self._shadows.caching = bool(value)
        self._shadows.reset(len(self._part_obj))

    # ------------------------------------------------------------------ objects
    def add(self, key: int, visual: Any, position: Any = (0.0, 0.0, 0.0),
            orientation: Any = (1.0, 0.0, 0.0, 0.0), skin: SkinnedModel | None = None) -> None:
        """Add (or replace) object ``key`` drawn as ``visual`` (a ``components.Visual``);
        with ``skin``, as that skinned model posed by :meth:`set_palettes`."""
        if key in self._objects:
            self.remove(key)
        row = self._new_row(key)
        self._pos[row] = position
        self._quat[row] = orientation
        if skin is not None:
            self._objects[key] = []
            if visual.visible:
                self._attach_skin(key, row, visual, skin)
        else:
            self._objects[key] = self._parts_for(key, row, visual) if visual.visible else []
        self._dirty = True

    def _new_row(self, key: int) -> int:
        row = self._free_rows.pop() if self._free_rows else len(self._rows)
        if row >= len(self._pos):
            grow = max(16, 2 * len(self._pos))
            self._pos = np.concatenate([self._pos, np.zeros((grow, 3))])
            self._quat = np.concatenate([self._quat, np.tile([1.0, 0, 0, 0], (grow, 1))])
        self._rows[key] = row
        self._rows_version += 1
        return row

    def remove(self, key: int) -> None:
        if key not in self._objects:
            return
        if self._skinned.pop(key, None) is not None:
            self._skinning.detach(key)
        del self._objects[key]
        self._free_rows.append(self._rows.pop(key))
        self._rows_version += 1
        self._dirty = True

    def __contains__(self, key: int) -> bool:
        return key in self._objects

    def pose(self, key: int) -> tuple[np.ndarray, np.ndarray]:
        """Where object ``key`` will be drawn: (position, orientation) copies."""
        row = self._rows[key]
        return self._pos[row].copy(), self._quat[row].copy()

    def set_pose(self, key: int, position: Any, orientation: Any) -> None:
        row = self._rows[key]
        self._pos[row] = position
        self._quat[row] = orientation

    def set_poses(self, keys: np.ndarray, positions: np.ndarray, orientations: np.ndarray
                  ) -> None:
        """Move many objects at once (unknown keys are ignored: bodies without a Visual)."""
        keys = np.asarray(keys)
        if (self._pose_keys is None or self._pose_rows_version != self._rows_version
                or len(keys) != len(self._pose_keys) or not np.array_equal(keys, self._pose_keys)):
            rows = np.array([self._rows.get(int(k), -1) for k in keys], dtype=np.int64)
            self._pose_keys, self._pose_rows = keys.copy(), rows
            self._pose_rows_version = self._rows_version
        rows = self._pose_rows
        assert rows is not None
        known = rows >= 0
        self._pos[rows[known]] = np.asarray(positions)[known]
        self._quat[rows[known]] = np.asarray(orientations)[known]

    def _parts_for(self, key: int, row: int, visual: Any) -> list[_Part]:
        scale = np.asarray(visual.scale, dtype=np.float64)
        color = tuple(float(c) for c in visual.color)
        texture = _WHITE
        if visual.texture:
            texture = visual.texture
        parts = []
        for shape in visual.shapes:
            try:
                pieces = self._meshes_for_shape(shape, visual.shader_state is None)
            except meshes.ModelError as exc:
                self._error(f"object {key}: {exc}")
                continue
            frame = math3d.compose(shape.offset, shape.rotation, scale)
            parts += [_Part(row, mesh, texture, visual.shader_state, frame @ piece, color,
                            visual.shadower and not self._meshes[mesh].is_plane,
                            visual.shadowed, visual.overlay) for mesh, piece in pieces]
        if visual.model:
            local = math3d.compose((0, 0, 0), (1, 0, 0, 0), scale)
            try:
                model = self.assets.model(visual.model, root=self.root)
            except AssetError as exc:
                self._told(exc, "drawing a placeholder box")
                self._mesh_for_shape_key("box:placeholder", lambda: meshes.box((1, 1, 1)))
                self._texture_for(_PLACEHOLDER)
                return parts + [_Part(row, "box:placeholder", _PLACEHOLDER, None, local,
                                      (1, 1, 1, 1), visual.shadower, visual.shadowed,
                                      visual.overlay)]
            for i, part in enumerate(model.parts):
                mkey = f"model:{model.path}#{i}"
                self._mesh_for_shape_key(mkey, lambda p=part: meshes.from_part(p))
                tex = texture
                if texture == _WHITE and part.texture is not None:
                    tex = f"{mkey}:texture"
                    if tex not in self._textures:
                        self._textures[tex] = self._upload_texture(part.texture)
                part_color = tuple(a * b for a, b in zip(color, part.color, strict=True))
                parts.append(_Part(row, mkey, tex, visual.shader_state, local, part_color,
                                   visual.shadower, visual.shadowed, visual.overlay))
        for part in parts:
            self._texture_for(part.texture)
        return parts

    def _meshes_for_shape(self, shape: Any, unit: bool) -> list[tuple[str, np.ndarray]]:
        """The meshes a shape is drawn with, each with the matrix placing it in the shape's
        frame. With ``unit`` (the default material, which normalises scaled normals)
        primitives are unit meshes scaled per instance, so objects of every size are one
        instanced batch per kind; an author's shader gets meshes of the shape's own size,
        as it always has."""
        if shape.kind in ("mesh", "hull"):
            if shape.vertices is None or shape.faces is None:
                raise meshes.ModelError(f"{shape.kind} shape without vertices and faces")
            digest = hashlib.sha1(np.ascontiguousarray(shape.vertices, np.float64).tobytes()
                                  + np.ascontiguousarray(shape.faces, np.int64).tobytes())
            key = f"mesh:{digest.hexdigest()}"
            return [(self._mesh_for_shape_key(
                key, lambda: meshes.mesh_from_arrays(shape.vertices, shape.faces)), _EYE4)]
        size = tuple(float(s) for s in shape.size)
        if unit and shape.kind in _UNIT_KINDS and size and all(0.0 < s < math.inf
                                                              for s in size):
            return self._unit_pieces(shape.kind, size)
        key = f"{shape.kind}:{tuple(round(s, 6) for s in size)}"
        return [(self._mesh_for_shape_key(key, lambda: meshes.primitive(shape.kind, size)),
                 _EYE4)]

    def _unit_pieces(self, kind: str, size: tuple[float, ...]) -> list[tuple[str, np.ndarray]]:
        """A primitive as unit meshes (with coarser levels of detail) and their placing
        matrices: a capsule is a cylinder between two spheres, so capsules of every
        proportion share the cylinders' and spheres' batches."""
        sphere = self._lod_meshes("sphere", lambda level: meshes.sphere(
            1.0, *sphere_segments(level)))
        if kind == "box":
            box = self._lod_meshes("box", lambda level: meshes.box((1.0, 1.0, 1.0)), 1)
            return [(box, np.diag([*(size if len(size) == 3 else (size[0],) * 3), 1.0]))]
        radius = size[0]
        if kind == "sphere":
            return [(sphere, np.diag([radius, radius, radius, 1.0]))]
        length = size[1] if len(size) > 1 else 1.0
        cylinder = self._lod_meshes("cylinder", lambda level: meshes.cylinder(
            1.0, 1.0, sphere_segments(level)[0]))
        pieces = [(cylinder, np.diag([radius, radius, length, 1.0]))]
        if kind == "capsule":
            pieces += [(sphere, math3d.compose((0.0, 0.0, end), (1.0, 0.0, 0.0, 0.0),
                                               (radius,) * 3))
                       for end in (-length / 2, length / 2)]
        return pieces

    def _lod_meshes(self, name: str, build: Any, levels: int = len(LOD_PIXELS) + 1) -> str:
        """Mesh ``unit:NAME`` and its coarser levels ``unit:NAME#1``...; returns the first."""
        keys = [f"unit:{name}"] + [f"unit:{name}#{level}" for level in range(1, levels)]
        for level, key in enumerate(keys):
            self._mesh_for_shape_key(key, lambda level=level: build(level))
        self._meshes[keys[0]].lods = tuple(keys[1:])
        return keys[0]

    def _mesh_for_shape_key(self, key: str, build: Any) -> str:
        if key not in self._meshes:
            data: meshes.MeshData = build()
            radius = float(np.max(np.linalg.norm(data.positions, axis=1))) if len(
                data.vertices) else 0.0
            self._meshes[key] = _GpuMesh(
                self.ctx.buffer(np.ascontiguousarray(data.vertices, np.float32).tobytes()),
                self.ctx.buffer(np.ascontiguousarray(data.indices, np.uint32).tobytes()),
                radius, data.name == "plane",
                data.name in ("box", "sphere", "capsule", "cylinder"))
        return key

    # ---------------------------------------------------------------- skinned
    def _attach_skin(self, key: int, row: int, visual: Any, model: SkinnedModel) -> None:
        """Object ``key`` joins the skin group of each part of ``model`` (one per way of
        drawing it); a group is drawn as one internal object at the avatars' centre."""
        local = math3d.compose((0, 0, 0), (1, 0, 0, 0), visual.scale) @ AVATAR_AXES
        variant = f"{visual.shader_state}|{visual.shadower:d}{visual.shadowed:d}|{visual.texture}"
        groups = self._skinning.attach(key, row, model, local, tuple(visual.color), variant)
        self._skinned[key] = groups
        for mesh_key, part in zip(groups, model.parts, strict=True):
            if mesh_key in self._group_keys:
                continue
            texture = visual.texture or _WHITE
            if visual.texture is None and part.texture is not None:
                texture = f"{mesh_key}:texture"
                if texture not in self._textures:
                    self._textures[texture] = self._upload_texture(part.texture)
            self._texture_for(texture)
            internal = -1 - len(self._group_keys)
            while internal in self._objects:
                internal -= 1
            self._group_keys[mesh_key] = internal
            self._group_parts[mesh_key] = _Part(self._new_row(internal), mesh_key, texture,
                                                visual.shader_state, np.eye(4), (1, 1, 1, 1),
                                                visual.shadower, visual.shadowed)
            self._objects[internal] = []  # drawn once its buffers fit (_prepare_skins)

    def set_palettes(self, palettes: np.ndarray, offsets: dict[int, int]) -> None:
        """Pose the skinned objects: every joint matrix ``(J, 3, 4)`` (the top rows of
        each 4x4) and the first palette entry of each object (an object without one is
        drawn in its bind pose)."""
        self._skinning.set_palettes(palettes, offsets)

    def _prepare_skins(self) -> None:
        """Fit each skin group's buffers to its members before batches are built."""
        for mesh_key, group in self._skinning.groups.items():
            internal = self._group_keys[mesh_key]
            drawn = bool(self._objects[internal])
            if drawn != bool(group.members):
                self._objects[internal] = [self._group_parts[mesh_key]] if group.members else []
                self._dirty = True
            if group.members and (self._skinning.resize(group) or mesh_key not in self._meshes):
                self._meshes[mesh_key] = _GpuMesh(group.output, group.indices, group.radius,
                                                  False, False)
                self._dirty = True

    def _skin_pass(self) -> None:
        """Skin every group for this frame's poses; place each group's object at its
        avatars' centre and size its bounds for shadow fitting."""
        self._shadows.fbo.use()  # Mesa captures nothing without a complete framebuffer bound
        for mesh_key, group in self._skinning.groups.items():
            if not group.members:
                continue
            centre, radius = self._skinning.update(group, self._pos, self._quat)
            self._pos[self._rows[self._group_keys[mesh_key]]] = centre
            self._meshes[mesh_key].radius = radius
        for index in self._skinned_parts.tolist():
            self._part_radius[index] = self._meshes[self._part_mesh[index]].radius

    # ---------------------------------------------------------------- textures
    def _upload_texture(self, rgba: np.ndarray, nearest: bool = False) -> Any:
        rgba = np.ascontiguousarray(np.flipud(rgba))  # image rows top-down; GL v=0 is bottom
        tex = self.ctx.texture((rgba.shape[1], rgba.shape[0]), 4, rgba.tobytes())
        if nearest:
            tex.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        else:
            tex.build_mipmaps()
            tex.filter = (self.ctx.LINEAR_MIPMAP_LINEAR, self.ctx.LINEAR)
        return tex

    def _texture_for(self, key: str) -> Any:
        tex = self._textures.get(key)
        if tex is not None:
            return tex
        if key == _WHITE:
            tex = self._upload_texture(np.full((1, 1, 4), 255, np.uint8), nearest=True)
        elif key == _PLACEHOLDER:
            tex = self._upload_texture(checker_image(), nearest=True)
        else:
            try:
                tex = self._upload_texture(self.assets.image(key, root=self.root).rgba)
            except AssetError as exc:
                self._told(exc, "drawing a checker placeholder")
                tex = self._upload_texture(checker_image(), nearest=True)
        self._textures[key] = tex
        return tex

    # ------------------------------------------------------------ shaders, post
    def load_shaders(self, library: ShaderLibrary) -> None:
        """Compile a scene's shader declarations (errors land in :attr:`errors`, not raised)."""
        self.shaders.load(library)
        self.errors.extend(self.shaders.errors)
        self._dirty = True

    def set_uniform(self, state_id: str, name: str, value: UniformValue) -> None:
        """Change a shader state's uniform at run time (the Lua API calls this)."""
        self.shaders.set_uniform(state_id, name, value)

    def set_post_passes(self, passes: list[PostPass]) -> None:
        self.post.set_passes(passes)
        self.errors.extend(self.post.errors)

    def enable_post(self, name: str, enabled: bool = True) -> None:
        self.post.enable(name, enabled)

    def set_post_uniform(self, name: str, uniform: str, value: UniformValue) -> None:
        self.post.set_uniform(name, uniform, value)

    def _error(self, message: str) -> None:
        self.errors.append(message)
        log.error("%s", message)

    def _told(self, error: AssetError, outcome: str) -> None:
        """An asset that failed: in :attr:`errors` always, logged unless the scene
        loader told it already (with its scene line)."""
        message = f"{error}; {outcome}"
        self.errors.append(message)
        if self.assets.mark_told(error):
            log.error("%s", message)

    # -------------------------------------------------------------- per frame
    def _rebuild(self) -> None:
        for batch in self._batches:
            batch.release()
        parts = [p for ps in self._objects.values() for p in ps]
        # planes last: they cover the screen, and drawing them after the objects lets the
        # depth test skip shading the floor hidden behind them; overlays after everything
        parts.sort(key=lambda p: (p.overlay, self._meshes[p.mesh].is_plane, p.mesh,
                                  p.texture, p.state or ""))
        n = len(parts)
        self._part_mesh = [p.mesh for p in parts]
        self._skinned_parts = np.array([i for i, p in enumerate(parts)
                                        if p.mesh in self._skinning.groups], np.int64)
        self._part_obj = np.array([p.row for p in parts], dtype=np.int64)
        self._part_local = np.array([p.local for p in parts]).reshape(n, 4, 4)
        extra = np.zeros((n, 8), np.float32)
        for i, p in enumerate(parts):
            extra[i, 0:4] = p.color
            extra[i, 4] = p.shadower
            extra[i, 5] = p.shadowed
        self._part_extra = extra
        self._part_radius = np.array([self._meshes[p.mesh].radius for p in parts]).reshape(n)
        self._part_casts = np.array([p.shadower for p in parts], dtype=bool).reshape(n)
        for state in {p.state for p in parts if p.state} - self._warned_states:
            if not self.shaders.has_state(state):
                self._warned_states.add(state)
                log.warning("unknown shader state %r; its objects use the default material", state)
        self._batches = []
        for i, p in enumerate(parts):
            key = (p.mesh, p.texture, p.state, p.overlay)
            if self._instancing and self._batches and self._batches[-1].key == key:
                self._batches[-1].stop = i + 1
            else:
                mesh = self._meshes[p.mesh]
                self._batches.append(_Batch(key, i, i + 1, (p.mesh, *mesh.lods)))
        self._part_batch = np.zeros(n, np.int64)
        self._part_coarsest = np.zeros(n, np.int8)
        for index, batch in enumerate(self._batches):
            self._part_batch[batch.start:batch.stop] = index
            self._part_coarsest[batch.start:batch.stop] = len(batch.levels) - 1
        self._shadows.reset(n)
        self._posed = None
        self._eye_cache.clear()
        self._dirty = False

    def _lit(self, lights: list[LightInfo], shadow_index: int, textured: bool,
             stereo: bool = False) -> Any:
        """The default material's program, specialised for this set of lights and for
        textured or plain objects; ``stereo``: both eyes in one pass."""
        kinds = tuple(KIND_CODES.get(light.kind, 0) for light in lights[:glsl.MAX_LIGHTS])
        key = (kinds, shadow_index, textured, stereo)
        program = self._lit_programs.get(key)
        if program is None:
            program = self.ctx.program(
                vertex_shader=glsl.LIT_VERTEX_STEREO if stereo else glsl.LIT_VERTEX,
                fragment_shader=glsl.lit_fragment(*key))
            self._lit_programs[key] = program
        return program

    def _face_culling(self, batch: _Batch) -> None:
        """Cull back faces of closed primitives (half the triangles); model files may be open
        meshes and stay two-sided."""
        if self._meshes[batch.key[0]].closed:
            self.ctx.enable(self.ctx.CULL_FACE)
        else:
            self.ctx.disable(self.ctx.CULL_FACE)

    def _vao(self, batch: _Batch, level: int, slot: int, program: Any) -> Any:
        """The vertex array drawing ``batch`` at a level of detail from one slot's
        instance buffer with ``program``."""
        vao = batch.vaos.get((level, slot, program.glo))
        if vao is None:
            mesh = self._meshes[batch.levels[level]]
            vao = self.ctx.vertex_array(
                program,
                [(mesh.vbo, meshes.VERTEX_FORMAT, *meshes.VERTEX_ATTRIBUTES),
                 (self._buffer(batch, level, slot), _INSTANCE_FORMAT, *_INSTANCE_ATTRS)],
                index_buffer=mesh.ibo, index_element_size=4, skip_errors=True)
            if slot == _STEREO_SLOT:
                _instance_divisor(vao, program, 2)
            batch.vaos[(level, slot, program.glo)] = vao
        return vao

    def _buffer(self, batch: _Batch, level: int, slot: int) -> Any:
        """A batch's instance buffer for one level and slot (room for all its parts)."""
        buffer = batch.buffers.get((level, slot))
        if buffer is None:
            buffer = batch.buffers[(level, slot)] = self.ctx.buffer(
                reserve=(batch.stop - batch.start) * INSTANCE_FLOATS * 4, dynamic=True)
        return buffer

    def _world(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every part's world matrix ``(P, 4, 4)``, world bounding radius and instance row
        ``(P, 24)``, straight from the pose arrays (no per-object Python). Parts whose
        object has not moved since the last frame keep what they had (most of a scene
        rests); skinned parts, whose bounds change with the pose, are always redone. The
        arrays are the renderer's own: read them, do not keep them."""
        rows = self._part_obj
        pos, quat = self._pos[rows], self._quat[rows]
        cache = self._posed
        if cache is None:
            parts = np.arange(len(rows))
            world = np.empty((len(rows), 4, 4))
            inst = np.empty((len(rows), INSTANCE_FLOATS), np.float32)
            inst[:, 16:] = self._part_extra
            cache = self._posed = _Posed(pos, quat, world, np.empty(len(rows)), inst)
        else:
            moved = np.any(pos != cache.position, axis=1) | np.any(quat != cache.orientation,
                                                                    axis=1)
            moved[self._skinned_parts] = True
            parts = np.flatnonzero(moved)
            cache.position, cache.orientation = pos, quat
        if len(parts):
            world = math3d.compose(pos[parts], quat[parts]) @ self._part_local[parts]
            cache.world[parts] = world
            cache.inst[parts, :16] = world.transpose(0, 2, 1).reshape(len(parts), 16)
            cache.radii[parts] = world_radii(world, self._part_radius[parts])
            cache.version += 1
        return cache.world, cache.radii, cache.inst

    def _upload(self, selected: np.ndarray, order_key: np.ndarray, level: np.ndarray,
                inst: np.ndarray, slot: int) -> list[_Run]:
        """Write the ``selected`` parts' instance rows into their batches' buffers of
        ``slot``, in ascending ``order_key`` within each batch and level of detail; returns
        the draws to make."""
        chosen = np.flatnonzero(selected)
        if not len(chosen):
            return []
        order = chosen[np.lexsort((order_key[chosen], level[chosen],
                                   self._part_batch[chosen]))]
        groups = self._part_batch[order] * 8 + level[order]
        cuts = np.flatnonzero(np.diff(groups)) + 1
        rows = inst[order]
        runs = []
        for start, stop in zip(np.r_[0, cuts].tolist(), np.r_[cuts, len(order)].tolist(),
                               strict=True):
            batch = self._batches[int(self._part_batch[order[start]])]
            lod = int(level[order[start]])
            self._buffer(batch, lod, slot).write(rows[start:stop].tobytes())
            runs.append(_Run(batch, lod, order[start:stop]))
        return runs

    def _eye_runs(self, eyes: list[Eye], slot: int, world: np.ndarray, radii: np.ndarray,
                  inst: np.ndarray) -> list[_Run]:
        """The draws of one eye, or of both eyes in one pass: the parts in a view frustum
        (all of them with :attr:`culling` off), each at its level of detail seen from the
        eyes' middle, near to far within a batch so the depth test rejects hidden
        fragments before they are shaded. Eyes that see what they saw last frame (the same
        view of parts that did not move) draw the same runs from the instance buffers as
        they are."""
        assert self._posed is not None
        key = (self._posed.version, *(e.view.tobytes() + e.proj.tobytes() for e in eyes),
               eyes[0].viewport, self.culling, self.lod)
        kept = self._eye_cache.get(slot)
        if kept is not None and kept[0] == key:
            self.stats.culled += kept[1]
            return kept[2]
        centres = world[:, :3, 3]
        visible = np.zeros(len(centres), bool) if self.culling else np.ones(len(centres), bool)
        for eye in eyes if self.culling else ():
            visible |= in_frustum(frustum_planes(eye.proj @ eye.view), centres, radii)
        middle = sum(e.position for e in eyes) / len(eyes)
        distance = np.linalg.norm(centres - middle, axis=1)
        first = eyes[0]
        levels = np.minimum(lod_levels(radii, distance, pixels_per_unit(first.proj,
                                                                         first.viewport[3])),
                            self._part_coarsest) if self.lod else np.zeros(len(radii), np.int8)
        culled = int(len(visible) - visible.sum())
        self.stats.culled += culled
        runs = self._upload(visible, distance, levels, inst, slot)
        self._eye_cache[slot] = (key, culled, runs)
        return runs

    def _single_pass(self, eyes: list[Eye]) -> bool:
        """Whether this frame's two eyes are drawn in one pass: side by side, alike in
        size, and every batch drawn by the engine's own material (an author's shader
        takes its matrices per eye)."""
        if not self.single_pass or len(eyes) != 2:
            return False
        (x0, y0, w0, h0), (x1, y1, w1, h1) = eyes[0].viewport, eyes[1].viewport
        if (w0, h0, y0) != (w1, h1, y1) or x1 != x0 + w0:
            return False
        return not any(batch.key[2] for batch in self._batches)

    def _stereo_uniforms(self, program: Any, eyes: list[Eye]) -> None:
        for name, values in (("u_eye_view", [e.view.T for e in eyes]),
                             ("u_eye_proj", [e.proj.T for e in eyes]),
                             ("u_eye_pos", [e.position for e in eyes])):
            member = program.get(name, None)
            if member is not None:
                member.write(np.ascontiguousarray(np.stack(values), dtype=np.float32).tobytes())

    def _shadow_light(self, lights: list[LightInfo]) -> int:
        return next((i for i, light in enumerate(lights) if light.shadows), -1)

    def _shadow_pass(self, light: LightInfo, world: np.ndarray, radii: np.ndarray,
                     inst: np.ndarray) -> np.ndarray | None:
        casts = self._part_casts
        if not casts.any():
            return None
        self.ctx.polygon_offset = (2.0, 4.0)
        unsorted = np.zeros(len(casts))
        level = np.minimum(self._part_coarsest, SHADOW_LEVEL)

        def draw(selected: np.ndarray, light_vp: np.ndarray) -> int:
            write_uniform(self._depth, "u_light_vp", _gl(light_vp))
            runs = self._upload(selected, unsorted, level, inst, _SHADOW_SLOT)
            for run in runs:
                self._face_culling(run.batch)
                driver = _time.thread_time()
                self._vao(run.batch, run.level, _SHADOW_SLOT, self._depth).render(
                    instances=len(run.parts))
                self.stats.driver_ms += (_time.thread_time() - driver) * 1e3
            return len(runs)

        deforming = np.zeros(len(casts), bool)
        deforming[self._skinned_parts] = True
        light_vp, frame = self._shadows.update(light, world, radii, casts, deforming, draw)
        self.stats.shadow_draw_calls += frame.draw_calls
        self.stats.shadow_cached = frame.cached
        self.stats.shadow_rebakes = int(frame.rebaked)
        self.ctx.polygon_offset = (0.0, 0.0)
        self.ctx.disable(self.ctx.CULL_FACE)
        return light_vp

    def _ensure_scene_targets(self, size: tuple[int, int]) -> None:
        if self._scene_size == size:
            return
        for obj in (self._scene_fbo, self._scene_tex, self._scene_depth):
            if obj is not None:
                obj.release()
        self._scene_tex = self.ctx.texture(size, 4)
        self._scene_tex.filter = (self.ctx.LINEAR, self.ctx.LINEAR)
        self._scene_tex.repeat_x = self._scene_tex.repeat_y = False
        self._scene_depth = self.ctx.depth_texture(size)
        self._scene_fbo = self.ctx.framebuffer(color_attachments=[self._scene_tex],
                                               depth_attachment=self._scene_depth)
        self._scene_size = size

    def frame_uniforms(self, eye: Eye, lights: list[LightInfo], shadow_index: int,
                       light_vp: np.ndarray | None) -> dict[str, Any]:
        """The values of :data:`glsl.ENGINE_UNIFORMS` for one eye (arrays as numpy arrays,
        matrices column-major), every one of them: the contract a user's shader relies on."""
        n = min(len(lights), glsl.MAX_LIGHTS)
        pad = glsl.MAX_LIGHTS
        kinds = np.zeros(pad, np.int32)
        pos, dirs, cols = np.zeros((pad, 3)), np.zeros((pad, 3)), np.zeros((pad, 3))
        cutoff = np.zeros(pad)
        for i, light in enumerate(lights[:n]):
            kinds[i] = KIND_CODES.get(light.kind, 0)
            pos[i], dirs[i] = light.position, light.direction
            cols[i] = np.asarray(light.color) * light.intensity
            cutoff[i] = np.cos(np.radians(light.cutoff))
        return {
            "u_view": _gl(eye.view), "u_proj": _gl(eye.proj),
            "u_camera_pos": tuple(float(x) for x in eye.position),
            "u_time": float(self.time), "u_ambient": tuple(self.ambient),
            "u_texture": glsl.TEXTURE_UNITS["u_texture"],
            "u_shadow_map": glsl.TEXTURE_UNITS["u_shadow_map"],
            "u_shadow_light": shadow_index if light_vp is not None else -1,
            "u_light_vp": _gl(light_vp if light_vp is not None else np.eye(4)),
            "u_light_count": n, "u_light_kind": kinds, "u_light_pos": pos,
            "u_light_dir": dirs, "u_light_color": cols, "u_light_cos_cutoff": cutoff,
        }

    def _frame_uniforms(self, program: Any, eye: Eye, lights: list[LightInfo], shadow_index: int,
                        light_vp: np.ndarray | None) -> None:
        for name, value in self.frame_uniforms(eye, lights, shadow_index, light_vp).items():
            if isinstance(value, np.ndarray):
                _write_array(program, name, value)
            else:
                write_uniform(program, name, value)
        w = write_uniform
        n = min(len(lights), glsl.MAX_LIGHTS)
        if program.get("c_LightSource[0].position", None) is not None:  # legacy GLSL
            for i, light in enumerate(lights[:n]):
                if light.kind == "directional":
                    d = -np.asarray(light.direction, dtype=np.float64)
                    p = eye.view @ np.append(d / (np.linalg.norm(d) or 1.0), 0.0)
                else:
                    p = eye.view @ np.append(np.asarray(light.position, np.float64), 1.0)
                c = (*(np.asarray(light.color) * light.intensity), 1.0)
                prefix = f"c_LightSource[{i}]."
                w(program, prefix + "position", tuple(p))
                w(program, prefix + "diffuse", c)
                w(program, prefix + "specular", c)
                w(program, prefix + "ambient", (*self.ambient, 1.0))
                w(program, prefix + "spotDirection",
                  tuple(eye.view[:3, :3] @ np.asarray(light.direction, np.float64)))
                w(program, prefix + "spotCutoff", light.cutoff if light.kind == "spot" else 180.0)

    def _begin_overlay(self) -> None:
        """Overlays (sorted last) are blended by their alpha and drawn over everything."""
        self.ctx.disable(self.ctx.DEPTH_TEST)
        self.ctx.enable(self.ctx.BLEND)
        self.ctx.blend_func = self.ctx.SRC_ALPHA, self.ctx.ONE_MINUS_SRC_ALPHA

    def _draw_per_object(self, program: Any, vao: Any, eye: Eye, world: np.ndarray) -> None:
        """One draw per object for shaders that take their matrices as uniforms."""
        view_proj = eye.proj @ eye.view
        for model in world:
            normal = np.linalg.inv(model[:3, :3]).T
            for name in ("mvp", "u_mvp"):
                write_uniform(program, name, _gl(view_proj @ model))
            for name in ("model", "u_model"):
                write_uniform(program, name, _gl(model))
            for name in ("normal_matrix", "u_normal_matrix"):
                write_uniform(program, name, tuple(normal.T.reshape(9)))
            vao.render(instances=1)
            self.stats.draw_calls += 1

    def render(self, dt: float | None = None) -> None:
        """Draw one frame into the target's framebuffer (and show it, for a window)."""
        start = _time.perf_counter()
        self.time += dt if dt is not None else 0.0
        self.stats = FrameStats()
        if self._skinning.groups:
            self._prepare_skins()
        if self._dirty:
            self._rebuild()
        if self._skinning.groups:
            self._skin_pass()
        output: tuple[int, int] = tuple(self.target.size)  # type: ignore[assignment]
        size = self.view_size(output)
        scaled = size != output
        world, radii, inst = self._world()
        screen_eyes = self.camera.eyes(*size)
        eyes = self._seen_eyes(screen_eyes)
        single = self._single_pass(eyes)
        if single:
            runs = [self._eye_runs(eyes, _STEREO_SLOT, world, radii, inst)]
        else:
            runs = [self._eye_runs([eye], slot, world, radii, inst)
                    for slot, eye in enumerate(eyes)]
        mark = self._stage("upload_ms", start)
        lights = self.lights or [DEFAULT_LIGHT]
        shadow_index = self._shadow_light(lights)
        light_vp = None
        if shadow_index >= 0 and len(world):
            light_vp = self._shadow_pass(lights[shadow_index], world, radii, inst)
        mark = self._stage("shadow_ms", mark)
        steps = self.post.steps(self.anomalies, [(eye_geometry(eye, size), eye.viewport)
                                                 for eye in screen_eyes], size)
        post = bool(steps)
        fbo = self._begin_scene(size, post or scaled)
        frame = _Frame(eyes, lights, shadow_index, light_vp, single, world)
        self._draw_eyes(fbo, frame, runs)
        mark = self._stage("draw_ms", mark)
        if post:
            self.post.run(steps, self._scene_tex, self._scene_depth, size, self.time,
                          self._scaled_output(size)[1] if scaled else self.target.fbo)
        if scaled:
            self._scale_up(self._scaled_output(size)[0] if post else self._scene_tex, output)
        mark = self._stage("post_ms", mark)
        self._present(output, post or scaled)
        end = self._stage("present_ms", mark)
        self.stats.frame_ms = (end - start) * 1000.0

    def _begin_scene(self, size: tuple[int, int], offscreen: bool) -> Any:
        """The framebuffer the 3D view is drawn into, cleared: the target's own, or the
        scene texture when post-processing or scaling reads it afterwards."""
        if offscreen:
            self._ensure_scene_targets(size)
        fbo = self._scene_fbo if offscreen else self.target.fbo
        fbo.use()
        fbo.viewport = (0, 0, *size)
        driver = _time.thread_time()
        fbo.clear(*self.background, 1.0, depth=1.0)
        self.stats.driver_ms += (_time.thread_time() - driver) * 1e3
        self.ctx.enable(self.ctx.DEPTH_TEST)
        self._shadows.texture.use(glsl.TEXTURE_UNITS["u_shadow_map"])
        return fbo

    def _draw_eyes(self, fbo: Any, frame: _Frame, runs: list[list[Any]]) -> None:
        """Every eye's runs of batches: one pass for both eyes (their viewports as one,
        each clipped at the middle) or one pass an eye."""
        eyes, single = frame.eyes, frame.single
        if single:
            x, y, w, h = eyes[0].viewport
            passes = [(_STEREO_SLOT, eyes[0], runs[0], (x, y, 2 * w, h))]
            self.ctx.enable_direct(_CLIP_DISTANCE0)
        else:
            passes = [(slot, eye, eye_runs, eye.viewport)
                      for slot, (eye, eye_runs) in enumerate(zip(eyes, runs, strict=True))]
        for slot, eye, eye_runs, viewport in passes:
            fbo.viewport = viewport
            configured: set[int] = set()
            for run in eye_runs:
                self._draw_run(run, slot, eye, frame, configured)
            self.ctx.enable(self.ctx.DEPTH_TEST)
            self.ctx.disable(self.ctx.BLEND)
        if single:
            self.ctx.disable_direct(_CLIP_DISTANCE0)
        self.ctx.disable(self.ctx.CULL_FACE)
        self.stats.batches = len(self._batches)

    def _draw_run(self, run: Any, slot: int, eye: Any, frame: _Frame,
                  configured: set[int]) -> None:
        """One run of a batch's parts, instanced (once an eye in a single stereo pass);
        a per-object shader draws them one at a time."""
        batch = run.batch
        if batch.key[3]:
            self._begin_overlay()
        shadowing = frame.shadow_index if frame.light_vp is not None else -1
        program = self._lit(frame.lights, shadowing, batch.key[1] != _WHITE, frame.single)
        compiled = self.shaders.state(batch.key[2]) if batch.key[2] else None
        if compiled is not None:
            program = compiled.program
            self.shaders.apply(compiled)
        if program.glo not in configured:
            self._frame_uniforms(program, eye, frame.lights, frame.shadow_index,
                                 frame.light_vp)
            if frame.single:
                self._stereo_uniforms(program, frame.eyes)
            configured.add(program.glo)
        self._textures[batch.key[1]].use(glsl.TEXTURE_UNITS["u_texture"])
        self._face_culling(batch)
        vao = self._vao(batch, run.level, slot, program)
        copies = 2 if frame.single else 1  # instances a part is drawn as
        self.stats.instances += copies * len(run.parts)
        if compiled is not None and compiled.per_object:
            self._draw_per_object(program, vao, eye, frame.world[run.parts])
            return
        driver = _time.thread_time()
        vao.render(instances=copies * len(run.parts))
        self.stats.driver_ms += (_time.thread_time() - driver) * 1e3
        self.stats.draw_calls += 1

    def _present(self, output: tuple[int, int], offscreen: bool) -> None:
        """The HUD drawn over the frame (a headset's on its own layer), then shown."""
        if hasattr(self.target, "frame_depth"):  # a headset's: hands the depth on
            self.target.frame_depth = self._scene_depth if offscreen else None
        hud_fbo = getattr(self.target, "hud_fbo", None)
        if hud_fbo is not None:  # a headset's HUD is its own (head-locked) layer
            hud_fbo.clear(0.0, 0.0, 0.0, 0.0)
            self.target.hud_shown = self.hud.draw(hud_fbo, self.target.hud_size)
        else:
            self.hud.draw(self.target.fbo, output)
        if self.before_present is not None:
            self.ctx.finish()
            self.before_present()
        self.target.present()

    def _scaled_output(self, size: tuple[int, int]) -> tuple[Any, Any]:
        """Where the post chain ends when the view is drawn smaller: a texture of the
        view's size (and its framebuffer), scaled up from there."""
        if self._scaled is None or tuple(self._scaled[0].size) != size:
            for obj in self._scaled or ():
                obj.release()
            texture = self.ctx.texture(size, 4)
            texture.filter = (self.ctx.LINEAR, self.ctx.LINEAR)
            texture.repeat_x = texture.repeat_y = False
            self._scaled = (texture, self.ctx.framebuffer(color_attachments=[texture]))
        return self._scaled

    def _scale_up(self, texture: Any, output: tuple[int, int]) -> None:
        """Draw the view, drawn smaller, over the whole output (bilinear)."""
        if self._upscale is None:
            program = self.ctx.program(vertex_shader=glsl.FULLSCREEN_VERTEX,
                                       fragment_shader=glsl.UPSCALE_FRAGMENT)
            self._upscale = (program, self.ctx.vertex_array(program, []))
        program, vao = self._upscale
        self.ctx.disable(self.ctx.DEPTH_TEST)
        self.target.fbo.use()
        self.target.fbo.viewport = (0, 0, *output)
        texture.use(0)
        write_uniform(program, "u_scene", 0)
        vao.render(vertices=3)

    def _seen_eyes(self, eyes: list[Eye]) -> list[Eye]:
        """The eyes as the perspective anomalies that are on show them (field of view, tilt,
        aspect); culling and drawing use these, the anomalies' passes the screen's."""
        for anomaly in self.anomalies:
            if anomaly.kind != "perspective":
                continue
            eyes = [adjust_eye(eye, anomaly.values)
                    if len(eyes) == 1 or anomaly.eye in ("both", ("left", "right")[i]) else eye
                    for i, eye in enumerate(eyes)]
        return eyes

    def _stage(self, name: str, since: float) -> float:
        """Record the milliseconds since ``since`` as stage ``name`` of this frame's stats
        (waiting for the GPU first when profiling); returns now."""
        if self.profile:
            self.ctx.finish()
        now = _time.perf_counter()
        setattr(self.stats, name, (now - since) * 1000.0)
        return now

    # ----------------------------------------------------------------- output
    def read_pixels(self) -> np.ndarray:
        """The last frame as ``(height, width, 3)`` uint8, first row at the top."""
        w, h = self.target.size
        data = self.target.fbo.read(viewport=(0, 0, w, h), components=3, alignment=1)
        return np.flipud(np.frombuffer(data, np.uint8).reshape(h, w, 3))

    def screenshot(self, path: str | Path) -> Path:
        """Save the last frame as a PNG (folders are created); returns the path."""
        from PIL import Image

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(self.read_pixels()).save(path, format="PNG")
        return path

    def release(self) -> None:
        """Free GPU objects (the context itself belongs to the target)."""
        for batch in self._batches:
            batch.release()
        for key, mesh in self._meshes.items():
            if key not in self._skinning.groups:  # skin groups' buffers are the skinning's
                mesh.vbo.release()
                mesh.ibo.release()
        self._skinning.release()
        for tex in self._textures.values():
            tex.release()
        self._shadows.release()
        for obj in (self._scene_fbo, self._scene_tex, self._scene_depth, self._depth,
                    *(self._scaled or ()), *(self._upscale or ()),
                    *self._lit_programs.values()):
            if obj is not None:
                obj.release()
        self.post.release()
        self.shaders.release()
        self.hud.release()


def _instance_divisor(vao: Any, program: Any, divisor: int) -> None:
    """Make every per-instance input of ``vao`` advance every ``divisor`` instances (the
    stereo pass draws each part twice from one row: glVertexAttribDivisor, which
    moderngl sets to 1 only)."""
    gl = libgl()
    gl.glBindVertexArray(vao.glo)
    for name in _INSTANCE_ATTRS:
        member = program.get(name, None)
        if member is None:
            continue
        columns = 4 if name == "i_model" else 1  # a mat4 takes four locations
        for location in range(member.location, member.location + columns):
            gl.glVertexAttribDivisor(location, divisor)
    gl.glBindVertexArray(0)


def _gl(matrix: np.ndarray) -> tuple[float, ...]:
    """A 4x4 matrix in GLSL's column-major order."""
    return tuple(np.asarray(matrix, dtype=np.float64).T.reshape(16))


def _write_array(program: Any, name: str, values: np.ndarray) -> None:
    member = program.get(name, None)
    if member is None:
        return
    dtype = np.int32 if values.dtype.kind == "i" else np.float32
    member.write(np.ascontiguousarray(values[: member.array_length], dtype=dtype).tobytes())
