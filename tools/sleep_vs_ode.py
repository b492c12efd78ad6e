"""The sleep rule beside ODE's own auto-disable, on what tells them apart: slow pendulums.

Issue 13 asks physics to use ODE's auto-disable unless our rule is measured better. This
runs the pendulums of ``tests/physics/test_sleep.py`` (a 1 m hinge pendulum, a 5 cm
sphere of 1 kg, released from rest at 0.5° to 30°) for 10 s at each step from 0.0005 to
0.02 s, three ways:

* ``ODE default``: libode's auto-disable with its own defaults (10 steps under
  0.01 m/s and 0.01 rad/s, one sample), straight through libode (ctypes), ``dWorldStep``;
* ``ODE by time``: the same with the rule's limits by time (``SleepTime`` 0.5 s under
  ``SleepLinear`` 0.03 m/s and ``SleepAngular`` 2°/s on each step's velocity), the
  plain-C reference's setting in ``colosseum bench physics``;
* ``ours``: :class:`engine.physics.ode3d.OdeBackend` with ``auto_sleep`` on (the rule of
  :mod:`engine.physics.sleep`).

Each cell is when the bob was frozen (s) or ``swings``. A pendulum that stops in mid-air
at its turning point is wrong physics; a rule that freezes one at some step and not at
another makes a run depend on Δt. The crate that must fall asleep is tested for the rule
(``test_a_crate_on_the_floor_sleeps_within_a_second_of_settling``); ODE's rule, which
needs only ``SleepTime`` (or 10 steps) under its limits, puts it to sleep sooner.

Run: ``python -m tools.sleep_vs_ode``.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import math
from typing import Any

import numpy as np

from app.bench import print_table
from components import Joint, Physical, Shape
from engine.physics.sleep import SLEEP_ANGULAR, SLEEP_LINEAR, SLEEP_TIME

STEPS = (0.0005, 0.001, 0.005, 0.01, 0.02)
AMPLITUDES = (0.5, 2.0, 5.0, 30.0)  # degrees
SECONDS = 10.0
LENGTH, RADIUS, MASS = 1.0, 0.05, 1.0
PIVOT = (0.0, 0.0, 2.0)

_ode: Any = None


def _libode() -> Any:
    """libode through ctypes (double precision, as the engine's binding is built)."""
    global _ode
    if _ode is None:
        name = ctypes.util.find_library("ode")
        if name is None:
            raise SystemExit("libode not found (install libode-dev; `tools/dev setup` does)")
        lib = ctypes.CDLL(name)
        real, ptr = ctypes.c_double, ctypes.c_void_p
        for fn, args, res in (
                ("dInitODE2", [ctypes.c_uint], ctypes.c_int),
                ("dWorldCreate", [], ptr), ("dWorldDestroy", [ptr], None),
                ("dWorldSetGravity", [ptr, real, real, real], None),
                ("dWorldStep", [ptr, real], ctypes.c_int),
                ("dWorldSetAutoDisableFlag", [ptr, ctypes.c_int], None),
                ("dWorldSetAutoDisableLinearThreshold", [ptr, real], None),
                ("dWorldSetAutoDisableAngularThreshold", [ptr, real], None),
                ("dWorldSetAutoDisableSteps", [ptr, ctypes.c_int], None),
                ("dWorldSetAutoDisableTime", [ptr, real], None),
                ("dWorldSetAutoDisableAverageSamplesCount", [ptr, ctypes.c_uint], None),
                ("dBodyCreate", [ptr], ptr),
                ("dMassSetSphereTotal", [ptr, real, real], None),
                ("dBodySetMass", [ptr, ptr], None),
                ("dBodySetPosition", [ptr, real, real, real], None),
                ("dBodyIsEnabled", [ptr], ctypes.c_int),
                ("dJointCreateHinge", [ptr, ptr], ptr),
                ("dJointAttach", [ptr, ptr, ptr], None),
                ("dJointSetHingeAnchor", [ptr, real, real, real], None),
                ("dJointSetHingeAxis", [ptr, real, real, real], None)):
            f = getattr(lib, fn)
            f.argtypes, f.restype = args, res
        lib.dInitODE2(0)
        _ode = lib
    return _ode


def _bob_start(amplitude_deg: float) -> tuple[float, float, float]:
    a = math.radians(amplitude_deg)
    return (PIVOT[0] + LENGTH * math.sin(a), 0.0, PIVOT[2] - LENGTH * math.cos(a))


def frozen_by_ode(amplitude_deg: float, dt: float, by_time: bool) -> float | None:
    """When libode's auto-disable froze the bob (s), or None: it swung for SECONDS."""
    ode = _libode()
    world = ode.dWorldCreate()
    try:
        ode.dWorldSetGravity(world, 0.0, 0.0, -9.81)
        ode.dWorldSetAutoDisableFlag(world, 1)
        if by_time:
            ode.dWorldSetAutoDisableLinearThreshold(world, SLEEP_LINEAR)
            ode.dWorldSetAutoDisableAngularThreshold(world, SLEEP_ANGULAR)
            ode.dWorldSetAutoDisableSteps(world, 0)
            ode.dWorldSetAutoDisableTime(world, SLEEP_TIME)
            ode.dWorldSetAutoDisableAverageSamplesCount(world, 1)
        body = ode.dBodyCreate(world)  # takes the world's auto-disable settings
        mass = (ctypes.c_double * 32)()  # dMass: mass, c[4], I[12] (room to spare)
        ode.dMassSetSphereTotal(mass, MASS, RADIUS)
        ode.dBodySetMass(body, mass)
        ode.dBodySetPosition(body, *_bob_start(amplitude_deg))
        hinge = ode.dJointCreateHinge(world, None)
        ode.dJointAttach(hinge, body, None)
        ode.dJointSetHingeAnchor(hinge, *PIVOT)
        ode.dJointSetHingeAxis(hinge, 0.0, 1.0, 0.0)
        for i in range(round(SECONDS / dt)):
            ode.dWorldStep(world, dt)
            if not ode.dBodyIsEnabled(body):
                return (i + 1) * dt
        return None
    finally:
        ode.dWorldDestroy(world)


def frozen_by_rule(amplitude_deg: float, dt: float) -> float | None:
    """When our backend's sleep rule put the bob to sleep (s), or None."""
    from engine.physics.backend import WorldSettings
    from engine.physics.ode3d import OdeBackend

    backend = OdeBackend(WorldSettings(auto_sleep=True))
    try:
        backend.add_body(1, Physical(mass=MASS, shapes=[Shape("sphere", (RADIUS,))]),
                         np.array(_bob_start(amplitude_deg)), np.array([1.0, 0.0, 0.0, 0.0]))
        backend.add_joint(2, Joint(kind="hinge", body_a=1, anchor=PIVOT, axis=(0.0, 1.0, 0.0)))
        for i in range(round(SECONDS / dt)):
            backend.step(dt)
            if backend.is_sleeping(1):
                return (i + 1) * dt
        return None
    finally:
        backend.close()


def _cell(t: float | None) -> str:
    return "swings" if t is None else f"frozen {t:.3g} s"


def run() -> list[dict[str, Any]]:
    rows = []
    for amplitude in AMPLITUDES:
        for dt in STEPS:
            rows.append({"amplitude deg": amplitude, "dt s": dt,
                         "ODE default": _cell(frozen_by_ode(amplitude, dt, by_time=False)),
                         "ODE by time": _cell(frozen_by_ode(amplitude, dt, by_time=True)),
                         "ours": _cell(frozen_by_rule(amplitude, dt))})
    return rows


def main() -> int:
    print("1 m hinge pendulums released from rest, 10 s: frozen by the sleep rule?")
    print_table(run())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
