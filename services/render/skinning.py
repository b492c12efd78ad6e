"""Linear-blend skinning on the GPU, by transform feedback, so every other program —
the default material, the shadow pass, an author's shaders, fixed-function-era ones —
draws skinned meshes unchanged.

All avatars showing one part of one model form a :class:`SkinGroup`. Each frame one
instanced transform-feedback draw skins the part for all of them at once: every vertex is
moved by the weighted sum of its joints' matrices (read from one float texture holding every
avatar's palette, three texels a joint) and by its avatar's model matrix, and written in
the renderer's ordinary vertex layout. The renderer then draws that buffer as one mesh
(placed at the group's centre, so shadow fitting and culling see where the avatars are).
:func:`engine.animation.skinning.skin` is the same arithmetic on the CPU.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from engine.assets.skinned import SkinnedModel, SkinnedPart
from services.render import meshes

#: Texels per row of the palette texture (a multiple of 3: a joint never straddles rows).
PALETTE_WIDTH = 768

SKIN_VERTEX = """
#version 330
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
in vec4 in_color;
in vec4 in_joints;
in vec4 in_weights;
in mat4 i_model;
in vec4 i_color;
in float i_palette;
uniform sampler2D u_palette;
out vec3 o_position;
out vec3 o_normal;
out vec2 o_uv;
out vec4 o_color;

// the three rows of joint ``joint``'s 3x4 matrix, weighted, added to r0..r2
void add_joint(float joint, float weight, inout vec4 r0, inout vec4 r1, inout vec4 r2) {
    int texel = (int(i_palette + 0.5) + int(joint + 0.5)) * 3;
    ivec2 at = ivec2(texel % %(width)d, texel / %(width)d);
    r0 += weight * texelFetch(u_palette, at, 0);
    r1 += weight * texelFetch(u_palette, at + ivec2(1, 0), 0);
    r2 += weight * texelFetch(u_palette, at + ivec2(2, 0), 0);
}

// normals go through the cofactor matrix: the inverse transpose, scaled
vec3 cofactor(vec3 c0, vec3 c1, vec3 c2, vec3 n) {
    return cross(c1, c2) * n.x + cross(c2, c0) * n.y + cross(c0, c1) * n.z;
}

void main() {
    vec3 p = in_position;
    vec3 n = in_normal;
    if (i_palette >= 0.0) {  // without a pose yet: the bind pose
        vec4 r0 = vec4(0.0), r1 = vec4(0.0), r2 = vec4(0.0);
        add_joint(in_joints.x, in_weights.x, r0, r1, r2);
        add_joint(in_joints.y, in_weights.y, r0, r1, r2);
        add_joint(in_joints.z, in_weights.z, r0, r1, r2);
        add_joint(in_joints.w, in_weights.w, r0, r1, r2);
        p = vec3(dot(r0, vec4(in_position, 1.0)), dot(r1, vec4(in_position, 1.0)),
                 dot(r2, vec4(in_position, 1.0)));
        n = cofactor(vec3(r0.x, r1.x, r2.x), vec3(r0.y, r1.y, r2.y), vec3(r0.z, r1.z, r2.z), n);
    }
    o_position = (i_model * vec4(p, 1.0)).xyz;
    mat3 m = mat3(i_model);
    n = cofactor(m[0], m[1], m[2], n);
    float len = length(n);
    o_normal = len > 0.0 ? n / len : vec3(0.0, 0.0, 1.0);
    o_uv = in_uv;
    o_color = in_color * i_color;
}
""".replace("%(width)d", str(PALETTE_WIDTH))

_SKIN_FORMAT = "4f 4f"
_SKIN_ATTRS = ("in_joints", "in_weights")
_INSTANCE_FORMAT = "16f 4f 1f/i"
_INSTANCE_ATTRS = ("i_model", "i_color", "i_palette")
_INSTANCE_FLOATS = 21


@dataclass(slots=True)
class _Member:
    key: int
    row: int  # the avatar's row in the renderer's pose arrays
    local: np.ndarray  # scale and the glTF-to-engine axes
    color: tuple[float, float, float, float]


@dataclass(slots=True)
class SkinGroup:
    """One model part drawn for several avatars: its bind-pose buffers and the skinned
    output the renderer draws (``mesh_key`` in its mesh table)."""

    mesh_key: str
    part: SkinnedPart
    radius: float  # of the bind pose about the model origin (model units)
    source: Any
    skin: Any
    members: list[_Member] = field(default_factory=list)
    instances: Any = None
    output: Any = None
    indices: Any = None
    vao: Any = None
    capacity: int = 0

    @property
    def vertex_count(self) -> int:
        return len(self.part.vertices)


class Skinning:
    """The renderer's skinned meshes: groups by model part, the palette texture, the
    transform-feedback program."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self.program = ctx.program(vertex_shader=SKIN_VERTEX,
                                   varyings=["o_position", "o_normal", "o_uv", "o_color"])
        self.groups: dict[str, SkinGroup] = {}
        self._palette: Any = None
        self._palette_rows = 0
        self.palettes = np.zeros((0, 3, 4), np.float32)
        self.offsets: dict[int, int] = {}
        self.palette_version = 0
        self._uploaded_version = -1

    # -- membership ------------------------------------------------------------------
    def attach(self, key: int, row: int, model: SkinnedModel, local: np.ndarray,
               color: tuple[float, float, float, float], variant: str) -> list[str]:
        """Draw ``model`` for object ``key`` (at pose row ``row``); returns the mesh keys
        of its parts' groups (``variant`` separates groups drawn differently)."""
        keys = []
        for i, part in enumerate(model.parts):
            mesh_key = f"skin:{model.path}#{i}|{variant}"
            group = self.groups.get(mesh_key)
            if group is None:
                group = self._group(mesh_key, part)
                self.groups[mesh_key] = group
            tint = tuple(a * b for a, b in zip(color, part.color, strict=True))
            group.members.append(_Member(key, row, local, tint))
            keys.append(mesh_key)
        return keys

    def detach(self, key: int) -> None:
        for group in self.groups.values():
            group.members = [m for m in group.members if m.key != key]

    def _group(self, mesh_key: str, part: SkinnedPart) -> SkinGroup:
        data = meshes.from_part(part)  # type: ignore[arg-type]
        skin = np.concatenate([part.joints.astype(np.float32), part.weights.astype(np.float32)],
                              axis=1)
        radius = float(np.max(np.linalg.norm(part.vertices, axis=1))) if len(
            part.vertices) else 0.0
        return SkinGroup(mesh_key, part, radius,
                         self.ctx.buffer(np.ascontiguousarray(data.vertices).tobytes()),
                         self.ctx.buffer(np.ascontiguousarray(skin).tobytes()))

    def resize(self, group: SkinGroup) -> bool:
        """Make the group's buffers fit its members; True when they were remade (the
        renderer must rebuild what draws them)."""
        n = max(len(group.members), 1)
        if group.output is not None and n == group.capacity:
            return False
        for obj in (group.vao, group.instances, group.output, group.indices):
            if obj is not None:
                obj.release()
        verts = group.vertex_count
        group.instances = self.ctx.buffer(reserve=n * _INSTANCE_FLOATS * 4, dynamic=True)
        group.output = self.ctx.buffer(reserve=n * verts * meshes.VERTEX_FLOATS * 4)
        faces = np.asarray(group.part.faces, np.uint32).reshape(-1)
        tiled = (faces[None, :] + (np.arange(n, dtype=np.uint32) * verts)[:, None]).reshape(-1)
        group.indices = self.ctx.buffer(tiled.tobytes())
        group.vao = self.ctx.vertex_array(
            self.program,
            [(group.source, meshes.VERTEX_FORMAT, *meshes.VERTEX_ATTRIBUTES),
             (group.skin, _SKIN_FORMAT, *_SKIN_ATTRS),
             (group.instances, _INSTANCE_FORMAT, *_INSTANCE_ATTRS)],
            skip_errors=True)
        group.capacity = n
        return True

    # -- per frame -------------------------------------------------------------------
    def set_palettes(self, palettes: np.ndarray, offsets: dict[int, int]) -> None:
        """Every avatar's joint matrices ``(J, 3, 4)`` (rows of 3x4 affine matrices) and
        where each avatar's block starts."""
        self.palettes = np.ascontiguousarray(palettes, np.float32).reshape(-1, 3, 4)
        self.offsets = offsets
        self.palette_version += 1

    def _upload_palettes(self) -> None:
        if self._uploaded_version == self.palette_version:
            return
        texels = self.palettes.reshape(-1, 4)
        rows = max(1, -(-len(texels) // PALETTE_WIDTH))
        if self._palette is None or rows > self._palette_rows:
            if self._palette is not None:
                self._palette.release()
            self._palette_rows = max(rows, 2 * self._palette_rows)
            self._palette = self.ctx.texture((PALETTE_WIDTH, self._palette_rows), 4,
                                             dtype="f4")
            self._palette.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        padded = np.zeros((rows * PALETTE_WIDTH, 4), np.float32)
        padded[:len(texels)] = texels
        self._palette.write(padded.tobytes(), viewport=(0, 0, PALETTE_WIDTH, rows))
        self._uploaded_version = self.palette_version

    def update(self, group: SkinGroup, position: np.ndarray, orientation: np.ndarray
               ) -> tuple[np.ndarray, float]:
        """Skin the group for its members at these poses (rows of the renderer's arrays);
        returns the centre its output is relative to and its radius about it."""
        from services.render.math3d import compose

        members = group.members
        rows = np.array([m.row for m in members], np.int64)
        world = compose(position[rows], orientation[rows]) @ np.array([m.local for m in members])
        scale = np.linalg.norm(world[:, :3, :3], axis=1).max(axis=1)
        lo = (world[:, :3, 3] - (group.radius * scale)[:, None]).min(axis=0)
        hi = (world[:, :3, 3] + (group.radius * scale)[:, None]).max(axis=0)
        centre = 0.5 * (lo + hi)
        radius = float(np.max(np.linalg.norm(world[:, :3, 3] - centre, axis=1)
                              + group.radius * scale))
        world[:, :3, 3] -= centre
        inst = np.empty((len(members), _INSTANCE_FLOATS), np.float32)
        inst[:, :16] = world.transpose(0, 2, 1).reshape(len(members), 16)
        inst[:, 16:20] = [m.color for m in members]
        inst[:, 20] = [self.offsets.get(m.key, -1) for m in members]
        group.instances.write(inst.tobytes())
        self._upload_palettes()
        self._palette.use(2)
        self.program["u_palette"].value = 2
        group.vao.transform(group.output, mode=self.ctx.POINTS, vertices=group.vertex_count,
                            instances=len(members))
        return centre, radius

    def release(self) -> None:
        for group in self.groups.values():
            for obj in (group.vao, group.instances, group.output, group.indices, group.source,
                        group.skin):
                if obj is not None:
                    obj.release()
        if self._palette is not None:
            self._palette.release()
        self.program.release()
