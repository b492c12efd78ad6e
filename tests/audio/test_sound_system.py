"""The sound plugin inside a running Engine: sources on bodies, listener on the camera,
contact sounds from real physics contacts, statistics, bad files."""

from __future__ import annotations

import logging
import math
import subprocess
import sys
from pathlib import Path

import pytest
from sound_helpers import active, read, rms, tone

from components import Camera, MaterialProps, Physical, Script, Shape, Sound, Transform
from engine import Engine, EngineConfig
from engine.physics import BackendUnavailable, create_backend
from engine.physics.backend import WorldSettings
from services.audio import SoundManager
from systems import create_engine
from systems.dynamics import DynamicsSystem
from systems.sound import SoundPlugin, SoundSystem

REPO = Path(__file__).resolve().parents[2]


def _engine(sound: str, backend: str = "ballistic", fast: bool = True,
            gravity: tuple[float, float, float] = (0.0, 0.0, 0.0),
            content: Path | None = None) -> Engine:
    cfg = EngineConfig(backend=backend, fast=fast, sound=sound, content_dir=content, dt=1 / 60,
                       world=WorldSettings(gravity=gravity, auto_sleep=False))
    engine = create_engine(cfg)
    engine.add_plugin(SoundPlugin())
    return engine


def test_sound_on_a_moving_body_pans_as_it_passes_the_camera(tmp_path: Path) -> None:
    """End to end: a hum on a body flying past a camera, recorded in real time."""
    hum = tone(tmp_path / "hum.wav", 300.0, 0.5)
    out = tmp_path / "out.wav"
    seconds, speed = 0.6, 12.0
    with _engine(f"wave:{out}", fast=False) as engine:
        engine.spawn(Transform(position=(0.0, -1.0, 0.0)), Camera())  # looks along +Y
        engine.spawn(Transform(position=(-speed * seconds / 2, 1.0, 0.0),
                               linear_velocity=(speed, 0.0, 0.0)),
                     Physical(gravity=False), Sound(file=str(hum), loop=True, auto_play=True))
        engine.run(seconds=seconds)
        assert engine.resource(SoundManager).stats()["active"] == 1
    data = active(read(out))
    n = len(data)
    first, last = data[: n // 4], data[-n // 4:]
    assert rms(first[:, 0]) > 3 * rms(first[:, 1])
    assert rms(last[:, 1]) > 3 * rms(last[:, 0])


def test_listener_follows_the_camera_pose(tmp_path: Path) -> None:
    """A camera far from the origin, turned to face -Y: a source at its +X world side is
    on its left."""
    beep = tone(tmp_path / "beep.wav", 500.0, 0.3)
    out = tmp_path / "out.wav"
    turn = (math.cos(math.pi / 2), 0.0, 0.0, math.sin(math.pi / 2))  # 180° about Z
    with _engine(f"wave:{out}", fast=False) as engine:
        engine.spawn(Transform(position=(20.0, 5.0, 1.0), orientation=turn), Camera())
        engine.spawn(Transform(position=(22.0, 5.0, 1.0)),
                     Sound(file=str(beep), auto_play=True))
        engine.run(seconds=0.4)
    data = active(read(out))
    assert rms(data[:, 0]) > 0.05 and rms(data[:, 1]) < 0.01 * rms(data[:, 0])


def test_files_are_found_in_the_content_folder_and_stats_are_reported(tmp_path: Path) -> None:
    (tmp_path / "sounds").mkdir()
    tone(tmp_path / "sounds" / "hum.wav", seconds=0.2)
    with _engine("null", content=tmp_path) as engine:
        engine.spawn(Transform(), Sound(file="hum.wav", loop=True, auto_play=True))
        engine.spawn(Sound(file="sounds/hum.wav", auto_play=True))  # at the listener
        engine.run(frames=3)
        stats = engine.stat_sources["sound"]()
    assert stats["backend"] == "null" and stats["played"] == 2 and stats["failed"] == 0
    assert {"queued", "dropped", "stolen", "contact_sounds"} <= set(stats)


def test_script_controls_and_removal_stop_the_sound(tmp_path: Path) -> None:
    hum = tone(tmp_path / "hum.wav", seconds=0.2)
    with _engine("null") as engine:
        entity = engine.spawn(Transform(), Sound(file=str(hum), loop=True))
        engine.run(frames=2)
        sounds = engine.resource(SoundSystem)
        manager = engine.resource(SoundManager)
        assert manager.stats()["active"] == 0  # no auto_play
        voice = sounds.play(engine, entity)
        assert voice is not None and voice.state == "playing"
        sounds.set_gain(entity, 0.25)
        assert voice.gain == 0.25
        engine.despawn(entity)
        engine.run(frames=2)
        assert voice.state == "stopped" and manager.stats()["active"] == 0


def test_a_missing_sound_file_keeps_the_simulation_running(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    with _engine("null", content=tmp_path) as engine, \
            caplog.at_level(logging.ERROR, "colosseum.audio"):
        body = engine.spawn(Transform(linear_velocity=(1.0, 0.0, 0.0)), Physical(gravity=False),
                            Sound(file="moo.wav", auto_play=True))
        engine.run(frames=30)
        assert engine.world.component_for_entity(body, Transform).position[0] > 0.4
    assert [r.getMessage() for r in caplog.records] == [
        f"error: cannot load sound \"moo.wav\" ({tmp_path / 'moo.wav'}): file not found "
        f"(the sound stays silent)"]


def _stack_scene(engine: Engine, knock: Path, drop_height: float | None) -> list[int]:
    """A ground, five boxes resting on it, and maybe a box falling beside them."""
    material = MaterialProps(name="wood", contact_sound=str(knock))
    box = [Shape("box", (0.5, 0.5, 0.5))]
    engine.spawn(Transform(position=(0.0, 0.0, -0.5)),
                 Physical(kind="static", shapes=[Shape("box", (20.0, 2.0, 1.0))]))
    ids = [engine.spawn(Transform(position=(0.0, 0.0, 0.25 + 0.5 * i)),
                        Physical(mass=2.0, shapes=box, material=material)) for i in range(5)]
    if drop_height is not None:
        ids.append(engine.spawn(Transform(position=(3.0, 0.0, drop_height)),
                                Physical(mass=1.0, shapes=box, material=material)))
    return ids


@pytest.mark.parametrize("physics", ["pymunk", "ode"])
def test_resting_stack_is_silent_and_a_falling_box_is_heard(tmp_path: Path,
                                                            physics: str) -> None:
    """Real contacts: the stack never sounds; the box dropped beside it does, about once."""
    try:
        create_backend(physics).close()
    except (BackendUnavailable, ImportError) as exc:
        pytest.skip(f"{physics} not built here: {exc}")
    knock = tone(tmp_path / "knock.wav", 900.0, 0.1)
    with _engine("null", backend=physics, gravity=(0.0, 0.0, -9.81)) as engine:
        _stack_scene(engine, knock, drop_height=None)
        engine.run(seconds=2.0)
        sounds = engine.resource(SoundSystem)
        assert engine.resource(DynamicsSystem).contacts_total >= 5 * 120  # touching all along
        assert sounds.contact_sounds == 0
    with _engine("null", backend=physics, gravity=(0.0, 0.0, -9.81)) as engine:
        ids = _stack_scene(engine, knock, drop_height=1.5)
        engine.run(seconds=2.0)
        sounds = engine.resource(SoundSystem)
        assert 1 <= sounds.contact_sounds <= 3  # the landing (and maybe a small bounce)
        stats = sounds.stats()
        assert stats["played"] + stats["dropped"] == stats["contact_sounds"]
        assert engine.world.component_for_entity(ids[-1], Transform).position[2] < 0.3


def test_without_a_device_openal_falls_back_to_null_with_one_warning() -> None:
    """In a fresh process whose OpenAL Soft has no usable driver; that process can no
    longer record (OpenAL Soft read its configuration) and says so."""
    code = ("import logging; logging.basicConfig(level=logging.WARNING);"
            "from services.audio import create_audio_backend as c, AudioDeviceError;"
            "print('backends', c('openal').name, c('openal').name)\n"
            "try: c('wave:/tmp/never.wav', fallback=False)\n"
            "except AudioDeviceError as e: print(e)")
    env = {"ALSOFT_DRIVERS": "no-such-driver", "PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=60, cwd=REPO)
    assert "backends null null" in done.stdout, done.stderr
    warnings = [line for line in done.stderr.splitlines() if "sound disabled" in line]
    assert len(warnings) == 1, done.stderr
    assert "openal: no audio device" in warnings[0]
    assert "reads its configuration only once; record in a fresh process" in done.stdout


def test_unknown_backend_name_is_an_error() -> None:
    from services.audio import create_audio_backend

    with pytest.raises(ValueError, match="unknown sound backend 'speakers'"):
        create_audio_backend("speakers")


def test_set_gain_from_lua_turns_a_loop_down(tmp_path: Path) -> None:
    hum = tone(tmp_path / "hum.wav", 400.0, 0.25)
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "vol.lua").write_text(
        "function onUpdate(dt) if time() > 0.3 then self:setGain(0.25) end end\n")
    out = tmp_path / "out.wav"
    with _engine(f"wave:{out}", fast=False, content=tmp_path) as engine:
        engine.spawn(Camera(), Transform(position=(0.0, -1.0, 0.0)))
        engine.spawn(Transform(), Sound(file=str(hum), loop=True, auto_play=True),
                     Script(file="scripts/vol.lua"))
        engine.run(seconds=0.7)
    data = active(read(out)).mean(axis=1)
    n = len(data)
    loud, quiet = rms(data[n // 10: 4 * n // 10]), rms(data[6 * n // 10: 9 * n // 10])
    assert quiet == pytest.approx(0.25 * loud, rel=0.15)
