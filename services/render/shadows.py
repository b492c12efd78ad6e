"""The shadow map of the one shadowed light, with the casters that rest drawn once.

Most of a scene does not move from frame to frame (walls, furniture, things asleep on a
shelf), but a shadow map drawn from scratch costs every caster every frame — on a CPU
rasteriser as much as the view itself. So casters that have not moved for
:data:`BAKE_AFTER` frames are drawn into a cached map; each frame starts from a copy of it
(a full-screen depth write) and draws only the casters that move. A cached caster that
moves, a change of light, or casters leaving the region the map covers redraw the cache at
once; casters that came to rest join it at most every :data:`REBAKE_EVERY` frames.

The region the map covers is kept while every caster stays inside it (and it has not
become much too large), so it does not wander with each moving body and invalidate the
cache.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from services.render import glsl
from services.render.lights import LightInfo, shadow_matrix

#: Frames a caster must stay still before it is drawn into the cached map.
BAKE_AFTER = 30
#: Casters that came to rest join the cached map at most this often (frames).
REBAKE_EVERY = 60
#: A covered region is refitted when the casters' own bound falls under this share of it.
SHRINK = 0.7

_COPY_DEPTH = """
#version 330
in vec2 v_uv;
uniform sampler2D u_depth;
void main() { gl_FragDepth = texture(u_depth, v_uv).r; }
"""

#: Draws the chosen casters (a mask over parts) into the bound framebuffer.
DrawCasters = Callable[[np.ndarray, np.ndarray], int]


@dataclass(slots=True)
class ShadowFrame:
    """What one frame's shadow map cost."""

    draw_calls: int = 0
    cached: int = 0  # casters that came from the cached map
    rebaked: bool = False


class ShadowMap:
    """A depth map (compared in the lit shader) and its cache of resting casters."""

    def __init__(self, ctx: Any, size: int) -> None:
        self.ctx = ctx
        self.size = int(size)
        self.texture = ctx.depth_texture((self.size,) * 2)
        self.texture.compare_func = "<="
        self.texture.filter = (ctx.LINEAR, ctx.LINEAR)
        self.texture.repeat_x = self.texture.repeat_y = False
        self.fbo = ctx.framebuffer(depth_attachment=self.texture)
        self._cache = ctx.depth_texture((self.size,) * 2)
        self._cache.compare_func = ""  # read as depth values, not compared
        self._cache.filter = (ctx.NEAREST, ctx.NEAREST)
        self._cache_fbo = ctx.framebuffer(depth_attachment=self._cache)
        self._copy = ctx.program(vertex_shader=glsl.FULLSCREEN_VERTEX,
                                 fragment_shader=_COPY_DEPTH)
        self._copy_vao = ctx.vertex_array(self._copy, [])
        #: Whether resting casters are cached (False draws every caster every frame).
        self.caching = True
        self._baked = np.zeros(0, bool)
        self._still = np.zeros(0, np.int64)
        self._previous: np.ndarray | None = None
        self._rects_drawn: np.ndarray | None = None
        self._rects_vp: np.ndarray | None = None  # the light matrix they were made for
        #: The light's view-projection and the light it is of, kept while the region is.
        self._matrix: tuple[tuple, np.ndarray] | None = None
        self._region: tuple[np.ndarray, float] | None = None
        self._light: tuple | None = None
        self._since_bake = 0

    def reset(self, parts: int) -> None:
        """The parts changed (objects came or went): nothing is cached; every part counts
        as resting until it is seen to move."""
        self._baked = np.zeros(parts, bool)
        self._still = np.full(parts, BAKE_AFTER, np.int64)
        self._previous = None
        self._rects_drawn = None

    def _fit(self, centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, float, bool]:
        """The region (centre, radius) the map covers; True when it changed."""
        lo = (centres - radii[:, None]).min(axis=0)
        hi = (centres + radii[:, None]).max(axis=0)
        centre = 0.5 * (lo + hi)
        radius = float(np.max(np.linalg.norm(centres - centre, axis=1) + radii))
        if self._region is not None:
            kept_centre, kept_radius = self._region
            inside = np.all(np.linalg.norm(centres - kept_centre, axis=1) + radii
                            <= kept_radius)
            if inside and radius >= SHRINK * kept_radius:
                return kept_centre, kept_radius, False
        self._region = (centre, radius)
        return centre, radius, True

    def update(self, light: LightInfo, world: np.ndarray, radii: np.ndarray,
               casts: np.ndarray, deforming: np.ndarray, draw: DrawCasters
               ) -> tuple[np.ndarray, ShadowFrame]:
        """Bring the map up to date for casters at ``world`` (P, 4, 4) with bounding
        ``radii``; ``casts`` marks the parts that cast, ``deforming`` those whose mesh
        changes shape every frame (skinned figures), which never rest. Returns the light's
        view-projection matrix.

        Between redraws of the cache only the texels under casters that moved (where they
        were and where they are) are restored from it and drawn again; when nothing moved
        the map is left as it is."""
        frame = ShadowFrame()
        moved = deforming.copy() if self._previous is None else (
            deforming | np.any(world != self._previous, axis=(1, 2)))
        self._previous = world.copy()
        self._still = np.where(moved, 0, self._still + 1)
        centre, radius, refit = self._fit(world[casts, :3, 3], radii[casts])
        light_key = (light.kind, tuple(light.direction), tuple(light.position), light.cutoff)
        if refit or self._matrix is None or self._matrix[0] != light_key:
            self._matrix = (light_key, shadow_matrix(light, centre, radius))
        light_vp = self._matrix[1]
        resting = casts & (self._still >= BAKE_AFTER) if self.caching else np.zeros_like(casts)
        previous_rects = self._rects_drawn
        rects = self._update_rects(world[:, :3, 3], radii, light_vp, moved)
        self._since_bake += 1
        self.ctx.enable(self.ctx.DEPTH_TEST)
        rebake = refit or light_key != self._light or np.any(self._baked & moved) or (
            np.any(resting & ~self._baked) and self._since_bake >= REBAKE_EVERY)
        if rebake:
            self._light, self._since_bake = light_key, 0
            self._baked = resting
            frame.rebaked = True
            self._cache_fbo.use()
            self._cache_fbo.viewport = (0, 0, self.size, self.size)
            self._cache_fbo.clear(depth=1.0)
            frame.draw_calls += draw(self._baked, light_vp)
        frame.cached = int(self._baked.sum())
        live = casts & ~self._baked
        if rebake or not self._baked.any() or previous_rects is None:
            region = (0, 0, self.size, self.size)
        else:
            changed = live & moved
            if not changed.any():
                return light_vp, frame  # the map drawn last frame still holds
            both = np.concatenate([rects[changed], previous_rects[changed]])
            low, high = both[:, :2].min(axis=0), both[:, 2:].max(axis=0)
            region = (int(low[0]), int(low[1]), int(high[0] - low[0]), int(high[1] - low[1]))
        self.fbo.use()
        self.fbo.viewport = (0, 0, self.size, self.size)
        self.fbo.scissor = region
        if self._baked.any():
            self.ctx.depth_func = "1"  # always: the copy replaces every texel
            self._cache.use(0)
            self._copy_vao.render(vertices=3)
            self.ctx.depth_func = "<"
        else:  # nothing cached: the whole map, from scratch
            self.fbo.clear(depth=1.0)
        frame.draw_calls += draw(live, light_vp)
        self.fbo.scissor = None
        return light_vp, frame

    def _update_rects(self, centres: np.ndarray, radii: np.ndarray, light_vp: np.ndarray,
                      moved: np.ndarray) -> np.ndarray:
        """Every part's texel rectangle this frame (:meth:`_rects`), worked out again only
        for the parts that moved while the light's matrix stays: most of a scene rests,
        and its rectangles were the bulk of a frame's shadow work once nothing was drawn.
        Returns a new array; the last frame's stays as it was."""
        kept = self._rects_drawn
        if kept is None or self._rects_vp is None or not np.array_equal(light_vp,
                                                                         self._rects_vp):
            rects = self._rects(centres, radii, light_vp)
        else:
            rects = kept.copy()
            rows = np.flatnonzero(moved)
            if len(rows):
                rects[rows] = self._rects(centres[rows], radii[rows], light_vp)
        self._rects_drawn, self._rects_vp = rects, light_vp
        return rects

    def _rects(self, centres: np.ndarray, radii: np.ndarray, light_vp: np.ndarray
               ) -> np.ndarray:
        """Each bounding sphere's texel rectangle ``(x0, y0, x1, y1)`` in the map (its box's
        corners projected, with a texel of margin for filtering); the whole map for one
        reaching behind a perspective light."""
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        corners = centres[:, None, :] + radii[:, None, None] * signs  # (N, 8, 3)
        clip = corners @ light_vp[:3, :3].T + light_vp[:3, 3]
        w = corners @ light_vp[3, :3] + light_vp[3, 3]
        safe = np.all(w > 1e-6, axis=1)
        xy = clip[..., :2] / np.where(w > 1e-6, w, 1.0)[..., None]
        texels = (xy * 0.5 + 0.5) * self.size
        out = np.empty((len(centres), 4))
        out[:, :2] = np.floor(texels.min(axis=1)) - 2
        out[:, 2:] = np.ceil(texels.max(axis=1)) + 2
        out[~safe] = (0, 0, self.size, self.size)
        return np.clip(out, 0, self.size)

    def release(self) -> None:
        for obj in (self._copy_vao, self._copy, self._cache_fbo, self._cache, self.fbo,
                    self.texture):
            obj.release()
