"""``colosseum bench accuracy``: reference cases against theory, beside MuJoCo.

Every case is a small scene whose outcome physics predicts (an analytic result,
worked out here, never a number someone measured), run on a fresh backend at its
default settings (``WorldSettings()``, the scene format's ``World`` defaults) at
each time step of ``STEPS``, on both backends where the case lives in the X–Z
plane the 2D backend simulates. Each row is the case's error against theory
beside MuJoCo's error on the same case at the same step, where ``mujoco`` is
installed (``pip install .[anchors]``; MuJoCo at its own defaults, with only what
the case needs set: the step, masses, friction, restitution as a contact spring).

The cases:

* pendulums: a 5 cm ball on a 1 m hinge or ball joint, released from rest at 2°,
  5° and 30°; the period against 4√(I/mgL)·K(sin(θ₀/2)) (exact at any amplitude);
* a bouncing ball at several ``Bounce`` values e: the first rebound's apex
  against e²·h;
* a friction slide: a box launched at 3 m/s with μ 0.3 stops after v²/2μg;
* a rolling incline: a ball rolling without slipping down 1° and 3° slopes
  accelerates at (5/7)·g·sin θ (fitted, so the integrator's time offset does not count);
* a stack of ten 0.5 m crates standing 20 s: the top's drift (mm) from where it
  stood (theory: none), and how far it sank;
* Newton's cradle: five touching balls on 1 m hinges, e = 1, the first released
  at 20°: the last swings up to 20° (the ratio's error);
* a spinning top (3D only): a disc spinning at 100 rad/s on a ball joint, tilted
  30°, set off in steady precession, precesses at the slow root of
  I₁ cos θ Ω² − I₃ ω₃ Ω + m g l = 0;
* a motorized hinge lifting a 10 kg bar (gravity load up to 49 N·m of its
  60 N·m) turns at its 2 rad/s.

Run: ``python -m app.bench.accuracy [--quick] [--backend ode|pymunk]``, or
``colosseum bench accuracy [--json F] [--plot F]``.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import ellipk

from app.bench import print_row, print_table
from components import Joint, MaterialProps, Physical, Shape
from engine.physics import create_backend
from engine.physics.backend import DynamicsBackend, WorldSettings
from engine.rotation import quat_from_rotation_vector, quat_to_matrix

#: Time steps every case runs at (s): coarse, the default, fine.
STEPS = (0.02, 0.01, 0.001)
#: The scene format's default step (``World { TimeStep }``).
DEFAULT_STEP = 0.01
G = 9.81
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])
GROUND = 1000


# -- our side: scenes on a backend ---------------------------------------------
class Probe:
    """Reads every body's state once per call; rows looked up by key."""

    def __init__(self, backend: DynamicsBackend) -> None:
        self.backend = backend
        self.table = np.zeros((backend.body_count(), 13))
        self.row: dict[int, int] = {}

    def __call__(self) -> Probe:
        keys = self.backend.read_state_into(self.table)
        if len(self.row) != len(keys):
            self.row = {int(k): i for i, k in enumerate(keys.tolist())}
        return self

    def position(self, key: int) -> np.ndarray:
        return self.table[self.row[key], 0:3]

    def orientation(self, key: int) -> np.ndarray:
        return self.table[self.row[key], 3:7]

    def velocity(self, key: int) -> np.ndarray:
        return self.table[self.row[key], 7:10]


#: World settings every case runs with on top of the defaults, and MuJoCo's options
#: (``model.opt``) likewise: empty but while :func:`solver` holds them (bench pareto).
_SOLVER: dict[str, Any] = {}
_MJ_OPTIONS: dict[str, Any] = {}


@contextmanager
def solver(world_settings: dict[str, Any] | None = None,
           mujoco_options: dict[str, Any] | None = None) -> Iterator[None]:
    """Run the cases with these world settings (ours) and MuJoCo options instead of the
    defaults, e.g. ``solver({"iterations": 5}, {"iterations": 5})``: how accurate each
    engine is at each solver setting (``colosseum bench pareto``)."""
    _SOLVER.update(world_settings or {})
    _MJ_OPTIONS.update(mujoco_options or {})
    try:
        yield
    finally:
        _SOLVER.clear()
        _MJ_OPTIONS.clear()


@contextmanager
def world(name: str, **settings: Any) -> Iterator[DynamicsBackend]:
    """A fresh backend at the default settings (plus ``settings``), closed afterwards."""
    backend = create_backend(name)
    backend.configure(WorldSettings(**{**_SOLVER, **settings}))
    try:
        yield backend
    finally:
        backend.close()


def _material(name: str = "default", friction: float = 0.5, bounce: float = 0.0) -> MaterialProps:
    return MaterialProps(name=name, friction=friction, bounce=bounce)


def _ball(radius: float, mass: float | None = 1.0, **material: Any) -> Physical:
    return Physical(mass=mass, shapes=[Shape("sphere", (radius,))],
                    material=_material(**material))


def _add(backend: DynamicsBackend, key: int, body: Physical, position: tuple[float, ...],
         orientation: np.ndarray = IDENTITY, linear: tuple[float, ...] | None = None,
         angular: tuple[float, ...] | None = None) -> None:
    backend.add_body(key, body, np.array(position, float), np.asarray(orientation, float),
                     None if linear is None else np.array(linear, float),
                     None if angular is None else np.array(angular, float))


def _floor(backend: DynamicsBackend, **material: Any) -> None:
    _add(backend, GROUND, Physical(kind="static", mass=None,
                                   shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))],
                                   material=_material(**material)), (0.0, 0.0, 0.0))


def _quat_y(phi: float) -> np.ndarray:
    """Rotation by ``phi`` about +Y (takes X toward −Z)."""
    return np.array(quat_from_rotation_vector((0.0, phi, 0.0)))


def _steps(seconds: float, dt: float) -> int:
    return round(seconds / dt)


# -- theory ---------------------------------------------------------------------
def pendulum_period(length: float, radius: float, amplitude: float) -> float:
    """Period (s) of a ball of ``radius`` on a massless rod, centre ``length`` from the
    pivot, released from rest at ``amplitude`` (rad): 4√(I/mgL)·K(k²), k = sin(θ₀/2)."""
    inertia = length**2 + 0.4 * radius**2  # about the pivot, per unit mass
    k = math.sin(amplitude / 2)
    return 4 * math.sqrt(inertia / (G * length)) * float(ellipk(k * k))


def steady_precession(i1: float, i3: float, spin: float, tilt: float, mgl: float) -> float:
    """The slow steady precession rate (rad/s) of a symmetric top: the smaller root of
    I₁ cos θ Ω² − I₃ ω₃ Ω + m g l = 0 (I₁ about the pivot, ω₃ the spin component)."""
    a, b = i1 * math.cos(tilt), i3 * spin
    return (b - math.sqrt(b * b - 4 * a * mgl)) / (2 * a)


def zero_crossing_period(t: np.ndarray, x: np.ndarray) -> float:
    """Mean period from the upward zero crossings of ``x`` (linearly interpolated)."""
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    if len(up) < 2:
        return math.nan
    times = t[up] + (t[up + 1] - t[up]) * x[up] / (x[up] - x[up + 1])
    return float(np.mean(np.diff(times)))


# -- the cases ------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class Outcome:
    """What a run gave: the measured value, and extra figures worth a column."""

    value: float
    extra: dict[str, float] | None = None


@dataclass(frozen=True, slots=True)
class Case:
    """One reference case: how to run it on a backend and in MuJoCo, and its theory."""

    name: str
    group: str
    #: What theory predicts, in ``unit``.
    theory: float
    unit: str
    ours: Callable[[str, float], Outcome]
    mujoco: Callable[[float], Outcome] | None
    #: How the error is told: "relative" (% of theory) or "absolute" (in ``unit``).
    error: str = "relative"
    #: Whether the 2D backend can simulate it (it moves in the X–Z plane).
    planar: bool = True
    #: The largest error (as ``error_of`` tells it) the engine promises at the default step
    #: on both backends (issue 22; tests/physics/test_accuracy.py holds it), or None.
    goal: float | None = None

    def error_of(self, value: float) -> float:
        if self.error == "relative":
            return 100.0 * (value - self.theory) / self.theory
        return value - self.theory


PENDULUM_LENGTH, BOB = 1.0, 0.05
PIVOT = (0.0, 0.0, 2.0)


def _pendulum_ours(kind: str, amplitude: float) -> Callable[[str, float], Outcome]:
    def run(backend_name: str, dt: float) -> Outcome:
        period = pendulum_period(PENDULUM_LENGTH, BOB, amplitude)
        with world(backend_name) as backend:
            _add(backend, 1, _ball(BOB), (PENDULUM_LENGTH * math.sin(amplitude), 0.0,
                                          PIVOT[2] - PENDULUM_LENGTH * math.cos(amplitude)))
            backend.add_joint(10, Joint(kind=kind, body_a=1, anchor=PIVOT, axis=(0.0, 1.0, 0.0)))
            probe = Probe(backend)
            n = _steps(4.2 * period, dt)
            xs = np.empty(n)
            for i in range(n):
                backend.step(dt)
                xs[i] = probe().position(1)[0]
        return Outcome(zero_crossing_period(dt * np.arange(1, n + 1), xs))
    return run


def _pendulum_mujoco(kind: str, amplitude: float) -> Callable[[float], Outcome]:
    def run(dt: float) -> Outcome:
        mj, (model, data) = _mujoco(f"""
          <option timestep="{dt}"/>
          <worldbody><body pos="{PIVOT[0]} {PIVOT[1]} {PIVOT[2]}">
            <joint type="{kind}" {'axis="0 1 0"' if kind == 'hinge' else ''}/>
            <geom type="sphere" size="{BOB}" pos="0 0 {-PENDULUM_LENGTH}" mass="1"/>
          </body></worldbody>""")
        _mj_turn_y(data, model, kind, amplitude)
        period = pendulum_period(PENDULUM_LENGTH, BOB, amplitude)
        n = _steps(4.2 * period, dt)
        xs = np.empty(n)
        for i in range(n):
            mj.mj_step(model, data)
            xs[i] = data.geom_xpos[0][0]
        return Outcome(zero_crossing_period(dt * np.arange(1, n + 1), xs))
    return run


def _mj_turn_y(data: Any, model: Any, kind: str, angle: float) -> None:
    """Start a body hung by a hinge about +Y or a ball joint turned by ``angle`` about +Y
    (the bob swings toward +X)."""
    if kind == "hinge":
        data.qpos[0] = angle
    else:
        data.qpos[0:4] = _quat_y(angle)
    import mujoco

    mujoco.mj_forward(model, data)


BALL_RADIUS, DROP = 0.1, 1.0
#: The restitution the rebound goal is stated for (issue 22: Bounce 0.8).
BOUNCE_GOAL = 0.8


def _first_apex(steps: int, advance: Callable[[], tuple[float, float]]) -> float:
    """The highest a dropped ball's bottom gets after it first moves up; ``advance`` takes a
    step and says (height of its bottom, vertical speed)."""
    apex, rising = -math.inf, False
    for _ in range(steps):
        z, vz = advance()
        rising = rising or vz > 0.0
        if rising:
            if vz < 0.0:
                break
            apex = max(apex, z)
    return apex


def _bounce_ours(e: float, drop: float = DROP,
                 mass: float = 1.0) -> Callable[[str, float], Outcome]:
    """The first rebound's apex over the drop height (bottom of the ball to the floor)."""
    def run(backend_name: str, dt: float) -> Outcome:
        with world(backend_name) as backend:
            _floor(backend, bounce=e)
            _add(backend, 1, _ball(BALL_RADIUS, mass, bounce=e), (0.0, 0.0, drop + BALL_RADIUS))
            probe = Probe(backend)

            def advance() -> tuple[float, float]:
                backend.step(dt)
                p = probe()
                return p.position(1)[2] - BALL_RADIUS, p.velocity(1)[2]

            apex = _first_apex(_steps(2 * math.sqrt(2 * drop / G) + 0.2, dt), advance)
        return Outcome(apex / drop)
    return run


def _restitution_solref(e: float, dt: float) -> str:
    """MuJoCo has no coefficient of restitution: a contact is a damped spring. This one
    has MuJoCo's default time constant (0.02 s, at least two steps) as its stiffness
    (k = 1/τ², per unit mass) and the damping ratio ζ whose half oscillation returns e
    of the speed, e = exp(−πζ/√(1−ζ²)); given as (−stiffness, −damping)."""
    zeta = -math.log(e) / math.sqrt(math.pi**2 + math.log(e) ** 2) if e > 0 else 1.0
    omega = 1.0 / max(0.02, 2 * dt)
    return f"{-omega * omega} {-2 * zeta * omega}"


def _bounce_mujoco(e: float) -> Callable[[float], Outcome]:
    def run(dt: float) -> Outcome:
        mj, (model, data) = _mujoco(f"""
          <option timestep="{dt}"/>
          <worldbody><geom type="plane" size="5 5 0.1" solref="{_restitution_solref(e, dt)}"/>
            <body pos="0 0 {DROP + BALL_RADIUS}"><freejoint/>
              <geom type="sphere" size="{BALL_RADIUS}" mass="1"
                    solref="{_restitution_solref(e, dt)}"/></body>
          </worldbody>""")

        def advance() -> tuple[float, float]:
            mj.mj_step(model, data)
            return data.qpos[2] - BALL_RADIUS, data.qvel[2]

        apex = _first_apex(_steps(2 * math.sqrt(2 * DROP / G) + 0.2, dt), advance)
        return Outcome(apex / DROP)
    return run


SLIDE_SPEED, SLIDE_MU, CRATE = 3.0, 0.3, 0.2


def _slide_ours(backend_name: str, dt: float) -> Outcome:
    with world(backend_name) as backend:
        _floor(backend, friction=SLIDE_MU)
        _add(backend, 1, Physical(mass=1.0, shapes=[Shape("box", (CRATE,) * 3)],
                                  material=_material(friction=SLIDE_MU)),
             (0.0, 0.0, CRATE / 2), linear=(SLIDE_SPEED, 0.0, 0.0))
        probe = Probe(backend)
        for _ in range(_steps(2 * SLIDE_SPEED / (SLIDE_MU * G), dt)):
            backend.step(dt)
            if abs(probe().velocity(1)[0]) < 1e-9:
                break
        return Outcome(float(probe.position(1)[0]))


def _slide_mujoco(dt: float) -> Outcome:
    mj, (model, data) = _mujoco(f"""
      <option timestep="{dt}"/>
      <worldbody><geom type="plane" size="10 10 0.1" friction="{SLIDE_MU} 0 0"/>
        <body pos="0 0 {CRATE / 2}"><freejoint/>
          <geom type="box" size="{CRATE / 2} {CRATE / 2} {CRATE / 2}" mass="1"
                friction="{SLIDE_MU} 0 0"/></body>
      </worldbody>""")
    data.qvel[0] = SLIDE_SPEED
    for _ in range(_steps(2 * SLIDE_SPEED / (SLIDE_MU * G), dt)):
        mj.mj_step(model, data)
    return Outcome(float(data.qpos[0]))


ROLL_TIME = 2.0


def _incline_ours(degrees: float) -> Callable[[str, float], Outcome]:
    def run(backend_name: str, dt: float) -> Outcome:
        theta = math.radians(degrees)
        q = _quat_y(theta)  # falls toward +X
        normal = np.array([math.sin(theta), 0.0, math.cos(theta)])
        downhill = np.array([math.cos(theta), 0.0, -math.sin(theta)])
        with world(backend_name) as backend:
            _add(backend, 2, Physical(kind="static", mass=None,
                                      shapes=[Shape("box", (40.0, 2.0, 0.2))]),
                 (0.0, 0.0, 0.0), q)
            start = normal * (0.1 + BALL_RADIUS)
            _add(backend, 1, _ball(BALL_RADIUS), tuple(start))
            probe = Probe(backend)
            n = _steps(ROLL_TIME, dt)
            s = np.empty(n)
            for i in range(n):
                backend.step(dt)
                s[i] = float(np.dot(probe().position(1) - start, downhill))
        return Outcome(_acceleration(dt * np.arange(1, n + 1), s))
    return run


def _acceleration(t: np.ndarray, s: np.ndarray) -> float:
    """Constant acceleration fitted to a distance travelled (s = s₀ + v₀t + at²/2)."""
    return 2.0 * float(np.polyfit(t, s, 2)[0])


def _incline_mujoco(degrees: float) -> Callable[[float], Outcome]:
    def run(dt: float) -> Outcome:
        theta = math.radians(degrees)
        normal = np.array([math.sin(theta), 0.0, math.cos(theta)])
        downhill = np.array([math.cos(theta), 0.0, -math.sin(theta)])
        start = normal * BALL_RADIUS
        mj, (model, data) = _mujoco(f"""
          <option timestep="{dt}"/>
          <worldbody><geom type="plane" size="40 2 0.1" euler="0 {degrees} 0"/>
            <body pos="{start[0]} {start[1]} {start[2]}"><freejoint/>
              <geom type="sphere" size="{BALL_RADIUS}" mass="1"/></body>
          </worldbody>""")
        n = _steps(ROLL_TIME, dt)
        s = np.empty(n)
        for i in range(n):
            mj.mj_step(model, data)
            s[i] = float(np.dot(data.qpos[0:3] - start, downhill))
        return Outcome(_acceleration(dt * np.arange(1, n + 1), s))
    return run


STACK, STACK_BOX, STACK_TIME = 10, 0.5, 20.0


def _stack_ours(backend_name: str, dt: float) -> Outcome:
    """Crates of default density (125 kg), standing exactly on each other."""
    with world(backend_name) as backend:
        _floor(backend)
        crate = Physical(mass=None, shapes=[Shape("box", (STACK_BOX,) * 3)])
        for i in range(STACK):
            _add(backend, i, crate, (0.0, 0.0, STACK_BOX * (i + 0.5)))
        probe = Probe(backend)
        for _ in range(_steps(STACK_TIME, dt)):
            backend.step(dt)
        moved = probe().position(STACK - 1) - (0.0, 0.0, STACK_BOX * (STACK - 0.5))
    return Outcome(1e3 * float(np.hypot(moved[0], moved[1])), {"sink mm": -1e3 * moved[2]})


def _stack_mujoco(dt: float) -> Outcome:
    h = STACK_BOX / 2
    bodies = "".join(f"""<body pos="0 0 {STACK_BOX * (i + 0.5)}"><freejoint/>
        <geom type="box" size="{h} {h} {h}" density="1000"/></body>""" for i in range(STACK))
    mj, (model, data) = _mujoco(f"""
      <option timestep="{dt}"/>
      <worldbody><geom type="plane" size="5 5 0.1"/>{bodies}</worldbody>""")
    top = 7 * (STACK - 1)
    start = data.qpos[top:top + 3].copy()
    for _ in range(_steps(STACK_TIME, dt)):
        mj.mj_step(model, data)
    moved = data.qpos[top:top + 3] - start
    return Outcome(1e3 * float(np.hypot(moved[0], moved[1])), {"sink mm": -1e3 * moved[2]})


CRADLE, CRADLE_BALL, CRADLE_ANGLE = 5, 0.05, math.radians(20.0)


def _cradle_ours(backend_name: str, dt: float) -> Outcome:
    """The last ball's highest swing after the first impact, as a share of the release."""
    with world(backend_name) as backend:
        for i in range(CRADLE):
            px = 2 * CRADLE_BALL * i
            phi = -CRADLE_ANGLE if i == 0 else 0.0
            _add(backend, i, _ball(CRADLE_BALL, friction=0.0, bounce=1.0),
                 (px + PENDULUM_LENGTH * math.sin(phi), 0.0,
                  PIVOT[2] - PENDULUM_LENGTH * math.cos(phi)))
            backend.add_joint(10 + i, Joint(kind="hinge", body_a=i, anchor=(px, 0.0, PIVOT[2]),
                                            axis=(0.0, 1.0, 0.0)))
        probe = Probe(backend)
        rest = 2 * CRADLE_BALL * (CRADLE - 1)
        highest = 0.0
        for _ in range(_steps(0.5 * pendulum_period(PENDULUM_LENGTH, CRADLE_BALL,
                                                    CRADLE_ANGLE), dt)):
            backend.step(dt)
            highest = max(highest, probe().position(CRADLE - 1)[0] - rest)
    return Outcome(math.asin(min(highest / PENDULUM_LENGTH, 1.0)) / CRADLE_ANGLE)


def _cradle_mujoco(dt: float) -> Outcome:
    solref = _restitution_solref(1.0, dt)
    bodies = "".join(f"""<body pos="{2 * CRADLE_BALL * i} 0 {PIVOT[2]}">
        <joint type="hinge" axis="0 1 0"/>
        <geom type="sphere" size="{CRADLE_BALL}" pos="0 0 {-PENDULUM_LENGTH}" mass="1"
              friction="0 0 0" solref="{solref}"/></body>""" for i in range(CRADLE))
    mj, (model, data) = _mujoco(f"""
      <option timestep="{dt}"/><worldbody>{bodies}</worldbody>""")
    data.qpos[0] = CRADLE_ANGLE  # a turn about +Y takes the first ball toward −X
    mj.mj_forward(model, data)
    highest = 0.0
    for _ in range(_steps(0.5 * pendulum_period(PENDULUM_LENGTH, CRADLE_BALL, CRADLE_ANGLE),
                          dt)):
        mj.mj_step(model, data)
        highest = max(highest, -data.qpos[CRADLE - 1])
    return Outcome(highest / CRADLE_ANGLE)


TOP_RADIUS, TOP_THICKNESS, TOP_ARM, TOP_MASS = 0.1, 0.02, 0.1, 1.0
TOP_SPIN, TOP_TILT, TOP_TIME = 100.0, math.radians(30.0), 3.0


def _top() -> tuple[float, float, float, float]:
    """(I₁ about the pivot, I₃, ω₃, the steady precession rate) of the top."""
    i3 = TOP_MASS * TOP_RADIUS**2 / 2
    i1 = TOP_MASS * (TOP_RADIUS**2 / 4 + TOP_THICKNESS**2 / 12 + TOP_ARM**2)
    rate = steady_precession(i1, i3, TOP_SPIN, TOP_TILT, TOP_MASS * G * TOP_ARM)
    return i1, i3, TOP_SPIN, rate


def _top_start() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(pivot, centre, axis, angular velocity): tilted toward +X, precessing steadily."""
    _, _, spin, rate = _top()
    axis = np.array([math.sin(TOP_TILT), 0.0, math.cos(TOP_TILT)])
    pivot = np.array(PIVOT)
    centre = pivot + TOP_ARM * axis
    # ω = ψ̇ e₃ + Ω z, with the spin component ω·e₃ = ψ̇ + Ω cos θ = ω₃
    omega = (spin - rate * math.cos(TOP_TILT)) * axis + rate * np.array([0.0, 0.0, 1.0])
    return pivot, centre, axis, omega


def _precession(t: np.ndarray, axes: np.ndarray) -> float:
    """The mean turning rate (rad/s) of an axis's azimuth about Z."""
    azimuth = np.unwrap(np.arctan2(axes[:, 1], axes[:, 0]))
    return float(np.polyfit(t, azimuth, 1)[0])


def _axis_z(q: np.ndarray) -> np.ndarray:
    """The body's local Z axis in the world, for (N, 4) quaternions w, x, y, z."""
    w, x, y, z = q.T
    return np.column_stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def _top_ours(backend_name: str, dt: float) -> Outcome:
    pivot, centre, _, omega = _top_start()
    with world(backend_name) as backend:
        disc = Physical(mass=TOP_MASS, shapes=[Shape("cylinder", (TOP_RADIUS, TOP_THICKNESS))])
        _add(backend, 1, disc, tuple(centre), _quat_y(TOP_TILT),
             linear=tuple(np.cross(omega, centre - pivot)), angular=tuple(omega))
        backend.add_joint(10, Joint(kind="ball", body_a=1, anchor=tuple(pivot)))
        probe = Probe(backend)
        n = _steps(TOP_TIME, dt)
        q = np.empty((n, 4))
        for i in range(n):
            backend.step(dt)
            q[i] = probe().orientation(1)
    return Outcome(_precession(dt * np.arange(1, n + 1), _axis_z(q)))


def _top_mujoco(dt: float) -> Outcome:
    pivot, _, _, omega = _top_start()
    q = _quat_y(TOP_TILT)
    mj, (model, data) = _mujoco(f"""
      <option timestep="{dt}"/>
      <worldbody><body pos="{pivot[0]} {pivot[1]} {pivot[2]}">
        <joint type="ball"/>
        <geom type="cylinder" size="{TOP_RADIUS} {TOP_THICKNESS / 2}" mass="{TOP_MASS}"
              pos="0 0 {TOP_ARM}"/></body></worldbody>""")
    data.qpos[0:4] = q
    r = quat_to_matrix(q)
    data.qvel[0:3] = r.T @ omega  # a ball joint's velocity is in the body frame
    n = _steps(TOP_TIME, dt)
    quats = np.empty((n, 4))
    for i in range(n):
        mj.mj_step(model, data)
        quats[i] = data.qpos[0:4]
    return Outcome(_precession(dt * np.arange(1, n + 1), _axis_z(quats)))


MOTOR_SPEED, MOTOR_TORQUE, BAR_MASS = 2.0, 60.0, 10.0


def _motor_ours(backend_name: str, dt: float) -> Outcome:
    """The mean rate from 0.5 s on, while the bar goes round against gravity."""
    with world(backend_name) as backend:
        _add(backend, 1, Physical(mass=BAR_MASS, shapes=[Shape("box", (1.0, 0.1, 0.1))]),
             (0.5, 0.0, PIVOT[2]))
        backend.add_joint(10, Joint(kind="motorized_hinge", body_a=1, anchor=PIVOT,
                                    axis=(0.0, 1.0, 0.0), motor_velocity=MOTOR_SPEED,
                                    motor_max_force=MOTOR_TORQUE))
        rates = []
        for i in range(_steps(3.0, dt)):
            backend.step(dt)
            if (i + 1) * dt > 0.5:
                rates.append(backend.joint_state(10)[1])
    return Outcome(float(np.mean(rates)), {"slowest": float(np.min(rates))})


def _motor_mujoco(dt: float) -> Outcome:
    mj, (model, data) = _mujoco(f"""
      <option timestep="{dt}"/>
      <worldbody><body pos="{PIVOT[0]} {PIVOT[1]} {PIVOT[2]}">
        <joint name="j" type="hinge" axis="0 1 0"/>
        <geom type="box" size="0.5 0.05 0.05" pos="0.5 0 0" mass="{BAR_MASS}"/></body>
      </worldbody>
      <actuator><velocity joint="j" kv="{BAR_MASS * 100}"
                 forcerange="{-MOTOR_TORQUE} {MOTOR_TORQUE}"/></actuator>""")
    data.ctrl[0] = MOTOR_SPEED
    rates = []
    for i in range(_steps(3.0, dt)):
        mj.mj_step(model, data)
        if (i + 1) * dt > 0.5:
            rates.append(float(data.qvel[0]))
    return Outcome(float(np.mean(rates)), {"slowest": float(np.min(rates))})


def _mujoco(body: str) -> tuple[Any, tuple[Any, Any]]:
    """MuJoCo and a model with its data from the inside of an MJCF ``<mujoco>``. MuJoCo's
    warnings (it writes them to MUJOCO_LOG.TXT and stderr) are only counted: a run that
    went unstable says so in its row (:func:`_mujoco_outcome`)."""
    import mujoco

    mujoco.set_mju_user_warning(lambda message: None)
    model = mujoco.MjModel.from_xml_string(f"<mujoco>{body}</mujoco>")
    for option, value in _MJ_OPTIONS.items():
        setattr(model.opt, option, value)
    data = mujoco.MjData(model)
    _RUNS.append(data)
    return mujoco, (model, data)


#: The MuJoCo data of the runs under way (to read their warning counters afterwards).
_RUNS: list[Any] = []


def _mujoco_outcome(run: Callable[[float], Outcome], dt: float) -> Outcome:
    """A MuJoCo run's outcome, marked ``unstable`` when MuJoCo found non-finite or huge
    accelerations and reset the simulation."""
    import mujoco

    _RUNS.clear()
    got = run(dt)
    bad = sum(int(d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number) for d in _RUNS)
    _RUNS.clear()
    return Outcome(got.value, {**(got.extra or {}), "unstable": float(bad > 0)}) if bad \
        else got


def cases() -> list[Case]:
    """Every reference case."""
    out = []
    for kind in ("hinge", "ball"):
        for degrees in (2.0, 5.0, 30.0):
            a = math.radians(degrees)
            out.append(Case(f"{kind} pendulum {degrees:g}°", "pendulum",
                            pendulum_period(PENDULUM_LENGTH, BOB, a), "s",
                            _pendulum_ours(kind, a), _pendulum_mujoco(kind, a), goal=0.5))
    for e in (0.3, 0.6, 0.8, 0.95):
        out.append(Case(f"bounce e={e:g}", "bounce", e * e, "of the drop", _bounce_ours(e),
                        _bounce_mujoco(e), goal=2.0 if e == BOUNCE_GOAL else None))
    out.append(Case("friction slide", "slide", SLIDE_SPEED**2 / (2 * SLIDE_MU * G), "m",
                    _slide_ours, _slide_mujoco, goal=1.0))
    for degrees in (1.0, 3.0):
        out.append(Case(f"rolling incline {degrees:g}°", "incline",
                        5 / 7 * G * math.sin(math.radians(degrees)), "m/s²",
                        _incline_ours(degrees), _incline_mujoco(degrees)))
    out.append(Case("10-crate stack drift", "stack", 0.0, "mm", _stack_ours, _stack_mujoco,
                    error="absolute", goal=10.0))
    out.append(Case("Newton's cradle", "cradle", 1.0, "of the release angle", _cradle_ours,
                    _cradle_mujoco))
    out.append(Case("spinning top precession", "top", _top()[3], "rad/s", _top_ours,
                    _top_mujoco, planar=False))
    out.append(Case("motorized hinge under load", "motor", MOTOR_SPEED, "rad/s", _motor_ours,
                    _motor_mujoco))
    return out


def mujoco_version() -> str | None:
    """MuJoCo's version, or None when it is not installed."""
    try:
        import mujoco
    except ImportError:
        return None
    return str(mujoco.__version__)


def run_bench(quick: bool = False, backend: str | None = None,
              only: str | None = None) -> list[dict[str, Any]]:
    """One row per case, step and backend: the error against theory beside MuJoCo's."""
    names = (backend,) if backend else ("ode", "pymunk")
    steps = (0.02, DEFAULT_STEP) if quick else STEPS
    anchor = mujoco_version()
    if anchor is None:
        print("MuJoCo is not installed: no MuJoCo column (pip install .[anchors])")
    rows = []
    for case in cases():
        if only and only not in case.name:
            continue
        for dt in steps:
            theirs = _mujoco_outcome(case.mujoco, dt) if anchor and case.mujoco else None
            for name in names:
                if name == "pymunk" and not case.planar:
                    continue
                got = case.ours(name, dt)
                row: dict[str, Any] = {
                    "case": case.name, "dt": dt, "default step": dt == DEFAULT_STEP,
                    "backend": name, "theory": case.theory, "unit": case.unit,
                    "measured": got.value, "error": case.error_of(got.value),
                    "error is": "%" if case.error == "relative" else case.unit}
                if case.goal is not None:
                    row["goal"] = case.goal
                for k, v in (got.extra or {}).items():
                    row[k] = v
                if theirs is not None:
                    row["mujoco measured"] = theirs.value
                    row["mujoco error"] = case.error_of(theirs.value)
                    for k, v in (theirs.extra or {}).items():
                        row[f"mujoco {k}"] = v
                print_row(row)
                rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--backend", choices=("ode", "pymunk"))
    parser.add_argument("--only", help="cases whose name contains this")
    args = parser.parse_args(argv)
    print_table(run_bench(args.quick, args.backend, args.only))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
