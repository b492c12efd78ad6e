"""Models through the asset layer (every built-in format) drawn, textures, and bad assets
drawn as placeholders."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import trimesh
from PIL import Image
from render_helpers import pixel_at

from components import Shape, Visual
from engine.assets import Assets
from engine.assets.generated import DARK, LIGHT, MARKER_BALL
from engine.assets.loaders import MODEL_EXTENSIONS
from services.render import CameraView
from services.render.materials import CHECKER_A

CENTRE = (0.0, 0.0, 0.5)


@pytest.mark.parametrize("suffix", MODEL_EXTENSIONS)
def test_every_supported_model_format_loads_and_draws(make_renderer, tmp_path, suffix):
    path = tmp_path / f"cube{suffix}"
    cube = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    cube.visual.face_colors = (255, 255, 255, 255)  # a white model, tinted by Visual.color
    cube.export(path)
    parts = Assets(tmp_path).model(path.name).parts
    extents = np.ptp(np.concatenate([p.vertices for p in parts]), axis=0)
    assert np.allclose(extents, 1.0, atol=1e-5)
    r = make_renderer(root=tmp_path)
    r.add(1, Visual(model=path.name, color=(0.1, 0.9, 0.1, 1.0)), position=CENTRE)
    r.render()
    rgb = pixel_at(r, r.read_pixels(), CENTRE)
    assert rgb[1] > 2 * rgb[0] and rgb[1] > 2 * rgb[2], rgb


def test_gltf_y_up_becomes_engine_z_up(tmp_path):
    path = tmp_path / "tall.glb"
    trimesh.creation.box(extents=(0.5, 2.0, 0.5)).export(path)  # tall along glTF's up (+Y)
    extents = np.ptp(Assets(tmp_path).model(path.name).parts[0].vertices, axis=0)
    assert np.allclose(extents, (0.5, 0.5, 2.0), atol=1e-5)


def test_visual_scale_multiplies_the_model(make_renderer, tmp_path):
    path = tmp_path / "cube.stl"
    trimesh.creation.box(extents=(1.0, 1.0, 1.0)).export(path)
    r = make_renderer(root=tmp_path)
    r.background = (0.0, 0.0, 0.0)
    r.add(1, Visual(model=path.name, scale=(0.1, 0.1, 0.1)), position=CENTRE)
    r.render()
    assert pixel_at(r, r.read_pixels(), (0.3, 0.0, 0.5)).sum() == 0  # 1 m cube is now 10 cm
    assert pixel_at(r, r.read_pixels(), CENTRE).sum() > 0


def test_textured_model_shows_its_texture(make_renderer, tmp_path):
    image = Image.new("RGB", (8, 8), (255, 0, 0))
    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    uv = np.zeros((len(box.vertices), 2)) + 0.5
    box.visual = trimesh.visual.TextureVisuals(uv=uv, image=image)
    box.export(tmp_path / "red.obj")
    r = make_renderer(root=tmp_path)
    r.ambient = (1.0, 1.0, 1.0)
    r.add(1, Visual(model="red.obj", color=(1, 1, 1, 1)), position=CENTRE)
    r.render()
    rgb = pixel_at(r, r.read_pixels(), CENTRE)
    assert rgb[0] > 200 and rgb[1] < 80 and rgb[2] < 80, rgb


def test_visual_texture_file_is_used(make_renderer, tmp_path):
    Image.new("RGB", (4, 4), (0, 0, 255)).save(tmp_path / "blue.png")
    r = make_renderer(root=tmp_path)
    r.ambient = (1.0, 1.0, 1.0)
    r.add(1, Visual(shapes=[Shape("box", (1.0, 1.0, 1.0))], texture="blue.png",
                    color=(1, 1, 1, 1)), position=CENTRE)
    r.render()
    rgb = pixel_at(r, r.read_pixels(), CENTRE)
    assert rgb[2] > 200 and rgb[0] < 80, rgb


def test_missing_texture_draws_a_checker_and_warns(make_renderer, tmp_path, caplog):
    r = make_renderer(root=tmp_path)
    r.ambient = (1.0, 1.0, 1.0)
    r.lights = []
    with caplog.at_level(logging.WARNING, logger="colosseum.render"):
        r.add(1, Visual(shapes=[Shape("box", (1.2, 1.2, 1.2))], texture="textures/gone.png",
                        color=(1, 1, 1, 1)), position=CENTRE)
        r.add(2, Visual(shapes=[Shape("box", (0.2, 0.2, 0.2))], texture="textures/gone.png"),
              position=(5.0, 0.0, 0.0))
    assert len(caplog.records) == 1  # told once, however many surfaces use it
    assert 'cannot load image "textures/gone.png"' in caplog.text
    assert "file not found" in caplog.text and "placeholder" in caplog.text
    assert any("gone.png" in e for e in r.errors)
    r.render()
    image = r.read_pixels().astype(int)
    x0, x1 = 60, 100  # the face toward the camera covers the middle of the frame
    patch = image[45:75, x0:x1].reshape(-1, 3)
    magenta = (patch[:, 0] > 150) & (patch[:, 1] < 80) & (patch[:, 2] > 150)
    dark = patch.sum(axis=1) < 120
    assert magenta.mean() > 0.2 and dark.mean() > 0.2  # both checker colours show
    assert CHECKER_A[:3] == (255, 0, 255)


def test_bad_model_stops_that_object_not_the_frame(make_renderer, tmp_path):
    (tmp_path / "cow.osg").write_text("osg")
    (tmp_path / "broken.obj").write_text("this is not an obj file\n")
    r = make_renderer(root=tmp_path)
    r.add(1, Visual(model="cow.osg"), position=CENTRE)
    r.add(2, Visual(model="missing.ply"), position=(1.5, 0.0, 0.5))
    r.add(3, Visual(model="broken.obj"), position=(-1.5, 0.0, 0.5))
    report = "\n".join(r.errors)
    assert "cow.osg" in report and "unsupported model format '.osg'" in report
    assert "missing.ply" in report and "not found" in report
    assert "broken.obj" in report
    r.render()  # placeholders are drawn; nothing raised
    rgb = pixel_at(r, r.read_pixels(), CENTRE)
    assert (rgb[0] > 100 and rgb[2] > 100 and rgb[1] < 40) or rgb.sum() < 120  # checker


def test_mesh_shape_from_raw_triangles_draws(make_renderer):
    ball = trimesh.creation.icosphere(subdivisions=1, radius=0.5)
    r = make_renderer()
    r.background = (0.0, 0.0, 0.0)
    r.add(1, Visual(shapes=[Shape("mesh", vertices=np.asarray(ball.vertices),
                                  faces=np.asarray(ball.faces))], color=(0, 0, 1, 1)),
          position=CENTRE)
    r.render()
    rgb = pixel_at(r, r.read_pixels(), CENTRE)
    assert rgb[2] > 60 and rgb[2] > 2 * rgb[0]


def test_the_hands_marker_ball_is_a_generated_checker_drawn_on_the_sphere(make_renderer,
                                                                          tmp_path):
    """The marker's texture is made, not read (no file): an 8 x 4 checker of two tones that,
    drawn on the marker's sphere, shows as light and dark patches under the same light as
    an untextured ball (the textured frame over the plain one is the texture's tone)."""
    assets = Assets(tmp_path)
    image = assets.image(MARKER_BALL)
    assert assets.image(MARKER_BALL) is image and not assets.loads  # made once, read never
    tones = image.rgba[..., 0]
    assert set(np.unique(tones).tolist()) == {LIGHT, DARK}
    assert (tones == LIGHT).mean() == 0.5 and (image.rgba[..., 3] == 255).all()
    assert tones[0, 0] == tones[0, 16] != tones[0, 8] and tones[0, 0] != tones[16, 0]

    def frame(texture: str | None) -> np.ndarray:
        r = make_renderer(root=tmp_path)
        r.camera = CameraView.looking_at((0.0, -3.0, 0.5), CENTRE)
        r.add(1, Visual(shapes=[Shape("sphere", (0.5,))], color=(1.0, 0.85, 0.2, 1.0),
                        texture=texture), position=CENTRE)
        r.render()
        return r.read_pixels()[..., :3].astype(float)

    plain, marked = frame(None), frame(MARKER_BALL)
    ball = np.abs(plain - plain[0, 0]).max(axis=2) > 30  # not the background
    lit = ball & (plain.max(axis=2) > 40)  # the lit face, where a ratio means something
    assert lit.sum() > 500, lit.sum()
    share = marked.max(axis=2)[lit] / plain.max(axis=2)[lit]
    assert (share > 0.9).mean() > 0.2 and (share < 0.6).mean() > 0.2  # both tones show
