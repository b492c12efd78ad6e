"""Issue 22's goals at default settings, on both backends: the reference cases of
``colosseum bench accuracy`` (app/bench/accuracy.py: each case's scene and the theory
it is held to are there, worked out from physics) within their goals at the default
step; and what the solver settings are for: restitution that does not depend on the
step or the mass, stacks that stand at a coarse step, settings checked where written.

(No pendulum sleeping mid-swing at any step and a crate asleep within a second:
test_sleep.py.)
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from app.bench import accuracy as bench
from engine.physics.backend import WorldSettings
from engine.scene import check

BACKENDS = ("ode", "pymunk")
CASES = {c.name: c for c in bench.cases()}


def _within_goal(case: bench.Case, backend: str, dt: float = bench.DEFAULT_STEP) -> float:
    error = case.error_of(case.ours(backend, dt).value)
    assert abs(error) <= case.goal, (case.name, backend, dt, error)
    return error


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", [n for n in CASES if "pendulum" in n])
def test_pendulum_period_within_half_a_percent_at_100_hz(backend: str, name: str) -> None:
    """Hinge and ball pendulums at 2°, 5° and 30° against the elliptic-integral period."""
    _within_goal(CASES[name], backend)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("dt", [0.01, 0.001])
def test_first_rebound_within_two_percent_of_e_squared(backend: str, dt: float) -> None:
    """Bounce 0.8 from drops that meet the floor at every phase of a step (a 100 Hz
    step's fall is 4.4 cm at impact speed): the apex is e²·h within 2 % each time."""
    e = bench.BOUNCE_GOAL
    for drop in np.linspace(1.0, 1.05, 6 if dt == 0.01 else 2):
        apex = bench._bounce_ours(e, float(drop))(backend, dt).value
        assert abs(apex / (e * e) - 1) <= 0.02, (drop, apex)


@pytest.mark.parametrize("backend", BACKENDS)
def test_friction_slide_stops_within_one_percent_of_v2_over_2_mu_g(backend: str) -> None:
    _within_goal(CASES["friction slide"], backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_ten_crate_stack_drifts_at_most_10_mm_in_20_s(backend: str) -> None:
    _within_goal(CASES["10-crate stack drift"], backend)


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_stack_stands_at_50_hz(backend: str) -> None:
    """Without the resting warm start both backends topple it within seconds."""
    top = CASES["10-crate stack drift"].ours(backend, 0.02)
    assert top.value < 100.0 and top.extra["sink mm"] < 50.0  # mm: still a stack


@pytest.mark.parametrize("dt", [0.01, 0.001])
def test_restitution_does_not_depend_on_the_step_or_the_mass(dt: float) -> None:
    """ODE: a bouncing contact is rigid whatever the world's softness, so a 1 kg and a
    1000 kg ball return the same e² at 100 Hz and 1 kHz (ODE's plain CFM took 4.5 % off
    at 1 kHz, more the heavier the ball)."""
    e = bench.BOUNCE_GOAL
    apexes = [bench._bounce_ours(e, mass=m)("ode", dt).value for m in (1.0, 1000.0)]
    assert apexes[0] == pytest.approx(apexes[1], rel=1e-3)
    assert apexes[0] == pytest.approx(e * e, rel=0.02)


def test_joint_islands_are_solved_exactly_and_contact_islands_iteratively() -> None:
    """A 30° pendulum's period at 100 Hz: with its island solved exactly (the default)
    within 0.05 % of theory; forced to QuickStep's 20 iterations (ExactRows 0), over 1 %
    slow, as measured before the exact islands."""
    case = CASES["ball pendulum 30°"]
    exact = case.error_of(case.ours("ode", 0.01).value)
    original = bench.world

    def iterative(name: str, **settings: object):  # type: ignore[no-untyped-def]
        return original(name, exact_rows=0, **settings)

    bench.world = iterative
    try:
        quick = case.error_of(case.ours("ode", 0.01).value)
    finally:
        bench.world = original
    assert abs(exact) < 0.05 < 1.0 < quick


def test_both_backends_take_the_resting_rules_from_one_header() -> None:
    """The resting warm start is written once (engine/physics/policy.h): the ODE step and
    pymunk's compiled pass both include it, and neither defines a rule's constant of its
    own."""
    physics = Path(__file__).parents[2] / "engine/physics"
    policy = (physics / "policy.h").read_text()
    names = ("REST_SLIP", "REST_SUPPORT", "REST_GRIP", "REST_SLIDING", "REST_SMOOTHING")
    for name in names:
        assert len(re.findall(rf"#define {name} ", policy)) == 1, name
    stepper = (physics / "ode3d/stepper.h").read_text()
    rows = (physics / "pymunk2d/_rows.pyx").read_text()
    assert '#include "../policy.h"' in stepper and "rp_stand(" in stepper
    assert 'cdef extern from "policy.h"' in rows and "rp_stand(" in rows
    for text in (stepper, rows, (physics / "pymunk2d/resting.py").read_text()):
        for name in names:
            assert not re.search(rf"(#define {name}\b|^{name} = )", text, re.M), name


def test_solver_settings_are_checked_where_they_are_written(tmp_path: Path) -> None:
    def errors(text: str) -> list[tuple[int, int, str]]:
        path = tmp_path / "main.scene"
        path.write_text(text)
        return [(d.line, d.col, d.message) for d in check(path) if d.is_error]

    assert errors("World {\n  WarmStart 1.5 }\n") == [
        (2, 13, "WarmStart must be from 0 to 0.99, got 1.5")]
    assert errors("World {\n  ContactSoftness -1 }\n") == [
        (2, 19, "ContactSoftness must be at least 0, got -1")]
    assert errors("World {\n  ExactRows -2 }\n") == [
        (2, 13, "ExactRows must be at least 0, got -2")]
    assert errors("World {\n  ERP 1.5 CFM -1 }\n") == [
        (2, 7, "ERP must be from 0 to 1, got 1.5"), (2, 15, "CFM must be at least 0, got -1")]
    assert errors("World { WarmStart 0 ContactSoftness 0 ExactRows 0 }\n") == []
    defaults = WorldSettings()
    assert 0 < defaults.warm_start < 1 and defaults.exact_rows > 0
    assert math.isfinite(defaults.contact_softness)


def test_the_bench_reports_each_case_beside_mujoco_or_the_goal() -> None:
    """``colosseum bench accuracy``'s rows and figures, for one case (quick: two steps)."""
    from app.bench import FIGURES

    rows = bench.run_bench(quick=True, only="friction slide")
    assert [(r["dt"], r["backend"]) for r in rows] == [
        (dt, b) for dt in (0.02, bench.DEFAULT_STEP) for b in BACKENDS]
    theory = CASES["friction slide"].theory
    for r in rows:
        assert r["error"] == pytest.approx(100 * (r["measured"] / theory - 1))
    (ode, pymunk) = FIGURES["accuracy"](rows)
    assert ode.ours == abs(rows[2]["error"]) and pymunk.ours == abs(rows[3]["error"])
    if bench.mujoco_version() is None:
        assert ode.reference == CASES["friction slide"].goal
    else:
        assert ode.reference == abs(rows[2]["mujoco error"])
