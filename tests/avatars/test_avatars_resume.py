"""Avatars continue from a saved state (serial mode): saved mid-crossfade, mid-queue and
mid-path, on a step, carrying things, with a bone driven, the resumed run poses every joint,
root, capsule and carried object as the run that never stopped, plays every clip at the same
time and ends the same clips at the same moments. The saved file passes ``check`` and is in
canonical form (``fmt`` leaves it as it is).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from avatar_helpers import GROUND, MODELS, content

from app.scene_loading import SceneLoadError, check_path, content_engine, save_state
from components import Name, Transform
from engine.animation import AnimationEnded
from engine.app import Engine
from engine.scene import format_scene, load_scene
from systems.avatars import AvatarSystem

pytest.importorskip("engine.physics.ode3d")

#: The walker's own script: a crossfade at frame 20 (0.5 s), at frame 90 a wave with two
#: clips queued after it; what ended is kept (and saved) in a local.
WALKER_SCRIPT = """\
local frame, ended = 0, {}
function onUpdate(dt)
  frame = frame + 1
  if frame == 20 then self:blend({Walk = 0.2, Run = 0.8}, {fade = 0.5}) end
  if frame == 90 then
    self:play("Wave", {fade = 0.2})
    self:queue({Walk = 1, Run = 0}, {fade = 0.3})
    self:queue("Run", {speed = 1.3})
  end
end
function onAnimationEnd(clip) ended[#ended + 1] = clip end
"""

#: The scene's script: the walker's left hand held at a world pose from frame 30 to 200.
SCENE_SCRIPT = """\
local frame, walker = 0, nil
function onStart() walker = find("walker") end
function onUpdate(dt)
  frame = frame + 1
  if frame == 30 then walker:driveBone("hand.L", {-0.3, 1.2, 1.1}, {1, 0, 0, 0}) end
  if frame == 200 then walker:releaseBone("hand.L") end
end
"""

SCENE = "\n".join([
    "World { TimeStep 0.01 }",
    GROUND,
    # a step up 0.12 m across the walker's path: ground following smooths it over 0.1 s
    'Object { ID "step" Dynamic 0 Position [0 2.6 0.06] Size [3 4 0.12] '
    'PhysicalAttributes { Geometry { Primitive "box" } } }',
    'Object { ID "crate" Position [3 0 1] Size [0.3 0.25 0.25] '
    'PhysicalAttributes { Mass 2 Geometry { Primitive "box" } } }',
    'Object { ID "lamp" Kinematic 1 Position [3 1 1] Size [0.1] '
    'PhysicalAttributes { Geometry { Primitive "sphere" } } }',
    'Avatar { ID "walker" Model "models/walker.glb" Position [0 0 0] '
    'Blend ["Walk" "Run"] Weights [1 0] Fade 0.4 Clip { Name "Wave" Loop 0 } '
    'Path [0 0 0  0 4 0  3 4 0  3 0 0] GroundFollow 1 '
    'FootIK ["thigh.L" "shin.L" "foot.L"  "thigh.R" "shin.R" "foot.R"] Capsule [0.4 1.0] '
    'Hold { Object "crate" Bone "hand.R" Offset [-0.17 -0.12 0] } '
    'Hold { Object "lamp" Bone "head" Offset [0 0.3 0] Orientation [0 0 30] } '
    'Script "scripts/walker.lua" }',
    'Avatar { ID "hound" Model "models/hound.glb" Scale 0.01 Position [-3 0 0] '
    'Animation "Walk" Clip { Name "Walk" GroundSpeed 1.2 } '
    'Path [-3 0 0  -4 2 0  -2 2 0] GroundFollow 1 Capsule [0.35 0.5] }',
    'Script "scripts/scene.lua"',
])

SAVES = (45, 100, 250)  # mid-crossfade; mid-wave with two queued; the queue playing on
LATER = (1, 7, 60, 160, 260)  # frames after the save at which the runs are compared


def by_name(engine: Engine) -> dict[str, int]:
    return {n.id: e for e, n in engine.world.get_component(Name)}


def observe(engine: Engine, figures: tuple[str, ...] = ("walker", "hound"),
            things: tuple[str, ...] = ("crate", "lamp")) -> dict[str, Any]:
    """What the avatars look like now: joint matrices, roots, capsules, carried objects,
    and each clip's time and weight."""
    system = engine.resource(AvatarSystem)
    names = by_name(engine)
    seen: dict[str, Any] = {}
    for name in figures:
        entity = names[name]
        first = system.palettes.offsets[entity]
        joints = system.mixer.animators[entity].rig.joints
        seen[f"{name} joints"] = system.palettes.matrices[first:first + joints].copy()
        seen[f"{name} clips"] = system.mixer.playing(entity)
    for name in (*figures, *(f"{f}:capsule" for f in figures), *things):
        t = engine.world.component_for_entity(names[name], Transform)
        seen[name] = np.concatenate([t.position, t.orientation])
    return seen


def run(engine: Engine, frames: int, marks: set[int], ended: list,
        look: Any = observe) -> dict[int, Any]:
    """Run ``frames`` frames, observing (``look``) after each frame in ``marks``; the clips
    that end are appended to ``ended`` (time, avatar, clip)."""
    engine.events.subscribe(AnimationEnded, lambda ev: ended.append(
        (round(engine.time, 9), engine.world.component_for_entity(ev.avatar, Name).id,
         ev.clip)))
    seen = {}
    for frame in range(1, frames + 1):
        engine.step()
        if frame in marks:
            seen[frame] = look(engine)
    return seen


def assert_same(want: dict[str, Any], got: dict[str, Any], when: str) -> None:
    """Clips (name, time, weight) exactly; matrices and poses within 1e-9."""
    assert got.keys() == want.keys()
    for what in want:
        if what.endswith("clips"):
            assert got[what] == want[what], f"{what} {when}"
        else:
            np.testing.assert_allclose(got[what], want[what], rtol=0, atol=1e-9,
                                       err_msg=f"{what} {when}")


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return content(tmp_path_factory.mktemp("sim"), SCENE,
                   {"walker.lua": WALKER_SCRIPT, "scene.lua": SCENE_SCRIPT},
                   models=(MODELS / "walker.glb", MODELS / "hound.glb"))


@pytest.fixture(scope="module")
def straight(folder: Path) -> tuple[dict[int, Any], list]:
    """The run that never stops, observed at every frame the resumed runs are."""
    ended: list = []
    with content_engine(folder) as engine:
        seen = run(engine, max(SAVES) + max(LATER),
                   {save + k for save in SAVES for k in LATER}, ended)
    return seen, ended


@pytest.mark.parametrize("save", SAVES)
def test_a_resumed_avatar_moves_as_if_never_stopped(folder: Path, straight: tuple,
                                                    save: int, tmp_path: Path) -> None:
    saved = tmp_path / "saves" / "state.scene"
    saved.parent.mkdir()
    with content_engine(folder) as engine:
        engine.run(frames=save)
        save_state(engine, saved)
    ended: list = []
    with content_engine(saved) as engine:
        again = run(engine, max(LATER), set(LATER), ended)
    seen, straight_ended = straight
    for k in LATER:
        assert_same(seen[save + k], again[k], f"{k} frames after the save")
    start_at, end_at = round(save * 0.01, 9), round((save + max(LATER)) * 0.01, 9)
    assert ended == [e for e in straight_ended if start_at < e[0] <= end_at]
    if save == 100:  # the wave ended, then the blend queued after it (both its clips)
        assert [clip for _, who, clip in ended if who == "walker"] == ["Wave", "Walk", "Run"]


def test_the_saved_state_says_what_it_resumes_and_is_checked_and_canonical(
        folder: Path, tmp_path: Path) -> None:
    """Saved at frame 100: the wave fading in, the blend it replaced fading out, two
    requests queued, a step being smoothed, the hand driven, two things carried."""
    saved = tmp_path / "saves" / "state.scene"
    saved.parent.mkdir()
    with content_engine(folder) as engine:
        engine.run(frames=100)
        save_state(engine, saved)
    assert check_path(saved) == 0
    assert format_scene(saved) == saved.read_text(encoding="utf-8")  # fmt changes nothing
    state = {b.get("Owner"): b for b in load_scene(saved).blocks("AvatarState")}
    walker = state["walker"]
    groups = walker.blocks("Group")
    assert [g.get("Current") for g in groups] == [0, 1]
    fading = groups[0].blocks("Layer") + groups[1].blocks("Layer")
    assert [(layer.get("Clip"), layer.get("FadeTo")) for layer in fading] == [
        ("Walk", 0.0), ("Run", 0.0), ("Wave", 1.0)]
    assert all(0 < layer.get("FadeTime") < layer.get("FadeLength") for layer in fading)
    assert [q.get("Clips") for q in walker.blocks("Queued")] == [("Walk", "Run"), ("Run",)]
    assert walker.get("Waypoint") == 1 and walker.get("StepOffset") != 0.0
    assert [h.get("Object") for h in walker.blocks("Hold")] == ["crate", "lamp"]
    assert walker.blocks("Hold")[0].get("Last") is not None  # the crate moves on with the hand
    assert [d.get("Bone") for d in walker.blocks("Drive")] == ["hand.L"]
    assert state["hound"].get("CapsulePosition") is not None


def test_a_broken_avatar_state_is_told_at_its_line(folder: Path, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    """A clip or bone the model lacks: told with its line and left out, the rest resumes;
    a number out of range: an error at its line, the file does not start."""
    saved = tmp_path / "saves" / "state.scene"
    saved.parent.mkdir()
    with content_engine(folder) as engine:
        engine.run(frames=100)
        save_state(engine, saved)
    text = saved.read_text(encoding="utf-8")
    lines = text.splitlines()
    wave = lines.index('      Clip "Wave"') + 1
    drive = next(i for i, line in enumerate(lines, 1) if line == '    Bone "hand.L"')
    saved.write_text(text.replace('Clip "Wave"', 'Clip "Wavy"').replace(
        'Bone "hand.L"', 'Bone "hand.X"'), encoding="utf-8")
    with content_engine(saved) as engine:
        engine.run(frames=5)
        system = engine.resource(AvatarSystem)
        walker = by_name(engine)["walker"]
        # the blend it replaced fades out, the queue goes on (the wave is gone)
        assert [name for name, _, _ in system.mixer.playing(walker)] == ["Walk", "Run"] * 2
        assert not system.figures[walker].drives
    told = capsys.readouterr().err
    assert f'{saved}:{wave}:' in told and 'has no clip "Wavy"' in told
    assert "did you mean" in told and f'{saved}:{drive}:' in told and 'no bone "hand.X"' in told
    phase = next(line for line in lines if line.strip().startswith("Phase "))
    saved.write_text(text.replace(phase, "    Phase 1.5", 1), encoding="utf-8")
    with pytest.raises(SceneLoadError, match=r"Phase is 0\.\.1, got 1\.5"):
        content_engine(saved)


#: A script that makes an avatar carrying a box it makes with it, at frame 10.
SPAWNER = """\
local frame = 0
function onUpdate(dt)
  frame = frame + 1
  if frame == 10 then
    spawn([[
      Object { ID "box" Position [1 1 1] Size [0.2]
        PhysicalAttributes { Mass 1 Geometry { Primitive "box" } } }
      Avatar { ID "visitor" Model "models/walker.glb" Position [1 0 0] Animation "CarryWalk"
        Path [1 0 0  1 3 0  -1 3 0] GroundFollow 1 Capsule [0.4 1.0]
        Hold { Object "box" Bone "hand.R" Offset [0 -0.12 0] } }
    ]])
  end
end
"""


def test_an_avatar_a_script_made_is_saved_and_continues(tmp_path: Path) -> None:
    folder = content(tmp_path / "sim", "\n".join([
        "World { TimeStep 0.01 }", GROUND, 'Script "scripts/spawner.lua"']),
        {"spawner.lua": SPAWNER})
    saved = tmp_path / "state.scene"

    def look(engine: Engine) -> dict[str, Any]:
        return observe(engine, ("visitor",), ("box",))

    with content_engine(folder) as engine:
        straight = run(engine, 60 + max(LATER), {60 + k for k in LATER}, [], look)
    with content_engine(folder) as engine:
        engine.run(frames=60)
        save_state(engine, saved)
    with content_engine(saved) as engine:
        again = run(engine, max(LATER), set(LATER), [], look)
    for k in LATER:
        assert_same(straight[60 + k], again[k], f"{k} frames after the save")
    state = load_scene(saved)
    assert [b.get("ID") for b in state.blocks("Avatar")] == ["visitor"]
    (visitor,) = state.blocks("AvatarState")
    assert [h.get("Object") for h in visitor.blocks("Hold")] == ["box"]
