"""Avatars on join nodes: a server process animates a walker (its script plays, blends and
queues clips; it walks a path with its feet on the ground by IK); nodes in this process,
joining a second into it, draw the skeleton the server drew at the frames they show."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from engine.animation import Palettes
from engine.animation.skinning import skin
from engine.assets.skinned import load_skinned
from engine.rotation import slerp
from services.net.bones import palette_matrices, palette_poses
from services.net.client import NetClient
from services.net.codec import POSITION_STEP, ROTATION_SCALE
from services.net.protocol import content_fingerprint
from tests.avatars.avatar_helpers import GROUND, MODELS, content
from tests.net.net_helpers import free_port, join_args, processes, serve_args, stats

DT = 1 / 60
SCENE = f"""World {{ Gravity [0 0 -9.81] TimeStep 1/60 }}
{GROUND}
Object {{ ID "ramp" Dynamic 0 Position [0 3 0.1] Orientation [6 0 0] Size [4 3 0.2]
  VisualAttributes {{ Geometry {{ Primitive "box" }} }}
  PhysicalAttributes {{ Geometry {{ Primitive "box" }} }} }}
Avatar {{ ID "walker" Model "models/walker.glb" Position [0 -1 0] Animation "Walk"
  Path [0 -1 0  0 6 0  2 6 0  2 -1 0] GroundFollow 1
  FootIK ["thigh.L" "shin.L" "foot.L"  "thigh.R" "shin.R" "foot.R"] Capsule [0.3 1.0]
  Script "scripts/walker.lua" }}
Camera {{ ID "eye" Position [6 -6 4] LookAt [0 2 0.5] }}
Display {{ ID "wall" LowerLeft [-2 8 0] LowerRight [2 8 0] UpperLeft [-2 8 3] Eye [0 0 1.6] }}
"""
# the script's calls happen while the nodes watch: timed from the second node's joining
# (the "cue", a measure in the server's --stats), however long joining took
WALKER_LUA = """
local done, joined, cue = {}, 0, nil
on("userJoined", function(user)
  joined = joined + 1
  if joined == 2 then cue = time(); measure("cue", cue) end
end)
function onUpdate(dt)
  if cue == nil then return end
  local t = time() - cue
  if t > 0.5 and not done.blend then done.blend = true
    self:blend({Walk = 0.4, Run = 0.6}, {fade = 0.4}) end
  if t > 1.5 and not done.wave then done.wave = true
    self:play("Wave", {fade = 0.3}); self:queue({Walk = 1}, {fade = 0.3}) end
end
"""
# the server's own record of what it drew: this frame's joint matrices at its time
RECORDER = """
from pathlib import Path

import numpy as np

from engine import Phase
from engine.animation import Palettes
from engine.system import System

OUT = Path(__file__).resolve().parents[2] / "server_palettes.npz"


class Recorder(System):
    phase = Phase.RENDER

    def __init__(self):
        self.drawn = {}

    def run(self, engine, dt):
        palettes = engine.try_resource(Palettes)
        if palettes is not None and palettes.offsets:
            self.drawn[engine.frame] = (engine.physics.snapshot.time, palettes.matrices.copy())

    def shutdown(self, engine):
        frames = sorted(self.drawn)
        np.savez(OUT, frames=np.array(frames), matrices=np.stack(
            [self.drawn[f][1] for f in frames]), times=np.array([self.drawn[f][0]
                                                                 for f in frames]))


def build(engine):
    engine.add_system(Recorder())
"""


def _content(root: Path) -> Path:
    folder = content(root / "content", SCENE, {"walker.lua": WALKER_LUA})
    (folder / "systems").mkdir()
    (folder / "systems" / "recorder.py").write_text(RECORDER)
    return folder


def _node(port: int, folder: Path, user: str, *flags: Any) -> tuple[Any, Any, NetClient]:
    """A node engine in this process (as ``colosseum join`` builds it), joined."""
    from app.cli import build_parser
    from app.cli_net import node_engine

    args = build_parser().parse_args([str(a) for a in join_args(port, user, *flags,
                                                                path=folder)])
    client = NetClient(args.address, user, content_fingerprint(folder), args.display)
    made = node_engine(args, client, client.join(), folder)
    assert not isinstance(made, int)
    engine, node, scene = made
    scene.instantiate(engine)
    engine.start()
    return engine, node.system, client


def _skinned(matrices: np.ndarray) -> np.ndarray:
    """Every vertex of the walker posed by ``matrices`` (the CPU skinning reference)."""
    model = load_skinned(MODELS / "walker.glb")
    palette = np.zeros((len(matrices), 4, 4))
    palette[:, :3] = matrices
    palette[:, 3, 3] = 1.0
    return np.concatenate([skin(p.vertices, p.normals, p.joints, p.weights, palette)[0]
                           for p in model.parts])


@pytest.mark.slow
def test_nodes_draw_the_skeleton_the_server_animates(tmp_path: Path) -> None:
    folder = _content(tmp_path)
    port = free_port()
    # per node: (frame shown, time shown, the frames it held, joint matrices)
    shown: dict[str, list[tuple[int, float, list[int], np.ndarray]]] = {"wall": [], "eye": []}
    with processes(tmp_path) as procs:
        server = procs.start("server", *serve_args(port, "--seconds", 6, "--stats",
                                                   tmp_path / "server.json", content=folder))
        procs.wait_log(server, "serving")
        time.sleep(1.0)  # the nodes join late: the walker is mid-stride
        nodes = {"wall": _node(port, folder, "wall", "--display", "wall"),
                 "eye": _node(port, folder, "eye")}
        try:
            end = time.monotonic() + 3.0
            while time.monotonic() < end:
                for name, (engine, follow, _) in nodes.items():
                    engine.step()
                    palettes = engine.resource(Palettes)
                    if palettes.offsets and follow.shown_frame >= 0:
                        held = [f.frame for f in follow.follower.frames]
                        shown[name].append((follow.shown_frame, follow.shown_time, held,
                                            palettes.matrices.copy()))
                time.sleep(DT / 2)
        finally:
            for engine, _, client in nodes.values():
                engine.close()
                client.close()
        assert procs.wait(server, 30) == 0, procs.log(server)
    drawn = np.load(tmp_path / "server_palettes.npz")
    by_frame = {int(f): i for i, f in enumerate(drawn["frames"])}
    times, matrices = drawn["times"], drawn["matrices"]
    # what the codec's steps allow: a step of translation, and two units (1/32767) of
    # quaternion, about 2/32767 rad, over the model's 1.5 units of reach
    quantum = POSITION_STEP + 2.0 / ROTATION_SCALE * 1.5

    # the wall shows exact server frames: the same skeleton to the codec's steps
    frames = {frame: m for frame, _, _, m in shown["wall"]}
    assert len(frames) > 60, f"the wall showed {len(frames)} distinct frames"
    for frame, m in frames.items():
        server_m = matrices[by_frame[frame]]
        assert np.abs(m - server_m).max() < quantum, frame
    first = min(frames)
    assert first > 40, "the wall joined after a second: it starts mid-walk"
    worst = max(np.linalg.norm(_skinned(m) - _skinned(matrices[by_frame[f]]), axis=1).max()
                for f, m in list(frames.items())[::15])
    assert worst < quantum, worst

    # the node on its own clock shows a time between two frames it holds: each joint
    # where interpolating those frames' joints puts it (translations linearly, rotations
    # by slerp), to the codec's steps
    checked = 0
    for _, t, held, m in shown["eye"]:
        held_times = times[[by_frame[f] for f in held]]
        after = int(np.searchsorted(held_times, t - 1e-9))
        if after == 0 or after >= len(held):
            continue
        ta, tb = held_times[after - 1], held_times[after]
        (a, _), (b, _) = (palette_poses(matrices[by_frame[held[i]]]) for i in (after - 1,
                                                                               after))
        alpha = (t - ta) / (tb - ta)
        between = np.column_stack([a[:, :3] + alpha * (b[:, :3] - a[:, :3]),
                                   slerp(a[:, 3:], b[:, 3:], alpha)])
        assert np.abs(m - palette_matrices(between)).max() < quantum, t
        checked += 1
    assert checked > 60

    # the script's calls showed: the run blend (a shorter stride) and the wave (arms up)
    # changed the skeleton the nodes drew, as they changed the server's
    cue = stats(tmp_path / "server.json")["measures"]["cue"]
    wave = [m for frame, m in frames.items() if cue + 1.6 < times[by_frame[frame]] < cue + 2.4]
    walk = [m for frame, m in frames.items() if times[by_frame[frame]] < cue + 0.45]
    assert wave and walk, (cue, min(times[by_frame[f]] for f in frames))
    def reach(m: np.ndarray) -> float:  # the highest vertex (the model's up is +Y)
        return float(_skinned(m)[:, 1].max())

    assert max(map(reach, wave)) > max(map(reach, walk)) + 0.1


def test_bone_ids_sort_after_every_body() -> None:
    from services.net.bones import BONE_FLAG, MAX_AVATAR_NET, bone_ids

    ids = bone_ids(np.array([1, MAX_AVATAR_NET - 1]), np.array([3, 1024]))
    assert ids.min() >= BONE_FLAG and (np.diff(ids.astype(np.int64)) > 0).all()
