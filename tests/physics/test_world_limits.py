"""The world's limits at run time: a body leaving the world (falling forever, thrown by a
velocity) is stopped at its last pose inside and disabled with one message naming it,
on both backends; ODE's own assertions, when something slips past the checks, stop the
physics with a message instead of aborting the process."""

from __future__ import annotations

import logging
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from components import Name, Physical, Shape, Transform
from engine.app import Engine, EngineConfig
from engine.physics import create_backend
from engine.physics.backend import WorldSettings
from systems import RegistryPlugin, load_plugin

REPO = Path(__file__).resolve().parents[2]
G = 9.81


def _engine(backend: str, mode: str, extent: float) -> Engine:
    config = EngineConfig(backend=backend, mode=mode, fast=True, dt=0.01,
                          world=WorldSettings(extent=extent))
    return Engine(config, plugins=[RegistryPlugin(), load_plugin("physics")])


@pytest.mark.parametrize("mode", ["serial", "threaded"])
@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_body_falling_forever_is_stopped_at_the_edge_with_one_message(
        backend: str, mode: str, caplog: pytest.LogCaptureFixture) -> None:
    extent = 20.0
    caplog.set_level(logging.INFO)
    with _engine(backend, mode, extent) as engine:
        faller = engine.spawn(Name("faller"), Transform((0.0, 0.0, 0.0)),
                              Physical(shapes=[Shape("sphere", (0.5,))]))
        engine.run(seconds=3.0)  # it passes z = -20 after 2.02 s of free fall
        t = engine.world.component_for_entity(faller, Transform)
        z, vz = float(t.position[2]), float(t.linear_velocity[2])
    told = [r.getMessage() for r in caplog.records if "left the world" in r.getMessage()]
    assert len(told) == 1, told  # stopped and disabled: it does not leave again
    assert "'faller'" in told[0] and "±20 m" in told[0]
    # at its last pose inside: the last step before the edge, at rest
    steps_inside = int(np.floor(np.sqrt(2 * extent / (G * 0.01 ** 2))))
    assert -extent <= z < -extent + G * 0.01 * 0.01 * steps_inside * 2
    assert vz == 0.0


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_body_thrown_out_stops_and_its_neighbour_goes_on(backend: str) -> None:
    with _engine(backend, "serial", 1000.0) as engine:
        thrown = engine.spawn(Name("thrown"), Transform((900.0, 0.0, 0.0), linear_velocity=(
            50_000.0, 0.0, 0.0)), Physical(shapes=[Shape("sphere", (0.5,))], gravity=False))
        other = engine.spawn(Name("other"), Transform((0.0, 0.0, 0.0),
                                                      linear_velocity=(1.0, 0.0, 0.0)),
                             Physical(shapes=[Shape("sphere", (0.5,))], gravity=False))
        engine.run(frames=10)
        x = float(engine.world.component_for_entity(thrown, Transform).position[0])
        moved = float(engine.world.component_for_entity(other, Transform).position[0])
    assert x == pytest.approx(900.0)  # out in its first step: back where it was inside
    assert moved == pytest.approx(10 * 0.01 * 1.0)  # the neighbour, untouched


def test_an_ode_internal_error_stops_physics_instead_of_the_process(tmp_path: Path) -> None:
    """Past every check (the raw binding called directly): a body 1e30 m away makes ODE
    fail an assertion inside the step, which would abort() the process. The guard turns
    it into an exception; the driver stops the physics with one message, and the run,
    scripts and a saved state go on."""
    program = textwrap.dedent("""
        import logging, numpy as np
        from components import Name, Physical, Transform
        from engine.app import Engine, EngineConfig
        from engine.physics.ode3d import _ode
        from systems import RegistryPlugin, load_plugin
        logging.basicConfig(level=logging.INFO)
        engine = Engine(EngineConfig(backend="ode", fast=True, dt=0.01),
                        plugins=[RegistryPlugin(), load_plugin("physics")])
        box = engine.spawn(Name("box"), Transform((0.0, 0.0, 5.0)), Physical())
        engine.run(frames=5)
        world, z = engine.physics.backend._world, np.zeros(3)
        _ode.create_body(world, 999, _ode.BODY_DYNAMIC, np.array([1e30, 0, 0.0]),
                         np.array([1.0, 0, 0, 0]), z, z, 0.0, 0.0, True)
        _ode.add_geom(world, 999, _ode.GEOM_SPHERE, np.array([0.5]), z,
                      np.array([1.0, 0, 0, 0]), 1000.0, 0, 1, 0xFFFFFFFF)
        _ode.finish_body(world, 999, 1.0)
        engine.run(frames=20)
        print("still running at t =", round(engine.time, 2), "failed:", engine.physics.failed)
        engine.close()
        print("closed")
    """)
    result = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                            timeout=120, cwd=REPO)
    assert result.returncode == 0, result.stderr[-2000:]
    assert "still running at t = 0.25" in result.stdout and "closed" in result.stdout
    assert "failed: ODE error 1: assertion" in result.stdout
    assert result.stderr.count("physics stopped at t = 0.05 s") == 1
    assert "Traceback" not in result.stderr


def test_the_binding_refuses_what_ode_would_abort_on() -> None:
    """Same-body and zero-axis joints, a hinge2 on one body (or on a static one) and
    parallel hinge2 axes are refused at the binding's door too; a universal with parallel
    axes would fail every step after it."""
    from components import Joint

    backend = create_backend("ode")
    q = np.array([1.0, 0, 0, 0])
    backend.add_body(1, Physical(), np.zeros(3), q)
    backend.add_body(2, Physical(kind="static"), np.array([0.0, 0, -1]), q)
    backend.add_body(3, Physical(), np.array([1.0, 0, 0]), q)
    up = (0.0, 0.0, 1.0)
    for joint in (Joint(kind="hinge", body_a=1, body_b=1),
                  Joint(kind="hinge", body_a=1, axis=(0.0, 0.0, 0.0)),
                  Joint(kind="hinge2", body_a=1), Joint(kind="hinge2", body_a=1, body_b=2),
                  Joint(kind="hinge2", body_a=2, body_b=1),
                  Joint(kind="hinge2", body_a=1, body_b=3, axis=up, axis2=(0.0, 0.0, -2.0)),
                  Joint(kind="universal", body_a=1, body_b=3, axis=up, axis2=up)):
        with pytest.raises(ValueError, match="two different bodies|zero|two bodies|parallel"):
            backend.add_joint(7, joint)
    backend.step(0.01)  # and the world is still whole
    backend.close()


def test_spawned_objects_are_held_to_the_running_worlds_extent(tmp_path: Path) -> None:
    """A snippet has no World of its own: the running scene's Extent (here 1e7 m, ten
    times the default) decides what it may place."""
    from engine.scene import instantiate, load_spec
    from services.scripting.runtime import ScriptRuntime
    from systems.scripting import ScriptingPlugin

    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "s.lua").write_text(
        "ok_near = pcall(spawn, 'Object { ID \"near\" Position [5e6 0 0] }')\n"
        "ok_far, far = pcall(spawn, 'Object { ID \"far\" Position [2e7 0 0] }')\n"
        "far = tostring(far)\n")
    (tmp_path / "main.scene").write_text('World { Extent 1e7 }\nScript "scripts/s.lua"\n')
    spec = load_spec(tmp_path)
    config = EngineConfig(backend="ode", fast=True, content_dir=tmp_path, world=spec.world)
    with Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                 ScriptingPlugin()]) as engine:
        instantiate(engine, spec)
        engine.run(frames=1)
        env = engine.resource(ScriptRuntime).scripts[0].env
        assert env.ok_near is True and env.ok_far is False
        assert "x = 2e+07 is outside the world (±1e7 m" in env.far
