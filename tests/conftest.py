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
