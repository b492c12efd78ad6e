"""GPU skinning (transform feedback in the renderer) against the CPU reference, on rendered
frames: the default material with shadows, the paper's fixed-function-era toon shader and a
modern user shader; and the skinned figure casts its shadow."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import AT_HAND, MODELS, ROOT, SAMPLES

from components import Shape, Visual
from engine.animation import Mixer
from engine.animation.skinning import skin
from engine.assets import Assets, MeshPart, ModelAsset, SkinnedModel, register_loader
from engine.assets.registry import unregister_loader
from engine.assets.skinned import AVATAR_AXES
from services.render import (
    CameraView,
    FragmentShader,
    HeadlessTarget,
    LightInfo,
    Renderer,
    ShaderLibrary,
    ShaderProgram,
    ShaderState,
    Uniform,
    VertexShader,
)
from services.render.math3d import compose, project

SHADERS = ROOT / "tests" / "render" / "content"
W, H = 240, 180
POSE = ((0.3, -0.2, 0.0), (0.9238795, 0.0, 0.0, 0.3826834))  # turned 45 degrees about Z
LIGHT = LightInfo("directional", direction=(1.0, 0.2, -1.0))


@pytest.fixture(scope="module")
def gl_ctx() -> Iterator[object]:
    import moderngl

    ctx = moderngl.create_context(standalone=True, backend="egl", require=330)
    yield ctx
    ctx.release()


@pytest.fixture
def cpu_models(tmp_path: Path) -> Iterator[tuple[dict[str, ModelAsset], Path]]:
    """Posed meshes the CPU reference made, readable as ``<name>.cpuskin`` files in a
    folder (the files only name them)."""
    made: dict[str, ModelAsset] = {}
    register_loader("model", ".cpuskin")(lambda path: made[path.stem])
    yield made, tmp_path
    unregister_loader("model", ".cpuskin")


def renderer(gl_ctx: object, assets: Assets, library: ShaderLibrary | None = None
             ) -> Renderer:
    r = Renderer(HeadlessTarget((W, H), ctx=gl_ctx), root=SHADERS, assets=assets)
    r.camera = CameraView.looking_at((2.2, -2.8, 1.6), (0.3, -0.2, 0.75))
    r.lights = [LIGHT]
    r.add(1000, Visual(shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))], color=(0.8, 0.8, 0.8, 1)))
    if library is not None:
        r.load_shaders(library)
    return r


def posed(model: SkinnedModel, clip: str, t: float) -> np.ndarray:
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    mixer.play(1, clip)
    mixer.advance(t)
    world, _ = mixer.evaluate()
    return world[mixer.animators[1].row + model.palette_nodes] @ model.inverse_bind


def draw_pair(gl_ctx: object, cpu_models: tuple[dict[str, ModelAsset], Path], file: str,
              scale: float,
              clip: str, t: float, state: str | None = None,
              library: ShaderLibrary | None = None, folder: Path = MODELS
              ) -> tuple[np.ndarray, np.ndarray]:
    """The same posed model (``file`` in ``folder``), skinned on the GPU and on the CPU,
    as two frames."""
    assets = Assets(folder)
    model = assets.skinned(file)
    palette = posed(model, clip, t)
    gpu = renderer(gl_ctx, assets, library)
    gpu.add(1, Visual(model=file, scale=(scale,) * 3, shader_state=state), *POSE, skin=model)
    gpu.set_palettes(palette[:, :3, :], {1: 0})
    gpu.render()
    gpu_image = gpu.read_pixels().astype(int)
    place = compose(*POSE, np.full(3, scale)) @ AVATAR_AXES
    parts = []
    for part in model.parts:
        v, n = skin(part.vertices, part.normals, part.joints, part.weights, palette)
        v = v @ place[:3, :3].T + place[:3, 3]  # uniform scale and a rotation:
        n = n @ place[:3, :3].T / scale  # normals turn with the vertices
        parts.append(MeshPart(v, part.faces, n, part.uv, part.colors, part.color, part.texture))
    made, folder = cpu_models
    name = f"{Path(file).stem}-{clip}"
    made[name] = ModelAsset(folder / f"{name}.cpuskin", tuple(parts))
    (folder / f"{name}.cpuskin").write_text("posed by the CPU reference")
    cpu = renderer(gl_ctx, Assets(MODELS), library)
    cpu.add(1, Visual(model=str(folder / f"{name}.cpuskin"), shader_state=state))
    cpu.render()
    cpu_image = cpu.read_pixels().astype(int)
    for r in (gpu, cpu):
        r.release()
    return gpu_image, cpu_image


def assert_alike(gpu: np.ndarray, cpu: np.ndarray) -> None:
    """Rounding may move an edge pixel: the mean difference under half a level, and fewer
    than 0.2 % of pixels off by more than 8 levels; the figure itself is on screen."""
    diff = np.abs(gpu - cpu).max(axis=2)
    assert diff.mean() < 0.5, diff.mean()
    assert (diff > 8).mean() < 0.002, (diff > 8).mean()
    floor_only = np.abs(gpu - gpu[-1:, :, :]).max(axis=2) > 30
    assert floor_only.mean() > 0.01  # something besides floor is drawn


@pytest.mark.parametrize("folder,file,scale,clip,t", [
    (MODELS, "walker.glb", 1.0, "Run", 0.3), (MODELS, "walker.glb", 1.0, "Wave", 0.6),
    (MODELS, "hound.glb", 0.012, "Run", 0.2), (SAMPLES, "strip.gltf", 0.6, "Sway", 1.2)])
def test_gpu_skinning_draws_what_the_cpu_reference_computes(gl_ctx, cpu_models, folder: Path,
                                                            file: str, scale: float, clip: str,
                                                            t: float):
    gpu, cpu = draw_pair(gl_ctx, cpu_models, file, scale, clip, t, folder=folder)
    assert_alike(gpu, cpu)


@pytest.mark.parametrize("path", AT_HAND)
def test_skinned_files_at_hand_draw_on_the_gpu_as_the_cpu_reference_skins_them(
        gl_ctx, cpu_models, path: Path):
    """Each file of a folder of others' samples (when one is at hand: avatar_helpers), made
    about 1.5 m tall, in its first clip."""
    model = Assets(path.parent).skinned(path.name)
    height = float(np.ptp(np.concatenate([p.vertices for p in model.parts]), axis=0).max())
    gpu, cpu = draw_pair(gl_ctx, cpu_models, path.name, 1.5 / height, model.clip_names[0],
                         0.4, folder=path.parent)
    assert_alike(gpu, cpu)


def test_a_skinned_figure_casts_its_shadow_on_the_floor(gl_ctx, cpu_models):
    assets = Assets(MODELS)
    model = assets.skinned("walker.glb")
    r = renderer(gl_ctx, assets)
    r.render()
    bare = r.read_pixels().astype(int)
    r.add(1, Visual(model="walker.glb"), *POSE, skin=model)
    r.set_palettes(posed(model, "Idle", 0.1)[:, :3, :], {1: 0})
    r.render()
    shaded = r.read_pixels().astype(int)
    # the chest (1.3 m up) throws its shadow along the light onto the floor
    d = np.array(LIGHT.direction) / np.linalg.norm(LIGHT.direction)
    chest = np.array([POSE[0][0], POSE[0][1], 1.3])
    on_floor = chest - d * (chest[2] / d[2])
    eye = r.camera.eyes(W, H)[0]
    x, y, _ = project(on_floor, eye.view, eye.proj, W, H)
    patch = (slice(int(y) - 1, int(y) + 2), slice(int(x) - 1, int(x) + 2))
    assert shaded[patch].mean() < bare[patch].mean() - 25
    r.release()


def user_shaders() -> ShaderLibrary:
    return ShaderLibrary(
        vertex_shaders=[VertexShader("toon_vertex", "shaders/toon.vert")],
        fragment_shaders=[FragmentShader("toon_fragment", "shaders/toon.frag"),
                          FragmentShader("tint", "shaders/tint.frag")],
        programs=[ShaderProgram("toon", "toon_vertex", "toon_fragment"),
                  ShaderProgram("tint", None, "tint")],
        states=[ShaderState("toon", "toon", [Uniform("DiffuseColor", (0.0, 0.25, 1.0)),
                                             Uniform("PhongColor", (0.75, 0.75, 1.0)),
                                             Uniform("Edge", 0.3), Uniform("Phong", 0.98)]),
                ShaderState("tint", "tint", [Uniform("Tint", (1.0, 1.0, 0.0))])])


@pytest.mark.parametrize("state", ["toon", "tint"])
def test_user_shaders_draw_skinned_figures_as_they_draw_posed_meshes(gl_ctx, cpu_models,
                                                                     state: str):
    gpu, cpu = draw_pair(gl_ctx, cpu_models, "walker.glb", 1.0, "Walk", 0.2, state,
                         user_shaders())
    assert_alike(gpu, cpu)
    if state == "toon":  # the paper's toon shader: its flat diffuse blue is on the figure
        blue = (np.abs(gpu[:, :, 0]) < 10) & (np.abs(gpu[:, :, 1] - 64) < 10) & (
            gpu[:, :, 2] > 245)
        assert blue.sum() > 100


def test_a_skinned_texture_is_drawn_the_way_up_the_file_means(gl_ctx):
    """glTF's texture coordinate v runs down from the image's top row. The hound's fur
    (tools/gltf_samples.py) has its tan coat in the top band, legs darkening into paws in
    the second, dark ears in the bottom one: seen from its right, lit from there, in its
    bind pose, its flank is tan (blue well under red) and its paws darker; read upside down
    the flank was dark brown and the paws tan."""
    assets = Assets(MODELS)
    model = assets.skinned("hound.glb")
    r = renderer(gl_ctx, assets)
    r.camera = CameraView.looking_at((3.0, 0.0, 0.8), (0.0, 0.0, 0.6))
    r.lights = [LightInfo("directional", direction=(-1.0, 0.0, -0.3))]
    scale = 0.015
    r.add(1, Visual(model="hound.glb", scale=(scale,) * 3), skin=model)
    r.set_palettes(np.tile(np.eye(4)[:3], (len(model.palette_nodes), 1, 1)), {1: 0})
    r.render()
    image = r.read_pixels().astype(float)
    eye = r.camera.eyes(W, H)[0]
    r.release()

    def colour(gltf_point: tuple[float, float, float]) -> np.ndarray:
        """The mean colour of the 3x3 pixels where a point of the model (glTF axes) is."""
        x, y, _ = project(scale * (AVATAR_AXES[:3, :3] @ gltf_point), eye.view, eye.proj, W, H)
        return image[int(y) - 1:int(y) + 2, int(x) - 1:int(x) + 2].reshape(-1, 3).mean(axis=0)

    flank = colour((-11.5, 54.0, 0.0))  # the right flank (glTF -X) faces the camera
    assert flank[2] < 0.55 * flank[0], flank
    paw = colour((-8.0, 3.0, 28.0))  # the right fore toe
    assert paw.max() < 0.6 * flank.max(), (paw, flank)
