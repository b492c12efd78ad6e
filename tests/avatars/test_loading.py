"""glTF skins through the asset layer: every shipped sample loads, and each way real files
go wrong is told at the scene line with the rest of the scene running."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import (
    AT_HAND,
    GROUND,
    MODELS,
    ROOT,
    SAMPLES,
    SHIPPED,
    avatar_engine,
    content,
    entity,
)

from components import Avatar
from engine.animation import Mixer
from engine.assets import AssetError, Assets
from engine.assets.skinned import MAX_INFLUENCES
from engine.scene import load_spec
from tools.gltf_samples import FIVE_INFLUENCES, FUR_SIZE, HOUND, two_bone, walker, write_shipped

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


@pytest.mark.parametrize("path", AT_HAND)
def test_skinned_files_at_hand_load_and_every_clip_plays_as_an_avatar(tmp_path: Path,
                                                                      path: Path):
    """Others' files (when a folder of them is at hand: avatar_helpers): each is an avatar
    whose scene checks without errors, and every clip poses it with finite matrices."""
    model = Assets(path.parent).skinned(path.name)
    assert model.skin_count >= 1 and model.clips
    for part in model.parts:
        np.testing.assert_allclose(part.weights.sum(axis=1), 1.0, atol=1e-6)
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    for clip in model.clip_names:
        mixer.play(1, clip)
        mixer.advance(0.3)
        world, plan = mixer.evaluate()
        assert np.isfinite(plan.palettes(world)).all()
    folder = content(tmp_path, "\n".join([
        GROUND, f'Avatar {{ ID "a" Model "models/{path.name}" Animation '
                f'"{model.clip_names[0]}" GroundFollow 1 }}']), models=(path,))
    assert not [p for p in load_spec(folder).problems if p.is_error]
    with avatar_engine(folder) as engine:
        engine.run(frames=10)
        assert engine.world.has_component(entity(engine, "a"), Avatar)


def test_the_hound_has_its_three_clips_every_joint_and_its_texture():
    hound = Assets(MODELS).skinned("hound.glb")
    assert hound.clip_names == ("Survey", "Walk", "Run")
    assert [hound.node_names[n] for n in hound.palette_nodes] == [j for j, _, _ in HOUND]
    assert len(hound.parts) == 1
    assert hound.parts[0].texture is not None
    assert hound.parts[0].texture.shape == (FUR_SIZE, FUR_SIZE, 4)
    assert hound.warnings == ()
    paths = {(hound.node_names[c.node], c.path, c.interpolation)
             for clip in hound.clips for c in clip.channels}
    assert ("chest", "scale", "LINEAR") in paths and ("ear.L", "rotation", "STEP") in paths


def test_the_shipped_models_are_what_tools_gltf_samples_writes(tmp_path: Path):
    """A change to the generator is not shipped until the files are written again."""
    write_shipped(tmp_path)
    written = sorted(p for p in tmp_path.rglob("*") if p.is_file())
    assert len(written) == 5  # the .bin beside walker_lost_texture.gltf too
    for made in written:
        shipped = ROOT / made.relative_to(tmp_path)
        assert made.read_bytes() == shipped.read_bytes(), shipped


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


def test_texture_coordinates_that_are_not_two_per_vertex_are_told_and_drawn_plain(
        tmp_path: Path):
    """The walker's textured shirt with TEXCOORD_0 read as one number per vertex: told, the
    shirt drawn in its base colour (not from one texel of its texture), the rest as before."""
    import pygltflib

    gltf = pygltflib.GLTF2().load(str(MODELS / "walker.glb"))
    shirt = gltf.meshes[0].primitives[1]
    gltf.accessors[shirt.attributes.TEXCOORD_0].type = "SCALAR"
    gltf.save_binary(str(tmp_path / "walker.glb"))
    model = Assets(tmp_path).skinned("walker.glb")
    (told,) = model.warnings
    assert "TEXCOORD_0 is not two numbers" in told and "base colour" in told
    assert model.parts[1].uv is None and model.parts[1].texture is None
    assert Assets(MODELS).skinned("walker.glb").parts[1].texture is not None
    assert model.parts[0].uv is not None


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


@pytest.mark.parametrize("extension,error", [("KHR_draco_mesh_compression", True),
                                             ("EXT_meshopt_compression", True),
                                             ("KHR_materials_variants", False)])
def test_a_required_extension_not_read_is_told_and_compressed_meshes_refused(
        tmp_path: Path, extension: str, error: bool):
    """A compressed mesh's accessors have no data of their own: read as zeros it would draw
    nothing, silently. Such a file is refused at its line; another extension is told."""
    import pygltflib

    path = two_bone(tmp_path / "models" / "bar.glb")
    gltf = pygltflib.GLTF2().load(str(path))
    gltf.extensionsUsed = gltf.extensionsRequired = [extension]
    gltf.save(str(path))
    folder = content(tmp_path, "\n".join([GROUND, BALL, avatar_line("models/bar.glb")]),
                     models=())
    (told,) = load_spec(folder).problems
    assert told.is_error == error
    assert f"requires {extension}" in told.message if error else \
        f"requires the extension {extension}" in told.message
    assert (told.line, told.col) == place(folder / "main.scene", '"models/bar.glb"')
    with avatar_engine(folder) as engine:
        engine.run(frames=5)
        assert len(engine.world.get_component(Avatar)) == (0 if error else 1)


def test_a_zero_rotation_key_leaves_its_clip_out_with_the_key_named(tmp_path: Path):
    """A zero quaternion is no rotation: slerped or drawn it makes NaN joint matrices."""
    import pygltflib

    path = two_bone(tmp_path / "models" / "bar.glb")
    gltf = pygltflib.GLTF2().load(str(path))
    (bend,) = [a for a in gltf.animations if a.name == "Bend"]
    (channel,) = [c for c in bend.channels if c.target.path == "rotation"]
    accessor = gltf.accessors[bend.samplers[channel.sampler].output]
    view = gltf.bufferViews[accessor.bufferView]
    blob = bytearray(gltf.binary_blob())
    start = view.byteOffset + (accessor.byteOffset or 0) + 16  # the second key
    blob[start:start + 16] = bytes(16)
    gltf.set_binary_blob(bytes(blob))
    gltf.save(str(path))
    folder = content(tmp_path, avatar_line("models/bar.glb", 'Animation "Lift"'), models=())
    (told,) = load_spec(folder).problems
    assert not told.is_error
    assert "animation 'Bend' is left out: node 2 rotation key 2 is the zero quaternion" \
        in told.message
    assert Assets(folder).skinned("models/bar.glb").clip_names == ("Lift",)


def test_foot_ik_bones_out_of_order_are_told_and_that_leg_left_out(tmp_path: Path):
    folder = content(tmp_path, "\n".join([
        GROUND, 'Avatar { ID "w" Model "models/walker.glb" GroundFollow 1 '
                'FootIK ["foot.L" "shin.L" "thigh.L"  "thigh.R" "shin.R" "foot.R"] }']))
    spec = load_spec(folder)
    (told,) = spec.problems
    assert told.is_error
    assert '"shin.L" does not hang below "foot.L"' in told.message
    assert (told.line, told.col) == place(folder / "main.scene", '"shin.L"')
    with avatar_engine(folder) as engine:
        engine.run(frames=3)
        (avatar,) = [a for _, a in engine.world.get_component(Avatar)]
    assert avatar.foot_ik == [("thigh.R", "shin.R", "foot.R")]
