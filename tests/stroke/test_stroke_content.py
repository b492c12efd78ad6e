"""content/stroke: it checks clean and runs quiet, its recorded session sets the table and
scores so, its tasks end the session, the log goes where it should, anomalies switch."""

from __future__ import annotations

import json
import logging
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from chair_helpers import CONTENT
from PIL import Image

from app.cli import main
from app.scene_loading import load_content_scene
from components import Joint, Name, Physical, Transform, Wheelchair
from engine import EngineConfig, Phase, system
from engine.content import load_systems, resolve
from engine.events import CustomEvent
from engine.rotation import quat_to_matrix
from engine.scene import check
from services.input import InputHub, Key
from services.input.desktop import WindowDevice
from services.input.events import WheelCount
from systems import create_engine
from systems.hands import Hands
from systems.input import Outputs
from systems.render import RenderSystem
from systems.session import log_folder, log_name, open_log, summarize
from tools.stroke_scene import EYES

pytest.importorskip("engine.physics.ode3d")

ITEMS = ("plate", "bowl", "cup", "spoon", "cereal")


def records(folder: Path) -> list[dict]:
    logs = sorted(folder.glob("*.jsonl"))
    assert len(logs) == 1, logs
    return [json.loads(line) for line in logs[0].read_text().splitlines()]


def session_engine(folder: Path, sessions: Path, params: dict | None = None,
                   render: bool = False):
    """An engine running a content folder with its session logged into ``sessions`` (and
    drawing 160x120 frames with ``render``)."""
    scene = load_content_scene(resolve(folder), params=params)
    config = EngineConfig(content_dir=scene.content.folder, fast=True, render=render,
                          options={"sessions": sessions, "size": "160x120"})
    scene.configure(config)
    engine = create_engine(config)
    load_systems(engine, scene.content.folder)
    scene.instantiate(engine)
    return engine


def test_the_stroke_content_checks_clean():
    report = check(CONTENT)
    assert report.diagnostics == []


def test_the_generated_files_are_what_their_generators_write(tmp_path):
    """Scenes (tools/stroke_scene.py), models and sounds (tools/stroke_assets.py): a change
    to a generator is not shipped until the files are written again."""
    import tools.stroke_assets
    import tools.stroke_scene

    written = tools.stroke_scene.write(tmp_path) + tools.stroke_assets.write(tmp_path)
    assert {p.relative_to(tmp_path).parts[0] for p in written} == {
        "wheelchair.scene", "apartment.scene", "crumbs.scene", "models", "sounds"}
    shipped = {p.relative_to(CONTENT) for folder in ("models", "sounds")
               for p in (CONTENT / folder).iterdir()}
    assert shipped == {p.relative_to(tmp_path) for p in written if p.parent != tmp_path}
    for made in written:
        assert made.read_bytes() == (CONTENT / made.relative_to(tmp_path)).read_bytes(), made


def test_it_runs_headless_for_a_few_seconds_without_a_message(tmp_path, caplog, capsys):
    with caplog.at_level(logging.WARNING):
        code = main(["run", str(CONTENT), "--headless", "--fast", "--seconds", "3",
                     "--sessions", str(tmp_path)])
    assert code == 0
    assert [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING] == []
    assert "warning" not in capsys.readouterr().err.lower()
    kinds = [r["kind"] for r in records(tmp_path)]
    assert kinds[0] == "session" and kinds[-1] == "end"
    assert kinds.count("pose") == pytest.approx(30, abs=1)  # 10 Hz for 3 s


def test_the_recorded_session_sets_the_table_and_scores_so(tmp_path, capsys, caplog):
    """demo.input (tools/stroke_demo.py) drives the chair to the table and puts the five
    breakfast things in their places; `colosseum score` replays it to its end, writes the
    session log again and reads the breakfast done from it."""
    with caplog.at_level(logging.WARNING):
        code = main(["--log-level", "warning", "score", str(CONTENT / "demo.input"),
                     str(CONTENT), "--sessions", str(tmp_path), "--json"])
    assert code == 0
    assert not caplog.records, caplog.text  # a scene changed since? python -m tools.stroke_demo
    summary = json.loads(capsys.readouterr().out)
    assert summary["tasks"]["breakfast"]["done"] is not None
    assert summary["tasks"]["sweep"]["done"] is None
    assert summary["grasp"] == summary["release"] == 5
    assert summary["collision"] == 0  # through the doorway, under the table, touching none
    assert 2.4 < summary["distance"] < 3.0  # the hall to the table
    log = records(tmp_path)
    assert log[0]["replay"].endswith("demo.input")
    placed = [r["object"] for r in log if r["kind"] == "task" and r["event"] == "placed"]
    assert sorted(placed) == sorted(ITEMS)  # each once: put down, stayed put
    grasped = [r["object"] for r in log if r["kind"] == "grasp"]
    assert grasped == list(ITEMS)
    done = next(r for r in log if r["kind"] == "task" and r["event"] == "done")
    assert done["t"] == summary["tasks"]["breakfast"]["done"] > max(
        r["t"] for r in log if r["kind"] == "release")
    last = [r for r in log if r["kind"] == "pose"][-1]
    assert abs(last["x"] - 8.7) < 0.05 and abs(last["y"] - 3.62) < 0.05  # parked


def test_both_tasks_done_end_the_session_and_the_run(tmp_path):
    """The things put on their marks and most crumbs swept into the floor zone (here by
    hand, as poses): the tracker reports both tasks done, ends the session, and the run
    stops by itself."""
    with session_engine(CONTENT, tmp_path) as engine:
        ids = {n.id: e for e, n in engine.world.get_component(Name)}

        @system(Phase.SCRIPT, reads=(Name, Transform, Physical))
        def tidy(e, dt):
            if e.frame != 10:
                return
            world = e.world
            for item in ITEMS:
                mark = world.component_for_entity(ids[f"mark {item}"], Transform).position
                half = _half_height(e, ids[item])
                e.physics.set_pose(ids[item], (mark[0], mark[1], 0.75 + half + 0.001),
                                   (1.0, 0.0, 0.0, 0.0))
            zone = world.component_for_entity(ids["mark sweep"], Transform).position
            for i in range(190):
                x, y = divmod(i, 14)
                e.physics.set_pose(ids[f"crumb {i}"], (zone[0] - 0.2 + 0.03 * x,
                                                       zone[1] - 0.19 + 0.028 * y, 0.006),
                                   (1.0, 0.0, 0.0, 0.0))

        engine.add_system(tidy)
        engine.run(seconds=10.0)
        stopped_at = engine.time
    log = records(tmp_path)
    done = {r["task"] for r in log if r["kind"] == "task" and r["event"] == "done"}
    assert done == {"breakfast", "sweep"}
    assert log[-1]["kind"] == "end" and log[-1]["reason"] == "done"
    assert stopped_at < 2.0  # ended by the session, not by the 10 s limit
    swept = [r["swept"] for r in log if r["kind"] == "task" and r["task"] == "sweep"
             and r["event"] == "done"]
    assert swept and swept[0] >= 180


def test_the_session_ends_when_its_time_is_up(tmp_path):
    folder = tmp_path / "stroke"
    shutil.copytree(CONTENT, folder, ignore=shutil.ignore_patterns("demo.input"))
    tasks = folder / "scripts" / "tasks.lua"
    tasks.write_text(tasks.read_text().replace("M.TIME_LIMIT = 900", "M.TIME_LIMIT = 1"))
    with session_engine(folder, tmp_path / "logs") as engine:
        engine.run(seconds=10.0)
        stopped_at = engine.time
    end = records(tmp_path / "logs")[-1]
    assert end["kind"] == "end" and end["reason"] == "timeout"
    assert end["breakfast"] is False and end["sweep"] is False
    assert 1.0 <= stopped_at < 1.5


def test_session_logs_go_beside_the_run_never_into_the_content(tmp_path, caplog):
    here = tmp_path / "work"
    assert log_folder(None, "", CONTENT, cwd=here) == here / "sessions"
    assert log_folder(None, "logs/x", CONTENT, cwd=here) == here / "logs" / "x"
    assert log_folder(tmp_path / "mine", "logs", CONTENT, cwd=here) == tmp_path / "mine"
    for outside in (str(tmp_path / "victim"), "../victim", "logs/../../victim"):
        with caplog.at_level(logging.WARNING):  # content chooses no folder outside
            assert log_folder(None, outside, CONTENT, cwd=here) == here / "sessions"
        assert "leads out of the working directory" in caplog.text
    assert log_name("../../x/run", CONTENT) == "run" and log_name("..", None) == "session"
    assert log_name("", CONTENT) == "stroke" and log_name("day 1", CONTENT) == "day 1"
    with caplog.at_level(logging.WARNING):
        inside = log_folder(CONTENT / "sessions", "", CONTENT, cwd=here)
    assert inside == CONTENT.parent / "stroke-sessions"
    assert "never go inside the content folder" in caplog.text
    first, f1 = open_log(tmp_path / "logs", "stroke", 0.0)
    second, f2 = open_log(tmp_path / "logs", "stroke", 0.0)  # the same second: not over it
    f1.close()
    f2.close()
    assert first != second and second.name.endswith("-2.jsonl")


def test_the_log_records_grasps_collisions_modes_and_summarizes(tmp_path):
    """A chair driven into a wall is a collision (the floor it rolls on is not); a hand's
    grasp and release, a mode switch: each a record, and a marker on the outputs."""
    markers: list[str] = []
    with session_engine(CONTENT, tmp_path) as engine:
        ids = {n.id: e for e, n in engine.world.get_component(Name)}
        engine.start()
        hub = engine.resource(InputHub)
        hub.clock = lambda: engine.time
        count = [0.0]

        @system(Phase.INPUT, before=("InputSystem",))
        def backwards(e, dt):  # reverse at 0.3 m/s: into the hall's south wall
            count[0] -= 1.0 / 0.305 / (2 * np.pi) * 1024 * dt
            for wheel in ("left", "right"):
                hub.inject(WheelCount(wheel, round(count[0]) % 65536, e.time))

        @system(Phase.POST_PHYSICS, before=("OutputSystem",))
        def tap(e, dt):  # what the outputs send this frame
            markers.extend(e.resource(Outputs).markers)

        engine.add_system(backwards)
        engine.add_system(tap)
        hands = engine.resource(Hands)
        engine.run(seconds=0.5)
        hands.grasp(ids["right hand"], ids["broom"])
        hands.release(ids["right hand"])
        engine.events.emit(CustomEvent("wheelchair", {"mode": "feedback"}))
        engine.run(seconds=4.0)
    log = records(tmp_path)
    hits = [r for r in log if r["kind"] == "collision"]
    assert hits and {r["object"] for r in hits} <= {"wall 0.0", "shoe cabinet"}
    assert all(r["object"] != "floor" for r in hits)
    assert [r["object"] for r in log if r["kind"] in ("grasp", "release")] == ["broom"] * 2
    assert [r["mode"] for r in log if r["kind"] == "mode"] == ["velocity", "feedback"]
    assert any(m.startswith("collision") for m in markers)
    summary = summarize(sorted(tmp_path.glob("*.jsonl"))[0])
    assert summary["collision"] == len(hits) and summary["grasp"] == 1


def test_anomalies_switch_from_keys_lua_and_the_scene_and_are_logged(tmp_path, caplog):
    """The scene's variable starts neglect; key 3 (its Input) toggles double vision; key 0
    (scripts/anomalies.lua) switches all off. Each switch is logged with its parameters
    and who made it, and nothing is told."""
    from engine.anomalies import Anomalies

    with caplog.at_level(logging.WARNING), session_engine(
            CONTENT, tmp_path, {"neglect_on": "1"}) as engine:
        engine.run(frames=2)
        hub = engine.resource(InputHub)
        hub.inject(Key("number_3", True))
        engine.run(frames=2)
        hub.inject(Key("number_3", False))
        engine.run(frames=1)
        hub.inject(Key("number_0", True))
        engine.run(frames=3)
        anomalies = engine.resource(Anomalies)
        assert not any(state.enabled for state in anomalies.states.values())
    switched = [(r["name"], r["on"], r["source"]) for r in records(tmp_path)
                if r["kind"] == "anomaly"]
    assert switched[:2] == [("neglect", True, "scene"),
                            ("double_vision", True, "input:key:number_3")]
    assert sorted(s[:2] for s in switched[2:]) == [("double_vision", False),
                                                   ("neglect", False)]
    assert all(s[2].startswith("lua:") for s in switched[2:])
    neglect = next(r for r in records(tmp_path) if r["kind"] == "anomaly")
    assert neglect["Side"] == "left" and neglect["Depth"] == 0.9 and neglect["onset"] == 1.0
    assert not caplog.records, caplog.text


def test_the_desktop_mouse_puts_the_hand_where_the_eyes_look(tmp_path):
    """The hands are tracked relative to the chair; the desktop device's pointer reports
    them in the chair's frame too, so the mouse at the middle of the view puts the right
    hand 0.6 m in front of the eyes, wherever the chair stands."""
    with session_engine(CONTENT, tmp_path) as engine:
        ids = {n.id: e for e, n in engine.world.get_component(Name)}
        engine.run(frames=2)
        engine.resource(WindowDevice).pointer(0.5, 0.5)
        engine.run(frames=30)
        chair = engine.world.component_for_entity(ids["wheelchair"], Transform)
        hand = engine.world.component_for_entity(ids["right hand"], Transform)
        look = np.array([0.0, 1.3, 0.8]) - np.array(EYES)  # the camera's LookAt, chair frame
        local = np.array(EYES) + 0.6 * look / np.linalg.norm(look)
        expected = chair.position + quat_to_matrix(chair.orientation) @ local
        assert np.linalg.norm(hand.position - expected) < 0.02


def _half_height(engine, entity: int) -> float:
    shape = engine.world.component_for_entity(entity, Physical).shapes[0]
    return shape.size[2] / 2 if shape.kind == "box" else shape.size[1] / 2


def test_a_switched_anomaly_reaches_the_image(tmp_path):
    """Neglect of the left side on: the left half of what the eyes see goes dark."""
    shots = []
    for severity in ("0", "1"):
        with session_engine(CONTENT, tmp_path / severity, {"neglect_on": severity},
                            render=True) as engine:
            engine.run(frames=3)
            shot = engine.resource(RenderSystem).screenshot(tmp_path / f"{severity}.png")
        with Image.open(shot) as image:
            shots.append(np.asarray(image.convert("L"), float))
    plain, neglect = shots
    left, right = slice(0, 50), slice(110, 160)
    assert neglect[:, left].mean() < 0.1 * plain[:, left].mean()
    assert neglect[:, right].mean() == pytest.approx(plain[:, right].mean(), rel=0.02)


def test_a_session_recorded_with_params_replays_and_scores_with_them(tmp_path, capsys, caplog):
    """--param chair_feedback=1 --param neglect_on=1 change what the session simulates:
    the recording keeps them, `score` replays with them (feedback mode, neglect switched
    on, both in the log again), and a replay given other params is warned about."""
    recording = tmp_path / "session.input"
    flags = ["--param", "chair_feedback=1", "--param", "neglect_on=1"]
    assert main(["run", str(CONTENT), "--headless", "--fast", "--frames", "20", "--sessions",
                 str(tmp_path / "live"), "--record", str(recording), *flags]) == 0
    header = json.loads(recording.read_text().splitlines()[0])
    assert header["params"] == {"chair_feedback": "1", "neglect_on": "1"}
    assert main(["--log-level", "warning", "score", str(recording), str(CONTENT),
                 "--sessions", str(tmp_path / "scored"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["anomaly"] == 1
    for folder in ("live", "scored"):
        log = records(tmp_path / folder)
        assert [r["mode"] for r in log if r["kind"] == "mode"] == ["feedback"]
        assert [(r["name"], r["on"]) for r in log if r["kind"] == "anomaly"] == [
            ("neglect", True)]
    with caplog.at_level(logging.WARNING):
        assert main(["run", str(CONTENT), "--headless", "--fast", "--frames", "1",
                     "--sessions", str(tmp_path / "other"), "--replay", str(recording),
                     "--param", "neglect_on=0"]) == 0
    assert "was recorded with --param chair_feedback=1 --param neglect_on=1" in caplog.text


def test_a_recording_whose_header_holds_a_bad_flag_is_refused_before_the_run(tmp_path, capsys):
    recording = tmp_path / "bad.input"
    recording.write_text('{"format": "colosseum-input", "version": 1, "substeps": -2}\n')
    assert main(["run", str(CONTENT), "--headless", "--frames", "1", "--replay",
                 str(recording)]) == 2
    assert "the header's substeps -2 is not a valid --substeps" in capsys.readouterr().err


def test_cutlery_plates_and_the_broom_sound_when_they_hit_the_floor(tmp_path):
    """Dropped from half a metre onto the kitchen floor, the fork clinks, the plate knocks
    as ceramic, the broom brushes: each its material's contact sound. (A 40 g fork
    falling less than about 16 cm stays silent: the filter's threshold is an impulse,
    0.1 N·s, services.audio.contacts.)"""
    from systems.sound import SoundSystem

    with session_engine(CONTENT, tmp_path) as engine:
        ids = {n.id: e for e, n in engine.world.get_component(Name)}
        played: list[str] = []
        sound = engine.resource(SoundSystem)
        play = sound.play_contact
        sound.play_contact = lambda file, gain, position: (played.append(file),
                                                            play(file, gain, position))
        engine.run(frames=5)
        drops = {"fork": (7.4, 3.2, 0.5), "plate": (7.8, 3.2, 0.5), "broom": (7.8, 2.9, 1.2)}
        for name, position in drops.items():
            pose = engine.world.component_for_entity(ids[name], Transform)
            engine.physics.set_pose(ids[name], position, pose.orientation)
        engine.run(seconds=0.6)
    assert {"sounds/clink.wav", "sounds/ceramic.wav", "sounds/brush.wav"} <= set(played)


#: The desktop device's wheels in content/stroke (main.scene: TurnsPerSecond 0.35): the
#: rim's speed, and the yaw rate of turning in place, (v_r - v_l) / track.
DESKTOP_RATE = 0.35 * 2 * np.pi  # rad/s
DESKTOP_SPEED = DESKTOP_RATE * 0.305
DESKTOP_YAW = 2 * DESKTOP_SPEED / 0.55


def desktop(engine) -> WindowDevice:
    """The window's keys, stamped and read on the simulation's clock from the first frame
    on (a fast run is not paced: on the wall clock a released key would stop the counters
    late, and a clock switched after the devices were polled would start the counters
    from wherever the machine's clock stood)."""
    engine.start()  # the input hub and the window are made at start
    window = engine.resource(WindowDevice)
    engine.resource(InputHub).clock = window.clock = lambda: engine.time
    return window


def heading(engine, chair: int) -> tuple[float, float]:
    """The chair's yaw (rad, counter-clockwise from +Y) and speed along its heading."""
    pose = engine.world.component_for_entity(chair, Transform)
    forward = quat_to_matrix(pose.orientation)[:, 1]
    return math.atan2(-forward[0], forward[1]), float(pose.linear_velocity @ forward)


@pytest.mark.parametrize("feedback", ["0", "1"])
def test_the_desktop_w_key_drives_the_chair_in_both_modes(tmp_path, feedback):
    """W held turns both wheel counters at the desktop device's 0.35 turns/s: velocity mode
    rolls the chair at that rate times the wheel radius, and so does feedback mode, whose
    rim inertia is the rolling chair's (each key press a push of the same speed)."""
    with session_engine(CONTENT, tmp_path, {"chair_feedback": feedback}) as engine:
        ids = {n.id: e for e, n in engine.world.get_component(Name)}
        window = desktop(engine)
        engine.run(frames=2)
        window.key("w", True)
        engine.run(seconds=1.0)  # (at 0.67 m/s the feet reach the kitchen threshold at 1.1 s)
        chair = engine.world.component_for_entity(ids["wheelchair"], Transform)
        forward = quat_to_matrix(chair.orientation)[:, 1]
        speed = float(chair.linear_velocity @ forward)
    assert speed == pytest.approx(DESKTOP_SPEED, rel=0.05)


@pytest.mark.parametrize("feedback", ["0", "1"])
def test_the_desktop_s_key_backs_the_chair_in_both_modes(tmp_path, feedback):
    """S held turns both counters backwards: the chair backs straight at the rim's speed
    (0.8 s: the hall's south wall is 0.6 m behind the wheels). In velocity mode it holds
    that speed; in feedback mode the press is a push up to it, after which the chair
    coasts, slowed by its casters swinging round to trail the other way."""
    with session_engine(CONTENT, tmp_path, {"chair_feedback": feedback}) as engine:
        chair = {n.id: e for e, n in engine.world.get_component(Name)}["wheelchair"]
        window = desktop(engine)
        engine.run(frames=2)
        yaw, _ = heading(engine, chair)
        window.key("s", True)
        speeds = []
        for _ in range(16):
            engine.run(seconds=0.05)
            speeds.append(heading(engine, chair)[1])
        turned = heading(engine, chair)[0]
    backing = speeds[-1] if feedback == "0" else min(speeds)
    assert backing == pytest.approx(-DESKTOP_SPEED, rel=0.05)
    assert abs(math.degrees(turned - yaw)) < 2.0


@pytest.mark.parametrize("feedback", ["0", "1"])
@pytest.mark.parametrize(("key", "sense"), [("a", 1.0), ("d", -1.0)])
def test_the_desktop_a_and_d_keys_turn_the_chair_left_and_right(tmp_path, feedback, key,
                                                                  sense):
    """A turns the wheels against each other, left one back: the chair turns left
    (counter-clockwise seen from above, yaw growing); D turns it right. In velocity mode,
    once the casters have swivelled round (2 s), it turns in place at (v_r - v_l) / track
    of its wheels' ground speeds, within 5 % of the counters' rate (the motors, at their
    MaxTorque against the casters' scrub, keep the wheels about 5 % under it)."""
    with session_engine(CONTENT, tmp_path, {"chair_feedback": feedback}) as engine:
        ids = {n.id: e for e, n in engine.world.get_component(Name)}
        chair = ids["wheelchair"]
        window = desktop(engine)
        engine.run(frames=2)
        yaw, _ = heading(engine, chair)
        window.key(key, True)
        engine.run(seconds=0.6)
        turned = heading(engine, chair)[0] - yaw
        assert sense * math.degrees(turned) > 10.0
        if feedback == "1":  # each press a push: the turn then coasts out
            return
        engine.run(seconds=1.4)
        yaws, rolling = [], []
        for _ in range(10):
            engine.run(frames=3)
            yaws.append(heading(engine, chair)[0])
            axes = quat_to_matrix(engine.world.component_for_entity(chair, Transform)
                                  .orientation)
            hubs = [engine.world.component_for_entity(ids[w], Transform).linear_velocity
                    @ axes[:, 1] for w in ("wheel_l", "wheel_r")]
            rolling.append((hubs[1] - hubs[0]) / 0.55)
        rate = np.mean(np.diff(np.unwrap(yaws))) / (3 * engine.config.dt)
    assert rate == pytest.approx(np.mean(rolling), rel=0.02)
    assert rate == pytest.approx(sense * DESKTOP_YAW, rel=0.07)


def test_the_m_key_switches_the_chair_between_its_modes(tmp_path):
    """M switches velocity mode to feedback and back: logged each time; in feedback the
    axle motors are off, and a press of W is a push whose angular impulse, published for
    the rig, is RimInertia times the change of the wheel's rate; back in velocity the
    motors hold the wheels again and W publishes no push."""
    pushes: list[float] = []
    with session_engine(CONTENT, tmp_path) as engine:
        ids = {n.id: e for e, n in engine.world.get_component(Name)}

        @system(Phase.POST_PHYSICS, before=("OutputSystem",))
        def tap(e, dt):
            values = e.resource(Outputs).values
            pushes.append(values["wheelchair:wheelchair/left/torque"][0] * dt)

        engine.add_system(tap)
        window = desktop(engine)
        engine.run(frames=2)
        axles = [engine.world.component_for_entity(ids[a], Joint) for a in ("axle_l",
                                                                           "axle_r")]
        chair = engine.world.component_for_entity(ids["wheelchair"], Wheelchair)
        impulses = []
        for mode in ("feedback", "velocity"):
            window.key("m", True)
            engine.run(frames=2)
            window.key("m", False)
            engine.run(frames=2)
            assert chair.mode == mode
            held = [a.motor_max_force for a in axles]
            assert held == ([0.0, 0.0] if mode == "feedback" else [chair.max_torque] * 2)
            pushes.clear()
            window.key("w", True)
            engine.run(seconds=0.4)
            window.key("w", False)
            impulses.append(sum(pushes))
            engine.run(seconds=1.0)  # the release brakes it (a push back) in feedback
    assert impulses[0] == pytest.approx(chair.rim_inertia * DESKTOP_RATE, rel=0.03)
    assert impulses[1] == 0.0
    log = records(tmp_path)
    assert [r["mode"] for r in log if r["kind"] == "mode"] == ["velocity", "feedback",
                                                               "velocity"]
