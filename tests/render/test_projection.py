"""Objects appear where the camera math says, in their colour; the camera convention holds."""

from __future__ import annotations

import numpy as np
from render_helpers import H, W, floor, pixel_at

from components import Shape, Visual
from services.render import CameraView
from services.render.math3d import camera_view, perspective, project


def test_object_colour_appears_at_its_projection(make_renderer):
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    floor(r, color=(0.3, 0.3, 0.3, 1.0))
    spots = {(1.0, 0.0, 0.0): (-1.5, 0.5, 0.4), (0.0, 1.0, 0.0): (1.2, -0.5, 0.4),
             (0.0, 0.0, 1.0): (0.0, 1.5, 0.4)}
    for key, (colour, pos) in enumerate(spots.items()):
        r.add(key, Visual(shapes=[Shape("sphere", (0.4,))], color=(*colour, 1.0)), position=pos)
    r.render()
    image = r.read_pixels()
    for colour, pos in spots.items():
        rgb = pixel_at(r, image, pos)
        channel = int(np.argmax(colour))
        assert rgb[channel] > 60, (colour, rgb)
        assert rgb[channel] > 2 * max(np.delete(rgb, channel)), (colour, rgb)


def test_moving_an_object_moves_its_pixels(make_renderer):
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    r.add(1, Visual(shapes=[Shape("box", (0.6, 0.6, 0.6))], color=(1, 1, 1, 1)),
          position=(-1.5, 0.0, 0.3))
    r.render()
    before = pixel_at(r, r.read_pixels(), (1.5, 0.0, 0.3))
    r.set_poses(np.array([1]), np.array([[1.5, 0.0, 0.3]]), np.array([[1.0, 0, 0, 0]]))
    r.render()
    after = pixel_at(r, r.read_pixels(), (1.5, 0.0, 0.3))
    assert before.sum() == 0 and after.sum() > 100


def test_identity_camera_looks_along_plus_y_with_z_up():
    view = camera_view(np.zeros(3), np.array([1.0, 0, 0, 0]))
    proj = perspective(60.0, W / H, 0.1, 100.0)
    x, y, depth = project(np.array([0.0, 5.0, 0.0]), view, proj, W, H)
    assert (x, y) == (W / 2, H / 2) and -1 < depth < 1
    _, y_up, _ = project(np.array([0.0, 5.0, 1.0]), view, proj, W, H)
    assert y_up < H / 2  # +Z is up on screen
    x_right, _, _ = project(np.array([1.0, 5.0, 0.0]), view, proj, W, H)
    assert x_right > W / 2  # +X is to the right
    _, _, behind = project(np.array([0.0, -5.0, 0.0]), view, proj, W, H)
    assert not -1 < behind < 1


def test_stereo_renders_two_eyes_side_by_side(make_renderer):
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    r.add(1, Visual(shapes=[Shape("sphere", (0.3,))], color=(1, 1, 1, 1)),
          position=(0.0, 0.0, 0.5))
    r.camera = CameraView.looking_at((0.0, -4.0, 0.5), (0.0, 0.0, 0.5), eye_separation=0.3)
    r.render()
    image = r.read_pixels().sum(axis=2)
    left, right = image[:, : W // 2], image[:, W // 2:]
    assert left.max() > 0 and right.max() > 0  # the sphere is in both halves
    cols_left = np.nonzero(left.max(axis=0))[0].mean()
    cols_right = np.nonzero(right.max(axis=0))[0].mean()
    # the left eye sits to the left, so it sees the sphere further right (parallax)
    assert cols_left > cols_right
    eyes = r.camera.eyes(W, H)
    assert np.allclose(np.linalg.norm(eyes[0].position - eyes[1].position), 0.3)


def test_empty_scene_has_default_light_and_floor_is_lit(make_renderer):
    r = make_renderer()
    r.lights = []  # nothing declared: the default light stands in
    floor(r)
    r.render()
    rgb = pixel_at(r, r.read_pixels(), (0.0, 0.0, 0.0))
    assert rgb.mean() > 120  # default grey material under the default light
