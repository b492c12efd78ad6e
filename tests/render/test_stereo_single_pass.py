"""Both eyes in one pass (instanced stereo) draw what one pass an eye draws, with the
draw calls of one eye: a headset's frame costs the CPU about what a mono frame does."""

from __future__ import annotations

import math

import numpy as np
from render_helpers import H, W, floor

from components import Shape, Visual
from services.render import CameraView, math3d
from services.render.camera import HeadsetEye
from services.xr.projection import Fov, fov_projection


def _scene(renderer) -> None:
    floor(renderer, color=(0.5, 0.55, 0.5, 1.0))
    for i in range(30):
        a = 2 * np.pi * i / 30
        renderer.add(10 + i, Visual(shapes=[Shape("box", (0.3, 0.3, 0.2 + 0.05 * (i % 5)))],
                                    color=(0.9, 0.3 + 0.02 * i, 0.2, 1)),
                     position=(3 * np.cos(a), 3 * np.sin(a), 0.4))
    renderer.add(99, Visual(shapes=[Shape("sphere", (0.4,))], color=(0.2, 0.4, 0.9, 1)),
                 position=(0.0, 0.0, 0.6))


def _headset_view() -> CameraView:
    """Two eyes 63 mm apart, each with its own asymmetric field of view (a headset's)."""
    eyes = []
    centre = np.array([0.0, -5.0, 1.6])
    look = math3d.look_at_orientation(centre, (0.0, 0.0, 0.5))
    right = math3d.compose(centre, look)[:3, 0]
    for side, fov in ((-1, Fov(-0.80, 0.70, 0.75, -0.85)), (1, Fov(-0.70, 0.80, 0.75, -0.85))):
        position = centre + side * 0.0315 * right
        eyes.append(HeadsetEye(position, look, fov_projection(fov, 0.05, 100.0)))
    return CameraView(centre, look, near=0.05, far=100.0, headset=eyes)


def _both(make_renderer, view: CameraView):
    images, stats = [], []
    for single in (True, False):
        r = make_renderer(size=(2 * W, H))
        r.single_pass = single
        r.camera = view
        _scene(r)
        r.render()
        images.append(r.read_pixels().astype(int))
        stats.append(r.stats)
    return images, stats


def _alike(a: np.ndarray, b: np.ndarray) -> None:
    differ = np.abs(a - b).max(axis=2) > 8
    assert differ.mean() < 0.003, f"{differ.sum()} pixels differ"


def test_a_stereo_camera_in_one_pass_looks_as_in_two(make_renderer):
    view = CameraView.looking_at((0.0, -5.0, 1.6), (0.0, 0.0, 0.5), eye_separation=0.064)
    (one, two), (s1, s2) = _both(make_renderer, view)
    _alike(one, two)
    assert s1.draw_calls * 2 == s2.draw_calls  # one draw a batch, not one an eye
    assert s1.instances == s2.instances


def test_a_headsets_asymmetric_eyes_in_one_pass_look_as_in_two(make_renderer):
    (one, two), (s1, s2) = _both(make_renderer, _headset_view())
    _alike(one, two)
    assert s1.draw_calls * 2 == s2.draw_calls


def test_nothing_of_one_eye_spills_into_the_other(make_renderer):
    """A wide magenta wall across the left eye's right edge, the right eye looking the
    other way: the right half shows none of it (each eye is clipped at the middle)."""
    r = make_renderer(size=(2 * W, H))
    centre = np.array([0.0, 0.0, 1.6])
    ahead = math3d.look_at_orientation(centre, (0.0, 5.0, 1.6))
    behind = math3d.look_at_orientation(centre, (0.0, -5.0, 1.6))
    fov = fov_projection(Fov(-0.6, 0.6, 0.5, -0.5), 0.05, 100.0)
    r.camera = CameraView(centre, ahead, headset=[HeadsetEye(centre, ahead, fov),
                                                  HeadsetEye(centre, behind, fov)])
    r.add(1, Visual(shapes=[Shape("box", (40.0, 0.2, 10.0))], color=(1.0, 0.0, 1.0, 1.0)),
          position=(0.0, 3.0, 1.6))
    for single in (True, False):
        r.single_pass = single
        r.render()
        image = r.read_pixels().astype(int)
        magenta = (image[:, :, 0] > 60) & (image[:, :, 1] < 30) & (image[:, :, 2] > 60)
        assert magenta[:, :W].mean() > 0.9, single
        assert not magenta[:, W:].any(), single


def test_the_projection_is_the_runtimes_frustum():
    fov = Fov(-0.7, 0.9, 0.6, -0.8)
    p = fov_projection(fov, 0.1, 50.0)
    for x, y in ((math.tan(-0.7), math.tan(0.6)), (math.tan(0.9), math.tan(-0.8))):
        clip = p @ np.array([x * 2.0, y * 2.0, -2.0, 1.0])
        assert np.allclose(np.abs(clip[:2] / clip[3]), 1.0)
