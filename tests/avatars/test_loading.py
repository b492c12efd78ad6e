"""glTF skins through the asset layer: every shipped sample loads, and each way real files
go wrong is told at the scene line with the rest of the scene running."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import GROUND, MODELS, SAMPLES, SHIPPED, avatar_engine, content, entity

from components import Avatar
from engine.assets import AssetError, Assets
from engine.assets.skinned import MAX_INFLUENCES
from engine.scene import load_spec
from tools.gltf_samples import FIVE_INFLUENCES, two_bone, walker

BALL = 'Object { ID "ball" Position [3 0 1] Size [0.5] }'


def avatar_line(file: str, extra: str = "") -> str:
    return f'Avatar {{ ID "bad" Model "{file}" {extra} }}'


def place(scene: Path, text: str) -> tuple[int, int]:
    for number, line in enumerate(scene.read_text().splitlines(), start=1):
        if text in line:
            return number, line.index(text) + 1
    raise AssertionError(f"{text} is not in {scene}")


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_sample_loads_with_skin_clips_and_normalised_weights(path: Path):
    model = Assets(path.parent).skinned(path.name)
    assert model.skin_count == 1
    assert model.clips and all(c.duration > 0 for c in model.clips)
    for part in model.parts:
        assert part.weights.shape == (len(part.vertices), MAX_INFLUENCES)
        np.testing.assert_allclose(part.weights.sum(axis=1), 1.0, atol=1e-6)
        assert part.joints.max() < len(model.palette_nodes)
    # each parent comes before its children
    assert all(p < i for i, p in enumerate(model.parents))


def test_the_khronos_fox_has_its_three_clips_its_24_joints_and_its_texture():
    fox = Assets(MODELS).skinned("Fox.glb")
    assert fox.clip_names == ("Survey", "Walk", "Run")
    assert len(fox.palette_nodes) == 24
    assert fox.parts[0].texture is not None and fox.parts[0].texture.shape == (1024, 1024, 4)
    assert fox.warnings == ()


def test_a_sample_whose_texture_is_missing_loads_with_a_message_and_is_still_drawn(
        tmp_path: Path):
    lost = SAMPLES / "walker_lost_texture.gltf"
    model = Assets(SAMPLES).skinned(lost.name)
    (warning,) = model.warnings
    assert "shirt.png" in warning and "not there" in warning
    assert all(part.texture is None for part in model.parts)
    folder = content(tmp_path, "\n".join([
        GROUND, 'Avatar { ID "lost" Model "models/walker_lost_texture.gltf" '
                'Animation "Walk" Color [1 0.2 0.2] }',
        'Camera { Position [0 -4 1.2] LookAt [0 0 0.9] }']), models=(lost,))
    spec = load_spec(folder)
    (told,) = spec.problems
    assert not told.is_error and "shirt.png" in told.message
    assert (told.line, told.col) == place(folder / "main.scene", '"models/walker_lost')
    with avatar_engine(folder, render=True) as engine:
        engine.run(frames=3)
        from systems.render import RenderSystem

        image = engine.resource(RenderSystem).renderer.read_pixels().astype(int)
    red = (image[:, :, 0] > 150) & (image[:, :, 1] < 90)  # the figure, tinted red
    assert red.sum() > 80  # about 150 pixels at this size


def test_a_model_without_a_skin_is_told_at_its_line_and_the_scene_runs(tmp_path: Path):
    two_bone(tmp_path / "models" / "bar.glb", skinned=False)
    folder = content(tmp_path, "\n".join([GROUND, BALL, avatar_line("models/bar.glb")]),
                     models=())
    spec = load_spec(folder)
    (told,) = spec.problems
    assert told.is_error and 'model "models/bar.glb" has no skin' in told.message
    assert "avatar 'bad' is left out" in told.message
    assert (told.line, told.col) == place(folder / "main.scene", '"models/bar.glb"')
    with avatar_engine(folder) as engine:
        engine.run(frames=20)
        assert engine.world.get_component(Avatar) == []
        ball = entity(engine, "ball")
        assert engine.world.entity_exists(ball)


def test_an_unknown_clip_names_the_clips_there_are_and_the_avatar_still_stands(tmp_path: Path):
    folder = content(tmp_path, "\n".join([
        GROUND, 'Avatar { ID "w" Model "models/walker.glb" Animation "Jog" }']))
    spec = load_spec(folder)
    (told,) = spec.problems
    assert told.is_error
    assert 'has no clip "Jog"' in told.message
    assert "(its clips: Idle, Walk, Run, CarryWalk, Wave)" in told.message
    assert (told.line, told.col) == place(folder / "main.scene", '"Jog"')
    with avatar_engine(folder) as engine:
        engine.run(frames=5)
        assert engine.world.has_component(entity(engine, "w"), Avatar)


@pytest.mark.parametrize("influences,scale,expect", [
    (5, 1.0, "more than 4 joint influences; the 4 largest are kept"),
    (4, 1.7, "sum to 1.7..1.7, not 1; renormalised")])
def test_weights_past_four_or_not_summing_to_one_are_repaired_and_told(
        tmp_path: Path, influences: int, scale: float, expect: str):
    path = two_bone(tmp_path / "models" / "bar.glb", influences=influences, weight_scale=scale)
    model = Assets(tmp_path).skinned("models/bar.glb")
    (warning,) = model.warnings
    assert expect in warning
    weights = model.parts[0].weights
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, atol=1e-6)
    folder = content(tmp_path, avatar_line("models/bar.glb", 'Animation "Bend"'), models=())
    assert path.exists()
    (told,) = load_spec(folder).problems
    assert not told.is_error and expect in told.message


def test_five_influences_keep_the_four_largest_renormalised(tmp_path: Path):
    two_bone(tmp_path / "bar.glb", influences=5)
    part = Assets(tmp_path).skinned("bar.glb").parts[0]
    kept = np.array(FIVE_INFLUENCES[:4]) / sum(FIVE_INFLUENCES[:4])
    np.testing.assert_allclose(part.weights, np.tile(kept, (len(part.weights), 1)), atol=1e-7)
    np.testing.assert_array_equal(part.joints, np.tile([0, 1, 0, 1], (len(part.joints), 1)))


def test_keyframe_times_out_of_order_leave_that_clip_out_with_the_key_named(tmp_path: Path):
    two_bone(tmp_path / "models" / "bar.glb", times_out_of_order=True)
    folder = content(tmp_path, avatar_line("models/bar.glb", 'Animation "Lift"'), models=())
    spec = load_spec(folder)
    (told,) = spec.problems
    assert "animation 'Bend' is left out" in told.message
    assert "out of order at key 3 (0.5 s after 1 s)" in told.message
    assert (told.line, told.col) == place(folder / "main.scene", '"models/bar.glb"')
    model = Assets(folder).skinned("models/bar.glb")
    assert model.clip_names == ("Lift",)


def test_a_missing_buffer_is_told_and_the_avatar_left_out(tmp_path: Path):
    path = two_bone(tmp_path / "models" / "bar", missing_buffer=True)
    assert path.suffix == ".gltf" and not path.with_suffix(".bin").exists()
    folder = content(tmp_path, "\n".join([GROUND, BALL, avatar_line("models/bar.gltf")]),
                     models=())
    spec = load_spec(folder)
    (told,) = spec.problems
    assert told.is_error
    assert told.message.startswith('cannot load skin "models/bar.gltf"')
    assert "buffer 0 is the file 'bar.bin', which is not there" in told.message
    assert "avatar 'bad' is left out" in told.message
    with pytest.raises(AssetError):
        Assets(folder).skinned("models/bar.gltf")
    with avatar_engine(folder) as engine:
        engine.run(frames=10)
        assert engine.world.get_component(Avatar) == []


def test_a_walker_written_as_gltf_with_its_bin_reads_as_the_glb_does(tmp_path: Path):
    glb = Assets(MODELS).skinned("walker.glb")
    walker(tmp_path / "w.glb")
    again = Assets(tmp_path).skinned("w.glb")
    assert again.clip_names == glb.clip_names
    for a, b in zip(glb.parts, again.parts, strict=True):
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.joints, b.joints)
