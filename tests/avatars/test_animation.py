"""Clip sampling, blending, queues and crossfades, checked against joint matrices worked
out by hand for the two-bone bar and against the channel-by-channel reference."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import GROUND, MODELS, SAMPLES, avatar_engine, avatars, content, entity

from engine.animation import AnimationEnded, AnimationError, Mixer
from engine.animation.mixer import fast_slerp
from engine.animation.sampling import clip_pose, joint_matrices
from engine.animation.skinning import skin
from engine.assets import Assets
from engine.rotation import compose, slerp
from tools.gltf_samples import two_bone

DT = 1 / 64  # exact in binary: phases add up without rounding


def played(model, clip: str, t: float) -> np.ndarray:
    """The batched mixer's joint matrices of ``model`` playing ``clip`` once, ``t`` s in."""
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    mixer.play(1, clip, loop=False)
    for _ in range(round(t / DT)):
        mixer.advance(DT)
    world, _ = mixer.evaluate()
    return world[mixer.animators[1].row + model.palette_nodes] @ model.inverse_bind


@pytest.fixture(scope="module")
def bars(tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    folder = tmp_path_factory.mktemp("bars")
    for kind in ("LINEAR", "STEP", "CUBICSPLINE"):
        two_bone(folder / f"{kind}.glb", interpolation=kind)
    assets = Assets(folder)
    return {kind: assets.skinned(f"{kind}.glb") for kind in ("LINEAR", "STEP", "CUBICSPLINE")}


def by_hand(angle_deg: float, lift: float = 0.0) -> np.ndarray:
    """The bar's palette with the tip turned ``angle_deg`` about Z and the root raised
    ``lift``: root = T(0, lift, 0); tip = T(0, lift, 0) T(0, 1, 0) Rz T(0, -1, 0)."""
    a = math.radians(angle_deg)
    rz = np.eye(4)
    rz[:2, :2] = [[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]
    up = np.eye(4)
    up[1, 3] = lift
    to_tip, back = np.eye(4), np.eye(4)
    to_tip[1, 3], back[1, 3] = 1.0, -1.0
    return np.stack([up, up @ to_tip @ rz @ back])


def bend_angle(kind: str, t: float) -> float:
    """Bend's tip angle at ``t`` (keys 0, 45, 90 degrees at 0, 0.5, 1 s)."""
    if t >= 1.0:
        return 90.0
    k, s = divmod(t / 0.5, 1.0)
    if kind == "STEP":
        return 45.0 * k
    if kind == "LINEAR":  # slerp about one axis: the angle is linear
        return 45.0 * (k + s)
    # zero tangents: p = (1 - h) q0 + h q1 with h = 3s^2 - 2s^3, then normalised
    h = 3 * s * s - 2 * s ** 3
    q0 = np.array([math.cos(math.radians(22.5 * k)), math.sin(math.radians(22.5 * k))])
    q1 = np.array([math.cos(math.radians(22.5 * (k + 1))), math.sin(math.radians(22.5 * (k + 1)))])
    q = (1 - h) * q0 + h * q1
    return 2 * math.degrees(math.atan2(q[1], q[0]))


@pytest.mark.parametrize("kind", ["LINEAR", "STEP", "CUBICSPLINE"])
@pytest.mark.parametrize("t", [0.0, 0.125, 0.25, 0.5, 0.75, 1.0, 1.5])
def test_reference_and_batched_palettes_match_the_bar_worked_by_hand(bars, kind: str, t: float):
    model = bars[kind]
    expected = by_hand(bend_angle(kind, t))
    reference = joint_matrices(model, compose(*clip_pose(model, "Bend", t)))
    np.testing.assert_allclose(reference, expected, atol=1e-6)
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    mixer.play(1, "Bend", loop=False)
    steps = round(min(t, 1.0) / DT)
    for _ in range(steps):
        mixer.advance(DT)
    world, _ = mixer.evaluate()
    animator = mixer.animators[1]
    batched = world[animator.row + model.palette_nodes] @ model.inverse_bind
    np.testing.assert_allclose(batched, expected, atol=1e-6)


def test_the_cpu_reference_skins_the_bar_as_worked_by_hand(bars):
    model = bars["LINEAR"]
    part = model.parts[0]
    palette = by_hand(90.0)
    positions, normals = skin(part.vertices, part.normals, part.joints, part.weights, palette)
    # the top ring (y = 2) turns 90 degrees about Z around the tip at (0, 1, 0)
    top = part.vertices[:, 1] == 2.0
    x, y = part.vertices[top, 0], part.vertices[top, 1]
    np.testing.assert_allclose(positions[top, 0], -(y - 1.0), atol=1e-6)
    np.testing.assert_allclose(positions[top, 1], 1.0 + x, atol=1e-6)
    # the middle ring (y = 1) is half root, half tip: the average of the two placements
    mid = part.vertices[:, 1] == 1.0
    v = part.vertices[mid]
    expected = 0.5 * v + 0.5 * np.stack([-(v[:, 1] - 1.0) + 0 * v[:, 0], 1.0 + v[:, 0],
                                         v[:, 2]], axis=1)
    np.testing.assert_allclose(positions[mid], expected, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-6)


@pytest.fixture(scope="module")
def strip_model() -> object:
    return Assets(SAMPLES).skinned("strip.gltf")


@pytest.mark.parametrize("t,angle", [(0.25, 15.0), (0.75, 52.5), (1.5, 75.0), (2.25, 17.5),
                                     (2.875, -10.0)])
def test_the_strip_under_turned_joints_is_skinned_as_worked_by_hand(strip_model, t: float,
                                                                    angle: float):
    """tools.gltf_samples.strip: the tip joint sits at c = (1, 1.5, 0) under a base turned
    90 degrees about Z (inverse bind matrices with a rotation), and turns about Z through
    0, 30, 75, 75, -40, 0 degrees at 0, 0.5, 1, 2, 2.5, 3 s; the angles above are those keys
    interpolated by hand (slerp about one axis: linear in the angle). A vertex at height y
    has weight w = (y - 0.5) / 2 on the tip and lands at (1 - w) v + w (Rz (v - c) + c);
    the tip's skinning matrix is T(c) Rz T(-c), the base's the identity."""
    model = strip_model
    assert model.warnings == () and model.clip_names == ("Sway",)
    part = model.parts[0]
    w = (part.vertices[:, 1:2] - 0.5) / 2.0
    np.testing.assert_array_equal(part.joints[:, :2], np.tile([0, 1], (10, 1)))  # strided
    np.testing.assert_allclose(part.weights[:, :2], np.hstack([1 - w, w]), atol=1e-7)
    a = math.radians(angle)
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    c = np.array([1.0, 1.5, 0.0])
    tip = np.eye(4)
    tip[:3, :3], tip[:3, 3] = rz, c - rz @ c
    expected = (1 - w) * part.vertices + w * ((part.vertices - c) @ rz.T + c)
    reference = joint_matrices(model, compose(*clip_pose(model, "Sway", t)))
    batched = played(model, "Sway", t)
    for palette in (reference, batched):
        np.testing.assert_allclose(palette, np.stack([np.eye(4), tip]), atol=1e-6)
        got, _ = skin(part.vertices, part.normals, part.joints, part.weights, palette)
        np.testing.assert_allclose(got, expected, atol=1e-6)


@pytest.mark.parametrize("weight", [0.0, 0.5, 1.0])
def test_blending_slerps_rotations_and_lerps_translations_by_weight(bars, weight: float):
    """Bend (the tip turns 90 degrees in 1 s) blended with Lift (the tip at rest, the root
    up 1 m in 2 s), in step: after one second both are at phase p, the weighted mean of
    their rates (1/s and 1/2 per s); the tip turns w * 90 p, the root rises (1 - w) p."""
    model = bars["LINEAR"]
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    mixer.blend(1, {"Bend": weight, "Lift": 1.0 - weight}, loop=False)
    for _ in range(64):
        mixer.advance(DT)
    world, _ = mixer.evaluate()
    palette = world[mixer.animators[1].row + model.palette_nodes] @ model.inverse_bind
    p = weight * 1.0 + (1.0 - weight) * 0.5
    np.testing.assert_allclose(palette, by_hand(weight * 90.0 * p, (1.0 - weight) * p),
                               atol=1e-6)


def test_the_fast_slerp_is_the_engines_slerp():
    rng = np.random.default_rng(3)
    q0 = rng.normal(size=(500, 4))
    q1 = rng.normal(size=(500, 4))
    q0 /= np.linalg.norm(q0, axis=1, keepdims=True)
    q1 /= np.linalg.norm(q1, axis=1, keepdims=True)
    q1[:10] = q0[:10]  # no angle between: the near branch
    t = rng.uniform(size=500)
    np.testing.assert_allclose(fast_slerp(q0, q1, t), slerp(q0, q1, t), atol=1e-12)


@pytest.mark.parametrize("t", [0.0, 0.5, 1.25, 2.5, 3.75, 4.5, 6.0])
def test_batched_key_slerp_takes_the_short_way_and_holds_repeated_keys(bars, t: float):
    """Keys the evaluator's precomputed slerp must treat as the reference does: a key
    repeated (no angle: a hold), the same rotation with its sign flipped (the short way is
    no turn at all), and two turns more than 90 degrees apart in 4D."""
    from dataclasses import replace

    from engine.assets.skinned import AnimationClip, Channel

    model = bars["LINEAR"]
    rng = np.random.default_rng(7)
    q, r = rng.normal(size=(2, 4))
    q, r = q / np.linalg.norm(q), r / np.linalg.norm(r)
    r *= np.sign(q @ r)  # so that -q to r, and -r to q, are the long way round in 4D
    keys = np.array([q, q, -q, r, -r, q])
    tip = model.node("tip")
    clip = AnimationClip("Keys", 5.0, (Channel(tip, "rotation", "LINEAR",
                                               np.arange(6.0), keys),))
    model = replace(model, clips=(clip,))
    expected = joint_matrices(model, compose(*clip_pose(model, "Keys", t)))
    got = played(model, "Keys", t)
    np.testing.assert_allclose(got, expected, atol=1e-9)


@pytest.mark.parametrize("t,x", [(0.5, 0.8125), (1.0, 1.25), (2.0, 1.0)])
def test_cubic_spline_tangents_are_the_out_of_one_key_and_the_in_of_the_next(bars, t: float,
                                                                             x: float):
    """glTF's Hermite spline over a 2 s interval, worked by hand: keys x = 0 (out-tangent 2)
    and x = 1 (in-tangent -1) above the tip's rest height; the other two tangents (7, 9)
    must not count. At s = t / 2,
    x = 2 (s^3 - 2 s^2 + s) 2 + (3 s^2 - 2 s^3) 1 + 2 (s^3 - s^2) (-1)."""
    from dataclasses import replace

    from engine.assets.skinned import AnimationClip, Channel

    model = bars["LINEAR"]
    # along Y (up: sideways travel would be taken for root motion and taken off)
    values = np.array([[[0, 7.0, 0], [0, 1.0, 0], [0, 2.0, 0]],   # in, value, out
                       [[0, -1.0, 0], [0, 2.0, 0], [0, 9.0, 0]]])
    clip = AnimationClip("Slide", 2.0, (Channel(model.node("tip"), "translation",
                                                "CUBICSPLINE", np.array([0.0, 2.0]), values),))
    model = replace(model, clips=(clip,))
    reference = joint_matrices(model, compose(*clip_pose(model, "Slide", t)))
    batched = played(model, "Slide", t)
    for palette in (reference, batched):  # the tip rose x above its rest place
        np.testing.assert_allclose(palette[1, :3, 3], (0.0, x, 0.0), atol=1e-9)


def test_the_batched_evaluation_of_many_avatars_is_the_reference_for_each():
    hound = Assets(MODELS).skinned("hound.glb")
    walker = Assets(MODELS).skinned("walker.glb")
    mixer = Mixer()
    plan = []
    for key in range(12):
        model = (hound, walker)[key % 2]
        mixer.add(key, mixer.library.rig_for(model))
        clip = model.clip_names[key % len(model.clip_names)]
        mixer.play(key, clip, speed=0.5 + 0.1 * key)
        plan.append((model, clip, 0.5 + 0.1 * key))
    for _ in range(37):
        mixer.advance(DT)
    world, _ = mixer.evaluate()
    for key, (model, clip, speed) in enumerate(plan):
        duration = model.clip(clip).duration
        t = (37 * DT * speed / duration % 1.0) * duration
        expected = joint_matrices(model, compose(*clip_pose(model, clip, t)))
        if clip in ("Walk", "Run", "CarryWalk") and model is walker:  # root motion taken off
            continue
        row = mixer.animators[key].row
        got = world[row + model.palette_nodes] @ model.inverse_bind
        np.testing.assert_allclose(got, expected, atol=1e-9)


def test_a_queued_clip_starts_when_the_first_ends_and_crossfades_in(bars):
    model = bars["LINEAR"]
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    mixer.play(1, "Bend", loop=False)
    mixer.queue(1, "Lift", fade=0.25)
    ends = []
    for frame in range(1, 100):
        for ended in mixer.advance(DT):
            ends.append((frame, ended))
        weights = {name: w for name, _, w in mixer.playing(1)}
        if frame < 64:
            assert weights == {"Bend": 1.0}
        elif frame == 64:  # Bend ends this frame; Lift starts at weight 0
            assert weights == {"Bend": 1.0, "Lift": 0.0}
        elif frame < 64 + 16:  # a 0.25 s fade is 16 frames
            k = (frame - 64) / 16
            assert weights == pytest.approx({"Bend": 1.0 - k, "Lift": k})
        else:
            assert weights == {"Lift": 1.0}
    assert ends == [(64, AnimationEnded(1, "Bend"))]


def test_a_looping_clip_with_something_queued_ends_at_the_end_of_its_loop(bars):
    model = bars["LINEAR"]
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    mixer.play(1, "Lift")  # loops, 2 s
    for _ in range(40):
        mixer.advance(DT)
    mixer.queue(1, "Bend")
    frames = [f for f in range(41, 400) for e in mixer.advance(DT) if e.clip == "Lift"]
    assert frames == [128]  # the end of its first loop, not one frame later or earlier


def test_play_crossfades_over_the_time_given_and_unknown_clips_name_the_known(bars):
    model = bars["LINEAR"]
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(model))
    mixer.play(1, "Lift")
    mixer.advance(DT)
    mixer.play(1, "Bend", fade=0.5)
    for _ in range(16):
        mixer.advance(DT)
    assert {n: w for n, _, w in mixer.playing(1)} == pytest.approx({"Lift": 0.5, "Bend": 0.5})
    with pytest.raises(AnimationError, match=r"no clip 'Jog' \(its clips: Bend, Lift\)"):
        mixer.play(1, "Jog")


def test_blended_clips_keep_one_phase_whatever_their_lengths():
    walker = Assets(MODELS).skinned("walker.glb")
    mixer = Mixer()
    mixer.add(1, mixer.library.rig_for(walker))
    mixer.blend(1, {"Walk": 0.5, "Run": 0.5})  # 1.0 s and 0.7 s long
    for _ in range(20):
        mixer.advance(DT)
    (walk, t_walk, _), (run, t_run, _) = mixer.playing(1)
    assert (walk, run) == ("Walk", "Run")
    assert t_walk / 1.0 == pytest.approx(t_run / walker.clip("Run").duration)
    # the phase moves at the weighted mean of the two rates: (1/1.0 + 1/0.7) / 2 per second
    rate = 0.5 * (1 / 1.0 + 1 / walker.clip("Run").duration)
    assert t_walk == pytest.approx(20 * DT * rate)


def test_a_blend_is_the_same_whatever_order_its_weights_are_given_in():
    """Layers are folded in one by one, and slerps taken in turn depend on their order
    (1e-5 here); a Lua table has no order that repeats from one run to the next. The
    model's order is used."""
    walker = Assets(MODELS).skinned("walker.glb")
    poses = []
    for weights in ({"Walk": 0.3, "Run": 0.6, "Idle": 0.1},
                    {"Idle": 0.1, "Run": 0.6, "Walk": 0.3}):
        mixer = Mixer()
        mixer.add(1, mixer.library.rig_for(walker))
        mixer.blend(1, weights)
        mixer.advance(0.37)
        poses.append(mixer.evaluate()[0])
        assert [name for name, _, _ in mixer.playing(1)] == ["Idle", "Walk", "Run"]
    np.testing.assert_array_equal(poses[0], poses[1])


SCRIPT = """
ends = {}
function onStart()
  self:play("Wave", {fade = 0})
  self:queue("Idle", {fade = 0.25})
end
function onAnimationEnd(clip)
  ends[#ends + 1] = clip .. "@" .. string.format("%.6f", time())
end
"""

SCENE_SCRIPT = """
heard = {}
function onAnimationEnd(avatar, clip)
  heard[#heard + 1] = avatar:getName() .. ":" .. clip
end
"""


def test_lua_hears_onanimationend_in_the_frame_the_clip_ends(tmp_path: Path):
    folder = content(tmp_path, "\n".join([
        GROUND, 'Avatar { ID "w" Model "models/walker.glb" Script "scripts/w.lua" }',
        'Script "scripts/scene.lua"']), {"w.lua": SCRIPT, "scene.lua": SCENE_SCRIPT})
    with avatar_engine(folder, dt=DT) as engine:
        events = []
        engine.events.subscribe(AnimationEnded, lambda e: events.append((engine.frame, e)))
        engine.run(frames=150)
        from services.scripting.runtime import ScriptRuntime

        runtime = engine.resource(ScriptRuntime)
        (own,) = [s for s in runtime.scripts if s.name == "scripts/w.lua"]
        (scene,) = [s for s in runtime.scripts if s.name == "scripts/scene.lua"]
        ends = list(own.env.ends.values())
        heard = list(scene.env.heard.values())
        w = entity(engine, "w")
    # Wave is 1.5 s = 96 frames; it starts in frame 0's SCRIPT phase and advances from
    # frame 0, so its 96th advance (frame 95) ends it; scripts hear it that frame
    assert [(f, e.clip, e.avatar == w) for f, e in events] == [(95, "Wave", True)]
    assert ends == [f"Wave@{95 * DT:.6f}"]
    assert heard == ["w:Wave"]


def test_a_queue_in_the_scene_file_plays_in_turn_with_its_fade(tmp_path: Path):
    """``Queue`` and ``Fade`` as written in the scene: Wave (1.5 s, played once) ends in
    frame 95 and Idle crossfades in over 0.25 s (16 frames); Idle (2 s, played once by its
    Clip block) ends 128 frames later and Walk crossfades in the same way."""
    folder = content(tmp_path, "\n".join([
        GROUND, 'Avatar { ID "w" Model "models/walker.glb" Animation "Wave" Loop 0 '
                'Queue ["Idle" "Walk"] Fade 0.25 Clip { Name "Idle" Loop 0 } }']))
    with avatar_engine(folder, dt=DT) as engine:
        w = entity(engine, "w")
        mixer = avatars(engine).mixer
        ends, weights = [], {}
        engine.events.subscribe(AnimationEnded, lambda e: ends.append((engine.frame, e.clip)))
        for frame in range(95 + 128 + 17):
            engine.run(frames=1)
            weights[frame] = {name: v for name, _, v in mixer.playing(w)}
    assert ends == [(95, "Wave"), (95 + 128, "Idle")]
    for first, (before, after) in ((95, ("Wave", "Idle")), (95 + 128, ("Idle", "Walk"))):
        assert weights[first - 1] == {before: 1.0}
        assert weights[first] == {before: 1.0, after: 0.0}
        for k in range(1, 16):
            assert weights[first + k] == pytest.approx({before: 1 - k / 16, after: k / 16})
        assert weights[first + 16] == {after: 1.0}


@pytest.mark.parametrize(("given", "rate"), [("", 0.5), ("Speed 2", 2.0)])
def test_the_first_clip_plays_at_its_clip_blocks_speed_unless_the_avatar_gives_one(
        tmp_path: Path, given: str, rate: float):
    folder = content(tmp_path, "\n".join([
        GROUND, f'Avatar {{ ID "w" Model "models/walker.glb" Animation "Walk" {given} '
                'Clip { Name "Walk" Speed 0.5 Loop 0 } }']))
    with avatar_engine(folder, dt=DT) as engine:
        engine.run(frames=40)  # 0.625 s
        system = avatars(engine)
        ((clip, t, _),) = system.mixer.playing(entity(engine, "w"))
        ended = system.mixer.groups.ended[system.mixer.animators[entity(engine, "w")].group]
    assert clip == "Walk" and t == pytest.approx(min(40 * DT * rate, 1.0))
    assert ended == (rate == 2.0)  # Walk is 1 s long and played once (Loop 0)
