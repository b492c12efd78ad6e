"""A saved state puts ODE's own numbers back: the rows ``exact_state`` gives, put back as
loading a saved state does (a body made at that pose and velocity), restore the body's
centre of mass, orientation and velocities to the bit, where ``read_state``'s rows come
back rounded (a centre of mass off the origin, ODE normalising the quaternion again).
A chaotic contact amplifies an ulp: the demo's rock on its turntable ended 0.75 m away
200 frames after a reload."""

from __future__ import annotations

import numpy as np
import pytest

from components import Physical
from components.physical import Shape

ode = pytest.importorskip("engine.physics.ode3d.backend")


def body_with_offset_centre(offset: np.ndarray) -> Physical:
    return Physical(mass=2.0, shapes=(Shape("box", (0.3, 0.2, 0.1), offset=tuple(offset)),))


def moved_and_reloaded(rng: np.random.Generator, rows: str) -> tuple[np.ndarray, np.ndarray]:
    """A body stepped into a random state, and one made from its ``rows`` state: both
    backends' exact rows (equal exactly when the raw states are)."""
    q = rng.normal(size=4)
    offset = rng.normal(size=3) * 0.2
    first = ode.OdeBackend()
    first.add_body(1, body_with_offset_centre(offset), rng.normal(size=3), q / np.linalg.norm(q),
                   rng.normal(size=3), rng.normal(size=3) * 3)
    for _ in range(3):
        first.step(0.01)
    row = getattr(first, rows)().table[0]
    second = ode.OdeBackend()
    second.add_body(1, body_with_offset_centre(offset), row[:3], row[3:7], row[7:10],
                    row[10:13])
    return first.exact_state().table[0], second.exact_state().table[0]


def test_exact_rows_put_odes_numbers_back_where_read_states_round():
    rng = np.random.default_rng(7)
    exact = [np.array_equal(*moved_and_reloaded(rng, "exact_state")) for _ in range(100)]
    rng = np.random.default_rng(7)
    read = [np.array_equal(*moved_and_reloaded(rng, "read_state")) for _ in range(100)]
    # a few quaternions have no nearby one ODE's normalisation turns into them exactly
    assert sum(exact) >= 95
    assert sum(read) <= 80  # 61 here: a rounded origin or velocity in about every third
