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
import time as _time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine.assets import AssetError, Assets, SkinnedModel
from engine.assets.skinned import AVATAR_AXES
from engine.render import glsl, math3d, meshes
from engine.render.camera import CameraView, Eye
from engine.render.hud import Hud
from engine.render.lights import (
    DEFAULT_AMBIENT,
    DEFAULT_LIGHT,
    KIND_CODES,
    LightInfo,
    shadow_matrix,
)
from engine.render.materials import checker_image
from engine.render.postprocess import PostChain, PostPass
from engine.render.shaders import ShaderLibrary, ShaderManager, UniformValue, write_uniform
from engine.render.skinning import Skinning

log = logging.getLogger("colosseum.render")

#: Per-instance floats: model matrix 16, colour 4, flags 4 (shadower, shadowed, -, -).
INSTANCE_FLOATS = 24
_INSTANCE_FORMAT = "16f 4f 4f/i"
_INSTANCE_ATTRS = ("i_model", "i_color", "i_flags")
_PLACEHOLDER = "<placeholder>"
_WHITE = "<white>"


@dataclass(slots=True)
class _GpuMesh:
    vbo: Any
    ibo: Any
    radius: float  # bounding radius about the local origin
    is_plane: bool
    closed: bool  # a closed primitive: back faces can be culled


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
    key: tuple[str, str, str | None, bool]
    start: int
    stop: int
    buffer: Any = None
    vaos: dict[int, Any] = field(default_factory=dict)


@dataclass(slots=True)
class FrameStats:
    """What the last frame cost: draw calls by pass, instances, CPU milliseconds."""

    draw_calls: int = 0
    shadow_draw_calls: int = 0
    instances: int = 0
    batches: int = 0
    frame_ms: float = 0.0


class Renderer:
    """Draws objects into a render target (see :mod:`engine.render.context`)."""

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
        self._lit_programs: dict[tuple[tuple[int, ...], int], Any] = {}
        self._depth = self.ctx.program(vertex_shader=glsl.DEPTH_VERTEX,
                                       fragment_shader=glsl.DEPTH_FRAGMENT)
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
        self._shadow_size = int(shadow_size)
        self._shadow_tex = self.ctx.depth_texture((self._shadow_size,) * 2)
        self._shadow_tex.compare_func = "<="
        self._shadow_tex.filter = (self.ctx.LINEAR, self.ctx.LINEAR)
        self._shadow_tex.repeat_x = self._shadow_tex.repeat_y = False
        self._shadow_fbo = self.ctx.framebuffer(depth_attachment=self._shadow_tex)
        self._scene_size: tuple[int, int] | None = None
        self._scene_tex: Any = None
        self._scene_depth: Any = None
        self._scene_fbo: Any = None
        self._texture_for(_WHITE)
        self._skinning = Skinning(self.ctx)
        self._skinned: dict[int, list[str]] = {}  # object -> the skin groups it is in
        self._group_keys: dict[str, int] = {}  # skin group -> its internal object key
        self._group_parts: dict[str, _Part] = {}  # skin group -> the part that draws it
        self._part_mesh: list[str] = []
        self._skinned_parts = np.zeros(0, np.int64)  # part indices drawing skin groups

    @property
    def instancing(self) -> bool:
        """False draws every part with its own draw call (the benchmark's reference)."""
        return self._instancing

    @instancing.setter
    def instancing(self, value: bool) -> None:
        self._instancing = bool(value)
        self._dirty = True

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
                mesh = self._mesh_for_shape(shape)
            except meshes.ModelError as exc:
                self._error(f"object {key}: {exc}")
                continue
            local = math3d.compose(shape.offset, shape.rotation, scale)
            parts.append(_Part(row, mesh, texture, visual.shader_state, local, color,
                               visual.shadower and not self._meshes[mesh].is_plane,
                               visual.shadowed, visual.overlay))
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

    def _mesh_for_shape(self, shape: Any) -> str:
        if shape.kind in ("mesh", "hull"):
            if shape.vertices is None or shape.faces is None:
                raise meshes.ModelError(f"{shape.kind} shape without vertices and faces")
            digest = hashlib.sha1(np.ascontiguousarray(shape.vertices, np.float64).tobytes()
                                  + np.ascontiguousarray(shape.faces, np.int64).tobytes())
            key = f"mesh:{digest.hexdigest()}"
            return self._mesh_for_shape_key(
                key, lambda: meshes.mesh_from_arrays(shape.vertices, shape.faces))
        key = f"{shape.kind}:{tuple(round(float(s), 6) for s in shape.size)}"
        return self._mesh_for_shape_key(key, lambda: meshes.primitive(shape.kind, shape.size))

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
        self._shadow_fbo.use()  # Mesa captures nothing without a complete framebuffer bound
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
            for vao in batch.vaos.values():
                vao.release()
            if batch.buffer is not None:
                batch.buffer.release()
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
                self._batches.append(_Batch(key, i, i + 1))
        for batch in self._batches:
            batch.buffer = self.ctx.buffer(
                reserve=(batch.stop - batch.start) * INSTANCE_FLOATS * 4, dynamic=True)
        self._dirty = False

    def _lit(self, lights: list[LightInfo], shadow_index: int) -> Any:
        """The default material's program, specialised for this set of lights."""
        kinds = tuple(KIND_CODES.get(light.kind, 0) for light in lights[:glsl.MAX_LIGHTS])
        key = (kinds, shadow_index)
        program = self._lit_programs.get(key)
        if program is None:
            program = self.ctx.program(vertex_shader=glsl.LIT_VERTEX,
                                       fragment_shader=glsl.lit_fragment(*key))
            self._lit_programs[key] = program
        return program

    def _cull(self, batch: _Batch) -> None:
        """Cull back faces of closed primitives (half the triangles); model files may be open
        meshes and stay two-sided."""
        if self._meshes[batch.key[0]].closed:
            self.ctx.enable(self.ctx.CULL_FACE)
        else:
            self.ctx.disable(self.ctx.CULL_FACE)

    def _vao(self, batch: _Batch, program: Any) -> Any:
        vao = batch.vaos.get(program.glo)
        if vao is None:
            mesh = self._meshes[batch.key[0]]
            vao = self.ctx.vertex_array(
                program,
                [(mesh.vbo, meshes.VERTEX_FORMAT, *meshes.VERTEX_ATTRIBUTES),
                 (batch.buffer, _INSTANCE_FORMAT, *_INSTANCE_ATTRS)],
                index_buffer=mesh.ibo, index_element_size=4, skip_errors=True)
            batch.vaos[program.glo] = vao
        return vao

    def _upload_instances(self) -> np.ndarray:
        """Write every part's instance data; returns world matrices ``(P, 4, 4)``.

        Instances of a batch are sorted near to far from the camera so the depth test rejects
        hidden fragments before they are shaded (a large saving on a CPU rasteriser).
        """
        rows = self._part_obj
        world = math3d.compose(self._pos[rows], self._quat[rows]) @ self._part_local
        inst = np.empty((len(rows), INSTANCE_FLOATS), np.float32)
        inst[:, :16] = world.transpose(0, 2, 1).reshape(len(rows), 16)
        inst[:, 16:] = self._part_extra
        distance = np.linalg.norm(world[:, :3, 3] - self.camera.position, axis=1)
        for batch in self._batches:
            chunk = inst[batch.start:batch.stop]
            if len(chunk) > 1:
                chunk = chunk[np.argsort(distance[batch.start:batch.stop], kind="stable")]
            batch.buffer.write(chunk.tobytes())
        return world

    def _shadow_light(self, lights: list[LightInfo]) -> int:
        return next((i for i, light in enumerate(lights) if light.shadows), -1)

    def _shadow_pass(self, light: LightInfo, world: np.ndarray) -> np.ndarray | None:
        casts = self._part_casts
        if not casts.any():
            return None
        centres = world[casts, :3, 3]
        scales = np.linalg.norm(world[casts, :3, :3], axis=1).max(axis=1)
        radii = self._part_radius[casts] * scales
        lo = (centres - radii[:, None]).min(axis=0)
        hi = (centres + radii[:, None]).max(axis=0)
        centre = 0.5 * (lo + hi)
        radius = float(np.max(np.linalg.norm(centres - centre, axis=1) + radii))
        light_vp = shadow_matrix(light, centre, radius)
        self._shadow_fbo.use()
        self._shadow_fbo.viewport = (0, 0, self._shadow_size, self._shadow_size)
        self._shadow_fbo.clear(depth=1.0)
        self.ctx.enable(self.ctx.DEPTH_TEST)
        self.ctx.polygon_offset = (2.0, 4.0)
        write_uniform(self._depth, "u_light_vp", _gl(light_vp))
        for batch in self._batches:
            if not casts[batch.start:batch.stop].any():
                continue
            self._cull(batch)
            self._vao(batch, self._depth).render(instances=batch.stop - batch.start)
            self.stats.shadow_draw_calls += 1
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
        size = tuple(self.target.size)
        self._ensure_scene_targets(size)  # type: ignore[arg-type]
        world = self._upload_instances()
        lights = self.lights or [DEFAULT_LIGHT]
        shadow_index = self._shadow_light(lights)
        light_vp = None
        if shadow_index >= 0 and len(world):
            light_vp = self._shadow_pass(lights[shadow_index], world)
        fbo = self._scene_fbo
        fbo.use()
        fbo.viewport = (0, 0, *size)
        fbo.clear(*self.background, 1.0, depth=1.0)
        self.ctx.enable(self.ctx.DEPTH_TEST)
        self._shadow_tex.use(glsl.TEXTURE_UNITS["u_shadow_map"])
        lit = self._lit(lights, shadow_index if light_vp is not None else -1)
        for eye in self.camera.eyes(*size):
            fbo.viewport = eye.viewport
            configured: set[int] = set()
            for batch in self._batches:
                if batch.key[3]:
                    self._begin_overlay()
                program = lit
                compiled = self.shaders.state(batch.key[2]) if batch.key[2] else None
                if compiled is not None:
                    program = compiled.program
                    self.shaders.apply(compiled)
                if program.glo not in configured:
                    self._frame_uniforms(program, eye, lights, shadow_index, light_vp)
                    configured.add(program.glo)
                self._textures[batch.key[1]].use(glsl.TEXTURE_UNITS["u_texture"])
                self._cull(batch)
                vao = self._vao(batch, program)
                self.stats.instances += batch.stop - batch.start
                if compiled is not None and compiled.per_object:
                    self._draw_per_object(program, vao, eye, world[batch.start:batch.stop])
                    continue
                vao.render(instances=batch.stop - batch.start)
                self.stats.draw_calls += 1
            self.ctx.enable(self.ctx.DEPTH_TEST)
            self.ctx.disable(self.ctx.BLEND)
        self.ctx.disable(self.ctx.CULL_FACE)
        self.stats.batches = len(self._batches)
        out = self.post.run(self._scene_tex, self._scene_depth, size, self.time) \
            if self.post.active() else None
        self.ctx.copy_framebuffer(self.target.fbo, out or self._scene_fbo)
        self.hud.draw(self.target.fbo, size)  # type: ignore[arg-type]
        self.target.present()
        self.stats.frame_ms = (_time.perf_counter() - start) * 1000.0

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
            for vao in batch.vaos.values():
                vao.release()
            if batch.buffer is not None:
                batch.buffer.release()
        for key, mesh in self._meshes.items():
            if key not in self._skinning.groups:  # skin groups' buffers are the skinning's
                mesh.vbo.release()
                mesh.ibo.release()
        self._skinning.release()
        for tex in self._textures.values():
            tex.release()
        for obj in (self._scene_fbo, self._scene_tex, self._scene_depth, self._shadow_fbo,
                    self._shadow_tex, self._depth, *self._lit_programs.values()):
            if obj is not None:
                obj.release()
        self.post.release()
        self.shaders.release()
        self.hud.release()


def _gl(matrix: np.ndarray) -> tuple[float, ...]:
    """A 4x4 matrix in GLSL's column-major order."""
    return tuple(np.asarray(matrix, dtype=np.float64).T.reshape(16))


def _write_array(program: Any, name: str, values: np.ndarray) -> None:
    member = program.get(name, None)
    if member is None:
        return
    dtype = np.int32 if values.dtype.kind == "i" else np.float32
    member.write(np.ascontiguousarray(values[: member.array_length], dtype=dtype).tobytes())
