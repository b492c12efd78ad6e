"""The resting warm start on pymunk: ODE's (engine/physics/ode3d/stepper.h) in the plane.

chipmunk warm-starts each contact from its last impulse, yet 20 iterations leave a
stack of ten crates rocking 2 to 4 cm at 100 Hz and toppling at 50 Hz. As on ODE, a
body at rest on its contacts gets ``warm_start`` of its weight as an upward force
before the step, so the solver finds only the rest of every contact force (for a body
at rest the contacts' whole force is its weight: normal and friction scale alike, and
the motion is the same whenever the solver converges). The rules and their constants are
written once for both backends, in C (engine/physics/policy.h's rp_stand, which ODE's
step calls too): at rest means held up by the contacts (REST_SUPPORT of the weight) for
two steps, not pushed sideways (the force averaged over REST_SMOOTHING seconds, against
REST_GRIP of the friction), friction short of its bound (REST_SLIDING), moving slower
than REST_SLIP, resting on a face (two contact points in the plane) or on level ground
only, with no joint and touching no kinematic body, in an island (bodies touching) with
no jointed, weightless or pushed body: each preloaded weight must reach the ground through
contacts (a platform a force holds up or a wheelchair's seat would take the preload of
what rests on it instead). Everything after the step is one compiled pass over chipmunk
(``_rows.Resting.after``: the bodies and arbiters read, what the contacts did, the
standing, the held rows' velocities written), as is the preload before it
(``_rows.Resting.preload``, the preloaded rows' forces read and written): no Python per
body.

A preloaded body resting on a face (two contact points) in equilibrium (its centre of
mass over the span of the points it lies on, policy.h's REST_BASE_MARGIN in: a block whose
centre of mass lies past its base must tip) that moves across gravity and turns slower
than REST_STILL_* (the sleep rule's limits) is held still after the step, as ODE's step
holds it (policy.h): chipmunk has no block solve, and a crate resting at zero
depth loses the corner that lifts by a hair, so from the first steps a stack rocks on its
base; the rocking decayed over 5 to 14 s above the sleep rule's steady band (asleep 5 to
14 s after settling), held it is asleep half a second after, and stands closer (the
bench's stack: 0.32 mm in 20 s at 0.01 s, was 1.6).
"""

from __future__ import annotations

import numpy as np

from engine.physics.pymunk2d import _rows

#: chipmunk's own warm start carries last step's impulses over: a preload switched on
#: at once would come on top of them for a step and pop a stack apart. It is ramped in by
#: this share of its full size a step, and out by twice that.
RAMP = 0.1


class RestingSupport:
    """Each row's standing (steps at rest, slid, the averaged force its contacts hold it
    with), its preload ramp, and the compiled passes over them (:class:`_rows.Resting`,
    over policy.h's rules: one call before a step, one after it)."""

    #: per-row arrays that follow their bodies when rows change; the rest start afresh
    _FOLLOW = ("steps", "slid", "held", "ramp", "still", "base")
    _SHAPES = {"mu": ((), np.float64), "mass": ((), np.float64), "cog": ((2,), np.float64),
               "jointed": ((), np.uint8), "kinematic": ((), np.uint8),
               "dynamic": ((), np.uint8), "held": ((2,), np.float64),
               "steps": ((), np.int8), "slid": ((), np.uint8), "kept": ((), np.uint8),
               "still": ((), np.uint8), "base": ((2,), np.float64),
               "reach": ((2,), np.float64),
               "ramp": ((), np.float64), "applied": ((), np.float64),
               "lifted": ((), np.float64), "force": ((2,), np.float64),
               "friction": ((), np.float64), "grip": ((), np.float64),
               "points": ((), np.int64), "tilted": ((), np.uint8),
               "chosen": ((), np.uint8), "unrest": ((), np.uint8),
               "moving": ((), np.uint8), "blocked": ((), np.uint8),
               "labels": ((), np.intp)}

    def __init__(self, n: int, beta: float) -> None:
        self.beta = beta
        self.arrays = self._fresh(n)
        self._pass = _rows.Resting(self.arrays)
        #: whether some row has its ramp on (it gets a preload before the next step)
        self.on = False

    @classmethod
    def _fresh(cls, n: int) -> dict[str, np.ndarray]:
        return {name: np.zeros((n, *shape), dtype) for name, (shape, dtype) in
                cls._SHAPES.items()}

    @property
    def n(self) -> int:
        """How many rows."""
        return len(self.arrays["steps"])

    def __getattr__(self, name: str) -> np.ndarray:
        try:
            return self.__dict__["arrays"][name]
        except KeyError:
            raise AttributeError(name) from None

    def follow(self, old_rows: np.ndarray) -> None:
        """New rows: each keeps the standing of ``old_rows[i]`` (-1: a new body); the
        bodies' own numbers are set again by :meth:`bodies`."""
        had = old_rows >= 0
        arrays = self._fresh(len(old_rows))
        for name in self._FOLLOW:
            arrays[name][had] = self.arrays[name][old_rows[had]]
        self.arrays = arrays
        self._pass = _rows.Resting(arrays)
        self.on = bool((arrays["ramp"] > 0).any())

    def bodies(self, mu: np.ndarray, mass: np.ndarray, cog: np.ndarray, jointed: np.ndarray,
               kinematic: np.ndarray, dynamic: np.ndarray) -> None:
        """Per row: friction coefficient, mass under gravity (0: not dynamic or gravity
        off), centre of gravity in the body's frame ((n, 2): whether it stands over its
        base decides the hold), jointed, a kinematic body with shapes (what it touches is
        not at rest), dynamic."""
        for name, value in (("mu", mu), ("mass", mass), ("cog", cog), ("jointed", jointed),
                            ("kinematic", kinematic), ("dynamic", dynamic)):
            self.arrays[name][:] = value

    @property
    def held_still(self) -> int:
        """How many rows the last step's pass held still (their velocity zeroed in its
        read, to be written back to the space)."""
        return self._pass.held_still

    @property
    def islands(self) -> np.ndarray | None:
        """Each row's island label (rows tied by contacts between moving bodies) when the
        last step found them (some row was chosen); None otherwise."""
        return self.arrays["labels"] if self._pass.found else None

    def forget(self, rows: np.ndarray) -> None:
        """These rows start afresh (moved or pushed by hand: no longer at rest), and their
        islands lose the preload for the next step."""
        rows = rows[rows >= 0]
        self.steps[rows] = 0
        self.slid[rows] = False
        islands = self.islands
        if islands is not None and len(rows):
            rows = np.flatnonzero(np.isin(islands, islands[rows]))
        self.ramp[rows] = 0.0
        self.kept[rows] = False
        self.still[rows] = False
        self.on = bool((self.ramp > 0).any())

    def preload(self, rows: _rows.Rows, gravity: tuple[float, float]) -> int:
        """Before a step: each awake row whose ramp is on given beta × ramp of its weight
        upward, on top of the force its body has (written into chipmunk for those rows;
        the share into ``applied``, the force into ``lifted``); how many rows got one."""
        return self._pass.preload(rows, self.beta, gravity[0], gravity[1])

    def no_preload(self) -> None:
        """No row got a preload this step."""
        self.applied[:] = 0.0
        self.lifted[:] = 0.0

    def after(self, rows: _rows.Rows, dt: float, gravity: tuple[float, float]) -> None:
        """After a step: every row's standing and its ramp for the next step, in one
        compiled pass (:meth:`_rows.Resting.after`) over the bodies (read by it, right
        after the step) and the step's arbiters. At rest means held up by its
        contacts (REST_SUPPORT of its weight, the share it was preloaded with aside) with
        its friction short of its bound, not pushed sideways, for two steps (policy.h's
        rp_stand); preloaded, a body stays so while it is held up at all (chipmunk
        carries its impulses over, and a preload switched off and on again jolts them).
        A chosen row (slower than REST_SLIP, four times that to stay; on a face or level
        ground; not jointed or touching a kinematic body) ramps in by RAMP a step in an
        island with no moving row that is unrest or weightless, and out by twice that;
        off at once where no contact is left. A preloaded row on a face slower than
        REST_STILL_* is held still: its velocity zeroed in the read and in chipmunk
        (:attr:`held_still` counts them). The bodies are read first (``rows.read()``'s
        read, which the step's state read and the sleep rule take too)."""
        self.on = self._pass.after(rows, dt, gravity[0], gravity[1], self.beta, RAMP) > 0


def carried_down(rows_a: np.ndarray, rows_b: np.ndarray, impulse: np.ndarray,
                 normal_up: np.ndarray, load: np.ndarray, rounds: int = 64) -> np.ndarray:
    """Contact impulses with the preloads put back: each preloaded row's share of its weight
    (``load``, N·s upward) goes into the contacts holding it up, in proportion to what each
    carried, and on through the rows under them down to the ground (stepper.h's
    cs_add_preloads in the plane). ``normal_up`` is each contact's normal (from b toward a)
    along the vertical; row -1 is static geometry. What each row passes on is found by
    repeating the pass down the stack until it settles (a stack's height of rounds); the
    passes are one C loop each (``_rows.carried_down``)."""
    return _rows.carried_down(np.ascontiguousarray(rows_a, np.int64),
                              np.ascontiguousarray(rows_b, np.int64),
                              np.asarray(impulse, np.float64),
                              np.ascontiguousarray(normal_up, np.float64),
                              np.ascontiguousarray(load, np.float64), int(rounds))
