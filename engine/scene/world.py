"""The ``World`` block, declared on the block registry: the dynamics settings, the step and
the scene's clock, a scene's one setting (built from its defaults where a file writes
none). Each bounded setting is checked against its one range, :data:`WORLD_RANGES` beside
:class:`WorldSettings`; the step against :data:`STEP_RANGE`."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import engine.scene.random_state as random_state
from components.blocks import BlockDeclaration, BuildContext, Key, declare
from engine.physics.backend import (
    MAX_EXTENT,
    WORLD_EXTENT,
    WORLD_RANGES,
    BackendName,
    WorldSettings,
)
from engine.physics.sleep import SLEEP_ANGULAR, SLEEP_LINEAR, SLEEP_TIME
from engine.realtime import STEP_RANGE, STEP_WARNING, TIME_STEP

#: The solver settings' defaults, defined once (WorldSettings).
_WORLD = WorldSettings()
#: The World block's bounded keys and the WorldSettings field each sets.
_BOUNDED = {"ERP": "erp", "CFM": "cfm", "Iterations": "iterations",
            "MaxContacts": "max_contacts", "WarmStart": "warm_start",
            "ContactSoftness": "contact_softness", "ExactRows": "exact_rows",
            "SleepTime": "sleep_time", "SleepLinear": "sleep_linear",
            "SleepAngular": "sleep_angular"}


def build_world(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """The scene's world settings, step, backend and clock (a saved state's too)."""
    _check_step(float(v["TimeStep"]), ctx)
    ctx.settle("world", WorldSettings(
        gravity=tuple(map(float, v["Gravity"])), auto_sleep=bool(v["AutoSleep"]),
        material_pairs=ctx.scene("material_pairs"), solver_seed=v["SolverSeed"],
        extent=_extent(v, ctx), **_bounded(v, ctx)))
    ctx.settle("time_step", float(v["TimeStep"]))
    ctx.settle("backend", v["Dynamics"])
    ctx.settle("time", float(v["Time"]))
    if v["RandomState"] is not None:
        try:
            ctx.settle("random_state", random_state.parse(str(v["RandomState"])))
        except ValueError as exc:
            ctx.error("RandomState", str(exc))
    return []


def _extent(v: Mapping[str, Any], ctx: BuildContext) -> float:
    """The world's Extent (m), checked; the default where it is refused."""
    extent = v["Extent"]
    if not (0 < extent <= MAX_EXTENT):
        ctx.error("Extent", f"Extent must be a positive number of metres up to "
                  f"{MAX_EXTENT:g}, got {extent:g}")
        return WORLD_EXTENT
    return float(extent)


def _bounded(v: Mapping[str, Any], ctx: BuildContext) -> dict[str, Any]:
    """The bounded settings, each within its one range (:data:`WORLD_RANGES`); a refused
    one told at its key and left at its default."""
    checked: dict[str, Any] = {}
    for key, name in _BOUNDED.items():
        value, allowed = v[key], WORLD_RANGES[name]
        if name == "sleep_angular":  # the file's is in deg/s
            value = math.radians(value)
        if value not in allowed:
            shown = math.degrees(value) if name == "sleep_angular" else value
            ctx.error(key, f"{key} must be {allowed.text()}, got {shown:g}")
            value = getattr(_WORLD, name)
        checked[name] = type(getattr(_WORLD, name))(value)
    return checked


def _check_step(step: float, ctx: BuildContext) -> None:
    """TimeStep within :data:`STEP_RANGE` (an error), up to :data:`STEP_WARNING` (else a
    warning: the step is suspicious)."""
    low, high = STEP_RANGE
    if not (low < step <= high):
        ctx.error("TimeStep", f"TimeStep must be more than {low:g} s and at most {high:g} s, "
                  f"got {step:g}")
    elif step > STEP_WARNING:
        ctx.problem("TimeStep", f"TimeStep {step:g} s is long: contacts and joints lose "
                    f"accuracy past {STEP_WARNING:g} s ({TIME_STEP:g} is the default)",
                    warning=True)


WORLD_BLOCK = declare(BlockDeclaration(
    "World", inside=("Scene",), build=build_world, entity=False, first=True, setting=True,
    named=False,
    doc="dynamics settings", keys=(
        Key("Gravity", "vec3", _WORLD.gravity, "m/s^2"),
        Key("TimeStep", "float", TIME_STEP, "s, fixed dynamics step (more than 0, at most 1; "
            "past 0.05 contacts and joints lose accuracy)"),
        Key("Extent", "float", WORLD_EXTENT, "m: bodies stay within this distance of the "
            "origin on every axis; positions beyond it are refused, and a body that leaves "
            "it is stopped (up to 1e12)"),
        Key("Dynamics", "enum", "ode", "dynamics backend: ode (3D) or pymunk (2D, X-Z plane)",
            allowed=tuple(BackendName)),
        Key("Iterations", "int", _WORLD.iterations,
            "solver iterations per step (ODE QuickStep, pymunk): more converge stacks and "
            "long chains further, at a cost that grows with them"),
        Key("WarmStart", "float", _WORLD.warm_start,
            "share of a resting body's weight carried from step to step (0 to 0.99; 0: "
            "off): stacks stand still with few iterations (ODE; see docs/PHYSICS.md)"),
        Key("ContactSoftness", "float", _WORLD.contact_softness,
            "contacts' give, as a share of their own stiffness: the same for every mass and "
            "step; a bouncing contact is always rigid (ODE; a material's Softness "
            "overrides)"),
        Key("ExactRows", "int", _WORLD.exact_rows,
            "islands held by joints alone with up to this many constraint rows are solved "
            "exactly (ODE dWorldStep): accurate pendulums and mechanisms, at a cost that "
            "grows with the cube of the rows; 0: all by the iterative solver"),
        Key("ERP", "float", _WORLD.erp, "error reduction per step"),
        Key("CFM", "float", _WORLD.cfm, "constraint force mixing"),
        Key("MaxContacts", "int", _WORLD.max_contacts, "per pair of geometries"),
        Key("AutoSleep", "bool", 1, "bodies that rest fall asleep (stop being simulated) "
            "until something wakes them; see engine.physics.sleep"),
        Key("SleepTime", "float", SLEEP_TIME, "s a body must stay quiet (slow and not "
            "accelerated) before it and what it touches fall asleep"),
        Key("SleepLinear", "float", SLEEP_LINEAR, "m/s: slow means a smoothed speed under "
            "this; it is steady when its velocity stays within a tenth of it"),
        Key("SleepAngular", "float", round(math.degrees(SLEEP_ANGULAR), 12), "deg/s: the "
            "same for spin"),
        Key("Time", "float", 0.0, "s, simulated time this state was saved at", example="2.0"),
        Key("SolverSeed", "int", None, "the solver's random state when this state was saved",
            example="2767133776"),
        Key("RandomState", "string", None, "the scene's random generator (randInterval and "
            "randNormal in text scripts spawn) when this state was saved"),
    )))
