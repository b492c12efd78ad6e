"""pymunk backend: state reads stay right as bodies sleep, wake and go; sleeping; queries."""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pymunk.batch
import pytest

from components import Physical, Shape
from engine.physics.backend import BodyState, WorldSettings
from engine.physics.pymunk2d import PymunkBackend
from engine.rotation import quat_multiply

# a failing pymunk callback is only printed by cffi: make it fail the test
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")


def _contacts_one_arbiter_at_a_time(backend: PymunkBackend) -> dict:
    """The same contacts through pymunk's per-arbiter API, body by body:
    {(a, b): (point, normal, impulse)}."""
    key_of = {rec.body: key for key, rec in backend._bodies.items()}
    moving = {key for key, rec in backend._bodies.items()
              if rec.body.body_type != pymunk.Body.STATIC}
    out = {}

    def collect(arbiter: pymunk.Arbiter) -> None:
        points = arbiter.contact_point_set.points
        ba, bb = arbiter.bodies
        if not points or all(b.is_sleeping or b.body_type == pymunk.Body.STATIC
                             for b in (ba, bb)):
            return  # sleepers keep their contacts but are not collided (as under ODE)
        ka, kb = key_of.get(ba, -1), key_of.get(bb, -1)
        normal = -np.array(arbiter.normal)  # pymunk's points from a to b; ours from b to a
        if (ka not in moving, ka) > (kb not in moving, kb):  # the static side is b
            ka, kb, normal = kb, ka, -normal
        point = sum(np.array(p.point_a) + np.array(p.point_b) for p in points) / (
            2 * len(points))
        out[ka, kb] = (point, normal, float(np.hypot(*arbiter.total_impulse)))

    for rec in backend._bodies.values():
        rec.body.each_arbiter(collect)
    return out


def test_contacts_match_pymunks_arbiters_one_by_one(kit) -> None:
    """The batch read finds what pymunk's per-arbiter API finds, body for body (no warm
    start: with it, a preloaded body's impulses are reported whole, more than chipmunk's;
    at 0.01 s: a longer step is substeps, whose contacts are merged)."""
    backend = PymunkBackend()
    backend.configure(WorldSettings(auto_sleep=True, warm_start=0.0))
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(300):  # boxes and balls in rows, falling onto each other
        kit.add(backend, 900 - i, kit.box((0.4, 0.4, 0.4)) if i % 2 else kit.sphere(0.2),
                (0.5 * (i % 30), 0.0, 0.2 + 0.45 * (i // 30)))
    compared = 0
    for step in range(200):  # they settle and fall asleep (and drop their arbiters)
        backend.step(0.01)
        if step == 50:
            backend.remove_body(890)
        if step % 20:
            continue
        ours = backend.contacts()
        theirs = _contacts_one_arbiter_at_a_time(backend)
        assert len(ours) == len(theirs)
        compared += len(ours)
        for row in ours:
            point, normal, impulse = theirs[int(row["a"]), int(row["b"])]
            np.testing.assert_allclose(row["position"][::2], point, atol=1e-12)
            np.testing.assert_allclose(row["normal"][::2], normal, atol=1e-12)
            assert row["impulse"] == pytest.approx(impulse, abs=1e-12)
    assert compared > 600


def _check_state_matches_bodies(backend: PymunkBackend) -> None:
    state = backend.read_state()
    for i, key in enumerate(state.keys):
        body = backend._bodies[int(key)].body
        assert state.position[i, 0] == body.position.x
        assert state.position[i, 2] == body.position.y
        assert state.linear_velocity[i, 0] == body.velocity.x


def test_read_state_survives_sleeping_and_removal(kit) -> None:
    backend = PymunkBackend()
    backend.configure(WorldSettings(auto_sleep=True))
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(12):
        kit.add(backend, i, kit.box((0.4, 0.4, 0.4)), (1.0 * (i % 4), 0.0, 0.2 + 0.45 * (i // 4)))
    kit.add(backend, 99, kit.sphere(), (-3.0, 0.0, 5.0))
    _check_state_matches_bodies(backend)
    for _ in range(180):
        backend.step(1 / 60)
    assert backend._bodies[0].body.is_sleeping
    _check_state_matches_bodies(backend)  # sleepers now come last in pymunk's iteration
    backend.remove_body(5)
    backend.set_sleeping(0, False)
    backend.step(1 / 60)
    _check_state_matches_bodies(backend)
    assert 5 not in backend.read_state().keys


def test_set_sleeping_and_can_sleep(kit) -> None:
    backend = PymunkBackend()
    backend.configure(WorldSettings(auto_sleep=True))
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    kit.add(backend, 1, kit.box((0.4, 0.4, 0.4)), (0.0, 0.0, 0.2))
    restless = kit.box((0.4, 0.4, 0.4))
    restless.can_sleep = False
    kit.add(backend, 2, restless, (2.0, 0.0, 0.2))
    for _ in range(120):
        backend.step(1 / 60)
    assert backend._bodies[1].body.is_sleeping
    assert not backend._bodies[2].body.is_sleeping
    backend.set_sleeping(1, False)
    assert not backend._bodies[1].body.is_sleeping
    backend.set_sleeping(1, True)
    assert backend._bodies[1].body.is_sleeping


def test_gravity_switch_and_damping(kit) -> None:
    backend = PymunkBackend()
    floating = Physical(shapes=[Shape("sphere", (0.1,))], gravity=False, linear_damping=0.1)
    kit.add(backend, 1, floating, (0.0, 0.0, 1.0))
    backend.set_velocity(1, np.array([1.0, 0.0, 0.0]), np.zeros(3))
    for _ in range(10):
        backend.step(1 / 60)
    r = kit.row(backend, 1)
    assert r["position"][2] == 1.0
    assert r["linear"][0] == pytest.approx(0.9**10)


def test_raycast_along_a_tilted_ray_measures_3d_distance(kit) -> None:
    backend = PymunkBackend()
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    d = np.array([0.0, 1.0, -1.0]) / np.sqrt(2.0)
    hit = backend.raycast(np.array([0.0, 0.0, 1.0]), d, 5.0)
    assert hit is not None and hit.key == kit.GROUND
    assert hit.distance == pytest.approx(np.sqrt(2.0))
    np.testing.assert_allclose(hit.position, [0.0, 1.0, 0.0], atol=1e-9)
    assert backend.raycast(np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0]), 5.0) is None


def test_contacts_are_sorted_and_static_side_is_b(kit) -> None:
    backend = PymunkBackend()
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(5):
        kit.add(backend, 10 - i, kit.box((0.4, 0.4, 0.4)), (float(i), 0.0, 0.2))
    backend.step(1 / 60)
    c = backend.contacts()
    assert list(c["a"]) == [6, 7, 8, 9, 10]
    assert set(c["b"]) == {kit.GROUND}
    assert backend.contacts() is c  # computed once per step


def test_a_body_gone_non_finite_is_reset_and_reported(kit) -> None:
    backend = PymunkBackend()
    kit.add(backend, 1, kit.sphere(), (0.0, 0.0, 5.0))
    kit.add(backend, 2, kit.sphere(), (1.0, 0.0, 5.0))
    backend.step(1 / 60)
    good = kit.row(backend, 1)["position"].copy()
    backend._bodies[1].body.velocity = (float("nan"), 0.0)  # what a blown-up solve leaves
    backend.step(1 / 60)
    state = backend.read_state()
    assert np.isfinite(state.position).all() and np.isfinite(state.linear_velocity).all()
    np.testing.assert_allclose(kit.row(backend, 1)["position"], good)
    assert [key for key, _ in backend.take_faults()] == [1]
    assert backend.take_faults() == []
    backend.step(1 / 60)  # the world steps on
    assert kit.row(backend, 2)["position"][2] < 5.0


def test_read_state_into_fills_rows_in_keys_order(kit) -> None:
    backend = PymunkBackend()
    for key in (5, 3, 9):
        kit.add(backend, key, kit.sphere(), (float(key), 1.0, 2.0), kit.quat_y(0.1 * key))
    backend.step(1 / 60)
    table = np.zeros((3, 13))
    assert backend.read_state_into(table).tolist() == [3, 5, 9]
    state = backend.read_state()
    np.testing.assert_array_equal(table, state.table)
    np.testing.assert_array_equal(backend.keys(), state.keys)


def _bodies_for_poses(kit, backend: PymunkBackend) -> None:
    """A tilted box off its centre of mass, a ball, a hand's shapeless kinematic control
    body and a static box: every case a pose is turned into the plane for."""
    tilt = np.array([math.cos(0.3), math.sin(0.3), 0.0, 0.0])  # 34° about X: a rest tilt
    offset = Physical(mass=2.0, shapes=[Shape("box", (0.4, 0.2, 0.1), (0.3, 0.0, 0.2))])
    kit.add(backend, 4, offset, (0.0, 0.5, 1.0), tilt)
    kit.add(backend, 7, kit.sphere(), (1.0, 0.0, 1.0))
    kit.add(backend, 9, Physical(kind="kinematic", mass=1.0, shapes=[], category=0, mask=0,
                                 gravity=False), (2.0, 0.0, 1.0))
    kit.add(backend, 12, kit.box(kind="static", mass=None), (3.0, 0.0, 0.5))


def _raw(backend: PymunkBackend) -> list[tuple[float, ...]]:
    return [(*rec.body.position, rec.body.angle, *rec.body.velocity, rec.body.angular_velocity,
             rec.y) for _, rec in sorted(backend._bodies.items())]


def test_write_state_sets_what_set_pose_and_set_velocity_set_to_the_bit(kit) -> None:
    """Many bodies in one write (the hands' control bodies each frame) and one by one:
    the same pymunk positions, angles and centre-of-mass velocities, bit for bit, and the
    same steps after; nothing a row asks for out of the plane goes unsaid."""
    rng = np.random.default_rng(5)
    one, batch = PymunkBackend(), PymunkBackend()
    for backend in (one, batch):
        _bodies_for_poses(kit, backend)
        backend.step(1 / 120)
    keys = np.array([4, 7, 9, 12])
    tilt = np.array([math.cos(0.3), math.sin(0.3), 0.0, 0.0])
    for _ in range(3):
        turns = rng.uniform(-3.0, 3.0, 4)
        orientation = np.array([quat_multiply(kit.quat_y(a), tilt if k == 4 else kit.IDENTITY)
                                for a, k in zip(turns, keys, strict=True)])
        position = rng.uniform(-2.0, 2.0, (4, 3))
        linear = rng.uniform(-1.0, 1.0, (4, 3)) * (1.0, 0.0, 1.0)
        angular = rng.uniform(-4.0, 4.0, (4, 3)) * (0.0, 1.0, 0.0)
        for i, key in enumerate(keys.tolist()):
            one.set_pose(key, position[i], orientation[i])
            one.set_velocity(key, linear[i], angular[i])
        batch.write_state(BodyState.from_arrays(keys, position, orientation, linear, angular))
        assert _raw(batch) == _raw(one)
        assert np.array_equal(batch.read_state().table, one.read_state().table)
        for backend in (one, batch):
            backend.step(1 / 120)
        assert _raw(batch) == _raw(one)


def test_write_state_warns_as_one_by_one_and_applies_nothing_of_a_bad_row(kit,
                                                                           caplog) -> None:
    backend = PymunkBackend()
    _bodies_for_poses(kit, backend)
    before = _raw(backend)
    rows = BodyState.from_arrays(np.array([7, 9]), np.array([[0.5, 0, 1], [np.nan, 0, 1]]),
                                 np.tile(kit.IDENTITY, (2, 1)), np.zeros((2, 3)),
                                 np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"body 9: pose \[nan, .*is not finite"):
        backend.write_state(rows)
    assert _raw(backend) == before  # not even the good row before it
    with pytest.raises(KeyError, match=r"no bodies with keys \[33\]"):
        backend.write_state(BodyState.from_arrays(np.array([33]), np.zeros((1, 3)),
                                                  kit.IDENTITY[None], np.zeros((1, 3)),
                                                  np.zeros((1, 3))))
    tilted = np.array([[math.cos(0.2), 0.0, 0.0, math.sin(0.2)]])  # about Z: out of plane
    backend.write_state(BodyState.from_arrays(np.array([7]), np.zeros((1, 3)), tilted,
                                              np.array([[0.0, 1.0, 0.0]]), np.zeros((1, 3))))
    assert "body 7: new orientation tilts differently out of the X–Z plane" in caplog.text
    assert "body 7: velocity out of the X–Z plane; only its in-plane part" in caplog.text


def _same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two labelings group the rows alike (the labels' values aside)."""
    return bool(np.array_equal(a[:, None] == a[None, :], b[:, None] == b[None, :]))


def test_the_sleep_rule_s_islands_from_the_arbiters_are_the_contacts_and_joints_own(kit):
    """The union-find over pymunk's arbiters and the joints (the sleep rule's islands on
    pymunk, in C) groups the rows as the rule's own islands from the contact records and
    joint pairs do: piles apart, a kinematic body tying what it touches, a jointed pair
    apart from the floor, a static body tying nothing."""
    backend = PymunkBackend()
    backend.configure(WorldSettings(auto_sleep=False))
    kit.add(backend, 0, kit.ground_plane(), (0.0, 0.0, 0.0))
    key = 1
    for x in (0.0, 3.0, 6.0):  # three piles of three crates
        for level in range(3):
            kit.add(backend, key, kit.box((0.5, 0.5, 0.5)), (x, 0.0, 0.25 + 0.5 * level))
            key += 1
    kit.add(backend, 20, kit.box((0.5, 0.5, 0.5), kind="kinematic"), (1.5, 0.0, 0.25))
    kit.add(backend, 21, kit.box((0.4, 0.4, 0.4)), (1.1, 0.0, 0.2))  # against the kinematic
    kit.add(backend, 22, kit.sphere(0.2), (10.0, 0.0, 3.0))  # a pendulum pair, in the air
    kit.add(backend, 23, kit.sphere(0.2), (11.0, 0.0, 3.0))
    backend.add_joint(30, kit.hinge(22, (10.0, 0.0, 4.0)))
    backend.add_joint(31, kit.hinge(22, (10.5, 0.0, 3.0), 23))
    for _ in range(30):
        backend.step(0.01)
    rule = backend._rule
    ours = backend._islands()
    edges = np.concatenate([backend._contact_pairs(), backend._joint_pairs])
    theirs = rule._islands(lambda: edges)
    assert _same_partition(ours, theirs)
    rows = {k: int(rule.rows(np.array([k]))[0]) for k in (1, 2, 4, 20, 21, 22, 23)}
    assert ours[rows[1]] == ours[rows[2]] != ours[rows[4]]  # a pile; piles apart
    assert ours[rows[20]] == ours[rows[21]]  # the kinematic ties what it touches
    assert ours[rows[22]] == ours[rows[23]] != ours[rows[1]]


def _batch_arbiters(space: pymunk.Space) -> tuple[np.ndarray, np.ndarray]:
    """The space's cached arbiters as pymunk's public batch API reads them."""
    fields = pymunk.batch.ArbiterFields
    buffer = pymunk.batch.Buffer()
    pymunk.batch.get_space_arbiters(space, fields.BODY_A_ID | fields.BODY_B_ID
                                    | fields.CONTACT_COUNT | fields.TOTAL_IMPULSE
                                    | fields.NORMAL | fields.POINT_A_1 | fields.POINT_B_1
                                    | fields.DISTANCE_1 | fields.POINT_A_2
                                    | fields.POINT_B_2 | fields.DISTANCE_2, buffer)
    return (np.frombuffer(buffer.int_buf(), np.int64).reshape(-1, 3).copy(),
            np.frombuffer(buffer.float_buf(), np.float64).reshape(-1, 14).copy())


def _batch_bodies(space: pymunk.Space) -> dict[int, np.ndarray]:
    """Every body's (x, z, θ, vx, vz, ω) as pymunk's public batch API reads them, by id."""
    fields = pymunk.batch.BodyFields
    buffer = pymunk.batch.Buffer()
    pymunk.batch.get_space_bodies(space, fields.BODY_ID | fields.POSITION | fields.ANGLE
                                  | fields.VELOCITY | fields.ANGULAR_VELOCITY, buffer)
    ids = np.frombuffer(buffer.int_buf(), np.int64)
    rows = np.frombuffer(buffer.float_buf(), np.float64).reshape(-1, 6)
    return {int(i): row.copy() for i, row in zip(ids, rows, strict=True)}


def _swap_arbiters(space: pymunk.Space) -> int:
    """Turn every cached arbiter's ``swapped`` flag over (through pymunk's declaration of
    cpArbiter); how many are swapped now. chipmunk swaps an arbiter whose collision
    handler names the pair's types the other way round; pymunk 7 looks its handlers up by
    the ordered pair, so none is found swapped after a step, yet the getters honour it."""
    found = [0]

    @pymunk.ffi.callback("void(*)(struct cpArbiter *, void *)")
    def turn(arbiter, _data) -> None:  # noqa: ANN001 (cffi pointers)
        arbiter.swapped = not arbiter.swapped
        found[0] += bool(arbiter.swapped)

    pymunk.cp.cpSpaceEachCachedArbiter(space._space, turn, pymunk.ffi.NULL)
    return found[0]


@pytest.mark.parametrize("swap", [False, True], ids=["as-stepped", "swapped"])
def test_the_direct_chipmunk_reads_are_pymunk_batch_s_to_the_bit(kit, swap: bool) -> None:
    """The compiled passes read chipmunk through pymunk's cffi library (_chipmunk.pxi):
    what they read is what pymunk.batch reads, to the bit, arbiter by arbiter in
    chipmunk's order (those without contacts: their ids and count) and body by body,
    asleep or awake. An arbiter's bodies, count, normal and total impulse are read from
    its fields with its getters' arithmetic, swapped arbiters too (the getters turn their
    bodies, normal and impulse round; ``swap``: every arbiter swapped for the reads), and
    in the step's own read its points and depths from the bodies' positions the step's
    body read took (their centres of gravity). A pymunk whose chipmunk reads otherwise
    fails here."""
    backend = PymunkBackend()
    backend.configure(WorldSettings(auto_sleep=True))
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(60):  # boxes and balls falling onto each other; some settle and sleep
        kit.add(backend, i, kit.box((0.4, 0.4, 0.4)) if i % 2 else kit.sphere(0.2),
                (0.5 * (i % 12), 0.0, 0.2 + 0.45 * (i // 12)))
    checked = sleepers = turned = 0
    for step in range(400):
        backend.step(0.01)
        if step % 25:
            continue
        reader = backend._space_reader()
        # the step's own read (its points from the step's body read), then afresh
        ints, floats = reader.arbiters()
        theirs_ints, theirs_floats = _batch_arbiters(backend._space)
        assert np.array_equal(ints, theirs_ints)
        assert np.array_equal(floats[ints[:, 2] > 0], theirs_floats[ints[:, 2] > 0])
        reader.new_step()
        swapped = _swap_arbiters(backend._space) if swap else 0
        turned += swapped
        ints, floats = (a.copy() for a in reader.arbiters())
        theirs_ints, theirs_floats = _batch_arbiters(backend._space)
        if swap:
            assert swapped == len(ints)
            _swap_arbiters(backend._space)
            reader.new_step()
            unswapped = reader.arbiters()[0]
            assert np.array_equal(unswapped[:, :2], theirs_ints[:, 1::-1])
        assert np.array_equal(ints, theirs_ints)
        touching = ints[:, 2] > 0
        assert np.array_equal(floats[touching], theirs_floats[touching])
        raw, awake = reader.read()
        theirs = _batch_bodies(backend._space)
        for row, rec in enumerate(backend._records):
            assert np.array_equal(raw[row], theirs[rec.body.id]), rec.key
            assert awake[row] == (not rec.body.is_sleeping
                                  and rec.body.body_type != pymunk.Body.STATIC)
        checked += int(touching.sum())
        sleepers += reader.sleepers
    assert checked > 150 and sleepers > 0 and (turned > 150) == swap


_DECLARED = """
struct cpVect { double x, y; };
struct cpBody;
enum cpArbiterState { CP_ARBITER_STATE_FIRST_COLLISION, CP_ARBITER_STATE_NORMAL,
    CP_ARBITER_STATE_IGNORE, CP_ARBITER_STATE_CACHED, CP_ARBITER_STATE_INVALIDATED };
struct cpContact { struct cpVect r1, r2; double nMass, tMass, bounce, jnAcc, jtAcc; };
struct cpArbiter { struct cpBody *body_a, *body_b; %s; struct cpContact *contacts;
    struct cpVect n; unsigned char swapped; enum cpArbiterState state; };
"""


@pytest.mark.parametrize(("count", "message"), [
    ("int count", None),
    ("int counted", "declares no struct cpArbiter field count"),
    ("short count", "declares struct cpArbiter's count as short, not int")])
def test_the_arbiter_layout_is_pymunk_s_declaration_checked_by_name(count: str,
                                                                    message: str | None):
    """The fields the passes read are taken from pymunk's cffi declaration at import:
    their offsets as declared, and a pymunk that lacks one, or declares it otherwise,
    fails by name (here a declaration of our own stands in for pymunk's)."""
    import cffi

    from engine.physics.pymunk2d import _rows

    ffi = cffi.FFI()
    ffi.cdef(_DECLARED % count)
    if message is None:
        layout = _rows.chipmunk_layout(ffi)
        assert layout["struct cpArbiter.count"] == 16
        assert layout["struct cpContact.jtAcc"] == 64 and layout["contact"] == 72
        assert layout["cached"] == 3
        assert _rows.chipmunk_layout(pymunk.ffi)["struct cpArbiter.swapped"] == \
            pymunk.ffi.offsetof("struct cpArbiter", "swapped")
    else:
        with pytest.raises(ImportError, match=message):
            _rows.chipmunk_layout(ffi)


def test_the_probe_finds_where_a_cpbody_keeps_its_velocity_force_and_spin() -> None:
    """The passes write an awake body's velocity, force and spin at the offsets a probe
    of a throwaway body found at import (pymunk does not declare cpBody's fields): with
    the pymunk we pin it finds all three, apart; where it finds no single answer (here a
    window too short to hold any of them) each is -1, and the setters are used."""
    from engine.physics.pymunk2d import _rows

    found = _rows.probe_body()
    assert found == _rows.BODY_FIELDS
    assert all(at >= 0 and at % 8 == 0 for at in found.values()), found
    spans = sorted((at, at + (8 if name == "w" else 16)) for name, at in found.items())
    assert all(a[1] <= b[0] for a, b in zip(spans, spans[1:], strict=False)), found
    assert _rows.probe_body(min(found.values())) == {"v": -1, "f": -1, "w": -1}


def _resting_run(kit) -> tuple[list[bytes], int, int, int]:
    """Three columns of boxes dropped and settling with sleeping on, 5 s at 1/60 s:
    each step's state read and contacts; how many steps preloaded rows, held rows still,
    and how many bodies sleep at the end."""
    backend = PymunkBackend()
    backend.configure(WorldSettings(auto_sleep=True))
    kit.add(backend, kit.GROUND, kit.ground_plane(), (0.0, 0.0, 0.0))
    for i in range(30):
        kit.add(backend, i, kit.box((1.0, 1.0, 1.0)), (1.2 * (i // 10), 0.0, 0.55 + 1.1 * (i % 10)))
    table = np.empty((31, 13))
    reads, preloaded, held = [], 0, 0
    for _ in range(300):
        backend.step(1 / 60)
        keys = backend.read_state_into(table)
        reads.append(keys.tobytes() + table.tobytes() + backend.contacts().tobytes())
        preloaded += backend._resting.on
        held += backend._resting.held_still > 0
    return reads, preloaded, held, sum(backend.is_sleeping(i) for i in range(30))


def _timers(monkeypatch: pytest.MonkeyPatch) -> list[float]:
    """chipmunk's sleep timer as each space step from now on starts, as they come."""
    seen: list[float] = []
    step = pymunk.Space.step

    def counted(space: pymunk.Space, dt: float) -> None:
        seen.append(space.sleep_time_threshold)
        step(space, dt)

    monkeypatch.setattr(pymunk.Space, "step", counted)
    return seen


def test_the_velocities_and_forces_written_straight_are_the_setters_to_the_bit(
        kit, monkeypatch: pytest.MonkeyPatch) -> None:
    """An awake body's velocity, spin and force are written without chipmunk's
    cpBodyActivate where no idle time can decide anything (the backend's timers, NEVER
    and QUIET): the same run with a timer just low enough for the passes to use the
    setters (one no idle time reaches either) at every step is the same to the bit,
    preloading and holding rows still, and with bodies asleep at the end."""
    from engine.physics.pymunk2d import _rows
    from engine.physics.pymunk2d import backend as module

    assert min(module.NEVER, module.QUIET) >= _rows.IDLE_UNREACHED  # straight writes
    direct, preloaded, held, asleep = _resting_run(kit)
    low = _rows.IDLE_UNREACHED / 10
    monkeypatch.setattr(module, "NEVER", low)
    monkeypatch.setattr(module, "QUIET", low)
    timers = _timers(monkeypatch)
    setters, *counts = _resting_run(kit)
    assert set(timers) == {low}
    assert preloaded > 0 and held > 0 and asleep > 0, (preloaded, held, asleep)
    assert counts == [preloaded, held, asleep]
    assert [i for i, (a, b) in enumerate(zip(direct, setters, strict=True)) if a != b] == []


def test_a_step_with_no_body_asleep_leaves_chipmunk_s_sleeping_off_to_the_same_bit(
        kit, monkeypatch: pytest.MonkeyPatch) -> None:
    """While no body sleeps a step is taken with chipmunk's sleep timer off (QUIET: it
    skips its islands, which decide nothing then), NEVER again after it: the same run
    with the timer left at NEVER every step is the same to the bit, bodies asleep at the
    end, and the timer is off from the second step (the first one's read is the first)
    until it is needed."""
    from engine.physics.pymunk2d import backend as module

    seen = _timers(monkeypatch)
    quiet, *counts = _resting_run(kit)
    timers, seen[:] = list(seen), []
    monkeypatch.setattr(module, "QUIET", module.NEVER)
    never, *again = _resting_run(kit)
    assert counts == again and counts[2] > 0, (counts, again)
    assert set(seen) == {module.NEVER}
    off = timers.index(module.NEVER, 1)  # the first step's read comes after it
    assert timers[0] == module.NEVER and set(timers[1:off]) == {math.inf}, timers[:off + 1]
    assert [i for i, (a, b) in enumerate(zip(quiet, never, strict=True)) if a != b] == []
