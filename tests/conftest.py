"""Shared fixtures: engines on every dynamics backend that is built here."""

from __future__ import annotations

import importlib
import importlib.util
import os

import pytest
from hypothesis import settings

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
# Every engine in the tests checks that systems touch only what they declare.
os.environ.setdefault("COLOSSEUM_DEBUG", "1")

# CI replays the same examples every run (no wall-clock deadlines on a shared machine);
# a developer's run explores new ones.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")


#: Tests that keep wall-clock time or measure it: real processes and sockets on deadlines
#: (serve/join, devices on real transports, OpenXR, sound), timed costs and ratios, a step
#: timed against a thread; a folder, a file or one test (its node id). ``tools/dev test``
#: runs them alone, after the rest has run on every core (pytest-xdist), so a busy
#: neighbour cannot make them miss their deadlines.
SERIAL = ("tests/net/", "tests/input/", "tests/xr/", "tests/audio/",
          "tests/core/test_actuation.py", "tests/core/test_readme_flows.py",
          "tests/experiments/test_experiment_lsl.py", "tests/experiments/test_run.py",
          "tests/render/test_anomaly_switching.py", "tests/scripting/test_scripting_sandbox.py",
          "tests/scripting/test_churn.py::test_a_spawn_and_a_delete_cost_the_same",
          "tests/physics/test_ode_physics.py::test_gil_is_released_while_stepping",
          "tests/core/test_threaded.py::test_no_torn_snapshot_over_thousands_of_frames",
          "tests/stroke/test_sweep.py::test_the_crumbs_fall_asleep_and_then_cost")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark the tests of :data:`SERIAL` ``serial``."""
    for item in items:
        if item.nodeid.startswith(SERIAL):
            item.add_marker(pytest.mark.serial)


def available_backends() -> list[str]:
    names = ["ballistic", "pymunk"]
    if importlib.util.find_spec("engine.physics.ode3d") is not None:
        try:
            importlib.import_module("engine.physics.ode3d")
            names.append("ode")
        except ImportError:
            pass
    return names


@pytest.fixture(params=available_backends())
def backend_name(request: pytest.FixtureRequest) -> str:
    return request.param


#: A fuzz run in the suite that has not done its inputs by then has hung.
SAFETY_SECONDS = 300.0


@pytest.fixture
def fuzz_briefly(capsys: pytest.CaptureFixture[str]):
    """Run one target of tools/fuzz.py for ``inputs`` inputs from seed 0 and check it: no
    failure, every input run, and inputs that worked beside inputs told as messages (both
    paths exercised). A count, not a time, so a loaded machine runs the same inputs; the
    time it took is printed (it depends on the machine)."""
    from tools.fuzz_core import Result, Target, run

    def fuzz(target: Target, inputs: int) -> Result:
        result = run([target], SAFETY_SECONDS, seed=0, max_inputs=inputs)
        kind = result.kinds[target.name]
        with capsys.disabled():
            print(f"\nfuzz {target.name}: {kind.inputs} inputs in {result.seconds:.1f} s "
                  f"({dict(kind.outcomes)}), slowest {kind.slowest_s:.2f} s")
        assert result.failure is None, f"{result.failure}\nreproducer: {result.reproducer}"
        assert kind.inputs == inputs, f"only {kind.inputs} of {inputs} in {SAFETY_SECONDS} s"
        assert len(kind.outcomes) >= 2
        return result

    return fuzz


@pytest.fixture(autouse=True)
def exports_are_valid_gltf(request: pytest.FixtureRequest):
    """Every file ``colosseum export`` writes in a test is checked against the
    KHR_physics_rigid_bodies and KHR_implicit_shapes JSON schemas of ../shared (when they
    are there): a test whose export does not validate fails (issue 31)."""
    from services import export as export_module

    written: list = []
    original = export_module.GltfWriter.write

    def write(self, path):  # type: ignore[no-untyped-def]
        out = original(self, path)
        if self.doc["asset"].get("generator") == "colosseum export":
            written.append(out)
        return out

    export_module.GltfWriter.write = write  # type: ignore[method-assign]
    try:
        yield
    finally:
        export_module.GltfWriter.write = original  # type: ignore[method-assign]
    from tests.interchange import gltf_schema

    if written and gltf_schema.available():
        bad = {str(p): gltf_schema.problems(p) for p in written if p.exists()}
        bad = {p: found for p, found in bad.items() if found}
        assert not bad, f"exports that do not validate: {bad}"
