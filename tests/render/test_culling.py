"""What the renderer leaves out or simplifies must not change the picture: frustum culling,
levels of detail, unit meshes scaled per instance, and the cache of resting shadow casters."""

from __future__ import annotations

import numpy as np
from render_helpers import H, W, floor

from components import Shape, Visual
from services.render import CameraView, LightInfo, math3d, meshes
from services.render.culling import frustum_planes, in_frustum, lod_levels, pixels_per_unit
from services.render.lights import shadow_matrix
from services.render.shadows import ShadowMap


def _ring(renderer, count: int = 24) -> None:
    """Boxes of different sizes all around the camera at (0, -6, 3): half are behind it."""
    for i in range(count):
        a = 2 * np.pi * i / count
        size = (0.3 + 0.02 * i, 0.4, 0.2 + 0.03 * i)
        renderer.add(10 + i, Visual(shapes=[Shape("box", size)], color=(0.9, 0.5, 0.2, 1)),
                     position=(4 * np.cos(a), -6 + 4 * np.sin(a), 0.5))


def test_frustum_planes_agree_with_the_projection():
    rng = np.random.default_rng(3)
    eye = CameraView.looking_at((1.0, -5.0, 2.0), (0.0, 0.0, 0.5), fov=50.0).eyes(W, H)[0]
    planes = frustum_planes(eye.proj @ eye.view)
    points = rng.uniform(-12, 12, (2000, 3))
    clip = np.c_[points, np.ones(len(points))] @ (eye.proj @ eye.view).T
    inside = np.all(np.abs(clip[:, :3]) <= clip[:, 3:], axis=1) & (clip[:, 3] > 0)
    assert np.array_equal(in_frustum(planes, points, np.zeros(len(points))), inside)
    # a sphere is kept while any of it can reach inside: its centre within a radius outside
    d = points @ planes[:, :3].T + planes[:, 3]
    near_miss = ~inside & (d.min(axis=1) > -0.5)
    assert in_frustum(planes, points[near_miss], np.full(near_miss.sum(), 0.5)).all()


def test_objects_behind_the_camera_are_not_drawn_and_the_image_is_the_same(make_renderer):
    images, stats = [], []
    for culling in (True, False):
        r = make_renderer()
        r.culling = culling
        floor(r)
        _ring(r)
        r.render()
        images.append(r.read_pixels())
        stats.append(r.stats)
    on, off = stats
    assert on.culled >= 8 and off.culled == 0
    assert on.instances == off.instances - on.culled
    assert np.array_equal(images[0], images[1])
    assert (images[0][..., 0].astype(int) - images[0][..., 2] > 60).mean() > 0.01  # boxes show


def test_boxes_of_every_size_are_one_draw_and_look_as_their_own_meshes(make_renderer):
    r = make_renderer()
    r.ambient = (0.3, 0.3, 0.3)
    for i in range(6):
        r.add(i, Visual(shapes=[Shape("box", (0.3 + 0.1 * i, 0.6, 0.2 + 0.15 * i))]),
              position=(-2.5 + i, 0.0, 0.5))
    r.render()
    assert r.stats.draw_calls == 1
    unit = r.read_pixels().astype(int)
    own = make_renderer()
    own.ambient = (0.3, 0.3, 0.3)
    for i in range(6):
        data = meshes.box((0.3 + 0.1 * i, 0.6, 0.2 + 0.15 * i))
        shape = Shape("mesh", vertices=data.positions.astype(np.float64),
                      faces=data.indices.reshape(-1, 3))
        own.add(i, Visual(shapes=[shape]), position=(-2.5 + i, 0.0, 0.5))
    own.render()
    diff = np.abs(own.read_pixels().astype(int) - unit).max(axis=2)
    assert (diff > 8).mean() < 0.002  # rounding at an edge, nothing more


def test_a_capsule_drawn_as_a_cylinder_between_spheres_covers_its_own_mesh(make_renderer):
    coverage = []
    for shape in (Shape("capsule", (0.3, 1.2)),
                  Shape("mesh", vertices=meshes.capsule(0.3, 1.2).positions.astype(float),
                        faces=meshes.capsule(0.3, 1.2).indices.reshape(-1, 3))):
        r = make_renderer()
        r.background = (0.0, 0.0, 0.0)
        r.camera = CameraView.looking_at((0.0, -3.0, 1.5), (0.0, 0.0, 0.8))
        r.add(1, Visual(shapes=[shape], color=(1, 1, 1, 1)), position=(0, 0, 0.8),
              orientation=(np.cos(0.4), np.sin(0.4), 0.0, 0.0))  # tipped 46 degrees
        r.render()
        coverage.append(r.read_pixels().max(axis=2) > 10)
    assert coverage[0].sum() > 600
    assert (coverage[0] != coverage[1]).sum() < 0.05 * coverage[0].sum()


def test_small_looking_spheres_get_coarser_levels():
    focal = pixels_per_unit(math3d.perspective(60.0, 1.0, 0.1, 100.0), 600)
    distance = np.array([1.0, 4.0, 100.0])
    levels = lod_levels(np.full(3, 0.1), distance, focal)
    assert levels.tolist() == [0, 1, 2]  # 52, 13 and 0.5 pixels of radius


def test_levels_of_detail_barely_change_the_picture(make_renderer):
    images = []
    for lod in (True, False):
        r = make_renderer()
        r.lod = lod
        floor(r)
        for i in range(30):
            r.add(i, Visual(shapes=[Shape("sphere", (0.08,))], color=(0.2, 0.6, 1, 1)),
                  position=(-3 + 0.2 * i, 4.0 + 0.3 * (i % 5), 0.3))
        r.render()
        images.append(r.read_pixels().astype(int))
    diff = np.abs(images[0] - images[1]).max(axis=2)
    assert diff.mean() < 0.5 and (diff > 40).mean() < 0.002


def test_cached_shadows_match_shadows_drawn_from_scratch(make_renderer):
    """A ball moves over boxes that rest; later one box moves too: the cached map (its
    copy patched where things moved) gives the image of a map drawn whole every frame."""
    pair = []
    for cache in (True, False):
        r = make_renderer(size=(200, 150))
        r.shadow_cache = cache
        r.lights = [LightInfo("directional", direction=(-0.3, 0.4, -1.0))]
        floor(r)
        for i in range(12):
            r.add(i + 1, Visual(shapes=[Shape("box", (0.3, 0.3, 0.6))]),
                  position=((i % 4) - 1.5, (i // 4) - 1.0, 0.3))
        r.add(100, Visual(shapes=[Shape("sphere", (0.3,))], color=(1, 0, 0, 1)),
              position=(0, 0, 1))
        pair.append(r)
    cached, fresh = pair
    rebakes = []
    for frame in range(80):
        ball = (1.5 * np.sin(0.1 * frame), 1.5 * np.cos(0.13 * frame), 1.0) if frame < 50 \
            else (0.5, 0.5, 1.0)
        for r in pair:
            r.set_pose(100, ball, (1.0, 0.0, 0.0, 0.0))
            if frame == 70:
                r.set_pose(3, (0.4, -1.6, 0.3), (1.0, 0.0, 0.0, 0.0))
            r.render()
        assert np.array_equal(cached.read_pixels(), fresh.read_pixels()), frame
        rebakes.append(cached.stats.shadow_rebakes)
        if frame == 60:  # the boxes are cached; the ball rests but has not joined them
            assert cached.stats.shadow_cached == 12 and cached.stats.shadow_draw_calls == 0
    # frame 0 caches everything (all assumed resting), frame 1 finds the ball moving and
    # leaves it out, frame 70 the box that moved
    assert [i for i, rebaked in enumerate(rebakes) if rebaked] == [0, 1, 70]


def test_shadow_rectangles_kept_for_resting_parts_are_those_worked_out_afresh(gl_ctx):
    """The shadow map works out the texel rectangles of the parts that moved only; every
    frame the whole set equals what all of them worked out again gives, and a new light
    matrix works them all out again."""
    shadows = ShadowMap(gl_ctx, 256)
    rng = np.random.default_rng(3)
    centres, radii = rng.uniform(-2, 2, (40, 3)), rng.uniform(0.05, 0.5, 40)
    light_vp = shadow_matrix(LightInfo("directional", direction=(-0.3, 0.4, -1.0)),
                             np.zeros(3), 3.0)
    for frame in range(12):
        moved = rng.random(40) < 0.2 if frame else np.ones(40, bool)
        centres[moved] += rng.normal(0, 0.1, (int(moved.sum()), 3))
        if frame == 8:
            light_vp = shadow_matrix(LightInfo("directional", direction=(0.2, 0.1, -1.0)),
                                     np.zeros(3), 3.0)
        kept = shadows._update_rects(centres, radii, light_vp, moved)
        assert np.array_equal(kept, shadows._rects(centres, radii, light_vp)), frame
    shadows.release()


def test_what_rests_is_not_worked_out_again_and_the_picture_is_the_same(make_renderer):
    """The renderer keeps the world matrices of parts that did not move, and an eye's
    draws while neither it nor anything moved; frame by frame (some still, some with a
    ball moving, the camera turned round on a still frame, a colour changed) the picture
    is that of a renderer working everything out afresh."""
    pair = []
    for _ in range(2):
        r = make_renderer(size=(160, 120))
        r.lights = [LightInfo("directional", direction=(-0.3, 0.4, -1.0))]
        floor(r)
        _ring(r)
        r.add(100, Visual(shapes=[Shape("sphere", (0.3,))], color=(1, 0, 0, 1)),
              position=(0, 0, 1))
        pair.append(r)
    kept, fresh = pair
    for frame in range(24):
        moving = frame % 6 < 3
        for r in pair:
            if moving:
                r.set_pose(100, (np.sin(0.3 * frame), 0.0, 1.0), (1.0, 0.0, 0.0, 0.0))
            if frame == 16:  # a still frame: the other way, where other boxes stand
                r.camera = CameraView.looking_at((0.0, -6.0, 3.0), (0.0, -12.0, 0.5))
            if frame == 18:
                r.add(100, Visual(shapes=[Shape("sphere", (0.3,))], color=(0, 1, 0, 1)),
                      position=r.pose(100)[0])
        fresh._posed = None
        fresh._eye_cache.clear()
        version = kept._posed.version if kept._posed is not None else None
        draws = kept._eye_cache.get(0)
        for r in pair:
            r.render()
        assert np.array_equal(kept.read_pixels(), fresh.read_pixels()), frame
        assert kept.stats.culled == fresh.stats.culled
        if frame % 6 in (4, 5) and frame != 16:  # still: nothing was worked out again
            assert kept._posed.version == version and kept._eye_cache[0] is draws


def test_stereo_eyes_are_culled_each_for_itself(make_renderer):
    r = make_renderer(size=(2 * W, H))
    r.single_pass = False  # one pass an eye: each culled for itself
    r.camera = CameraView.looking_at((0.0, -6.0, 3.0), (0.0, 0.0, 0.5), eye_separation=0.065)
    _ring(r)
    r.render()
    assert r.stats.culled >= 16  # every eye leaves out those behind it
    each = r.stats.culled
    r.single_pass = True  # one pass for both: what neither eye sees is left out once
    r.render()
    assert each // 2 - 1 <= r.stats.culled < each
