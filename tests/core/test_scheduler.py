"""Phase order, systems and plugins, engine isolation, clean shutdown."""

from __future__ import annotations

import pytest

from components import Name, Physical, Transform
from engine import Engine, EngineConfig, Phase, System, system
from engine.events import CustomEvent, Spawned
from engine.system import SystemFailure
from systems import create_engine


def make_engine(**kw) -> Engine:
    return create_engine(EngineConfig(backend="ballistic", fast=True, **kw))


def test_phases_run_in_order_every_frame():
    order: list[tuple[int, str]] = []
    with make_engine() as eng:
        # registered out of order on purpose
        for phase in (Phase.RENDER, Phase.INPUT, Phase.POST_PHYSICS, Phase.SCRIPT, Phase.FIXED):
            eng.add_system(system(phase)(lambda e, dt, p=phase: order.append((e.frame, p.name))))
        eng.run(frames=2)
    names = [p for _, p in order]
    per_frame = ["INPUT", "SCRIPT", "FIXED", "POST_PHYSICS", "RENDER"]
    assert names == per_frame * 2
    assert [f for f, _ in order] == [0] * 5 + [1] * 5


def test_dynamics_runs_in_fixed_between_script_and_post_physics():
    seen = {}
    with make_engine() as eng:
        ball = eng.spawn(Transform(position=(0, 0, 10)), Physical())

        @system(Phase.SCRIPT, reads=(Transform,))
        def before(e, dt):
            seen.setdefault("script", e.world.component_for_entity(ball, Transform).position[2])

        @system(Phase.POST_PHYSICS, reads=(Transform,))
        def after(e, dt):
            seen.setdefault("post", e.world.component_for_entity(ball, Transform).position[2])

        eng.add_system(before)
        eng.add_system(after)
        eng.step()
    assert seen["script"] == 10.0
    assert seen["post"] < 10.0


def test_system_declares_phase_reads_and_writes():
    class Mover(System):
        phase = Phase.SCRIPT
        reads = (Name,)
        writes = (Transform,)

        def run(self, engine, dt):
            for _, (t,) in engine.world.get_components(Transform):
                t.position[0] += 1.0

    mover = Mover()
    assert (mover.phase, mover.reads, mover.writes, mover.name) == (
        Phase.SCRIPT, (Name,), (Transform,), "Mover")
    with make_engine() as eng:
        e = eng.spawn(Transform())
        eng.add_system(mover)
        eng.run(frames=3)
        assert eng.world.component_for_entity(e, Transform).position[0] == 3.0


def test_plugins_build_once_and_load_by_name():
    built = []

    class Counter:
        name = "counter"

        def build(self, engine):
            built.append(engine)

    with make_engine() as eng:
        eng.register_plugin("counter", Counter, aliases=("tally",))
        eng.request_plugin("tally")
        eng.request_plugin("counter")
        assert built == [eng]
        with pytest.raises(KeyError, match="unknown plugin 'nope'"):
            eng.request_plugin("nope")
        assert "physics" in eng.plugins


def test_events_are_delivered_between_phases_in_order():
    got = []
    with make_engine() as eng:
        eng.events.subscribe(CustomEvent, lambda ev: got.append((ev.name, eng.frame)))
        eng.events.subscribe(Spawned, lambda ev: got.append(("spawned", ev.entity)))

        @system(Phase.INPUT)
        def fire(e, dt):
            e.events.emit(CustomEvent("a"))
            e.events.emit(CustomEvent("b"))

        @system(Phase.SCRIPT)
        def check(e, dt):
            # delivered at the end of INPUT, visible to every later phase this frame
            assert [ev.name for ev in e.events.frame(CustomEvent)] == ["a", "b"]

        eng.add_system(fire)
        eng.add_system(check)
        entity = eng.spawn(Name("x"))
        eng.step()
    assert got == [("spawned", entity), ("a", 0), ("b", 0)]


def test_two_engines_in_one_process_are_isolated():
    with make_engine() as a, make_engine() as b:
        ea = a.spawn(Name("only-in-a"), Transform(position=(1, 2, 3)))
        b.spawn(Name("only-in-b"))
        b.spawn(Name("also-b"))
        assert [n.id for _, n in a.world.get_component(Name)] == ["only-in-a"]
        assert sorted(n.id for _, n in b.world.get_component(Name)) == ["also-b", "only-in-b"]
        a.despawn(ea)
        a.step()
        assert a.world.get_component(Name) == []
        assert len(b.world) == 2


def test_despawn_is_deferred_to_the_phase_boundary():
    with make_engine() as eng:
        e = eng.spawn(Name("x"), Transform(), Physical())
        eng.step()
        assert eng.physics.snapshot.bodies.keys.tolist() == [e]

        @system(Phase.SCRIPT)
        def kill(en, dt):
            if en.frame == 1:
                en.despawn(e)
                assert en.world.entity_exists(e)  # still there until the phase ends

        eng.add_system(kill)
        eng.step()
        assert not eng.world.entity_exists(e)
        eng.step()
        assert eng.physics.snapshot.bodies.keys.tolist() == []


@pytest.mark.parametrize("mode", ["serial", "threaded"])
def test_a_system_that_raises_is_named_and_physics_stops(mode):
    eng = make_engine(mode=mode)
    eng.spawn(Transform(), Physical())

    @system(Phase.POST_PHYSICS)
    def broken(e, dt):
        if e.frame == 5:
            raise ValueError("boom")

    eng.add_system(broken)
    with pytest.raises(SystemFailure, match="broken.*ValueError: boom") as info:
        eng.run(frames=50)
    assert info.value.system_name.endswith("broken")
    eng.close()
    assert not eng.physics.running
    assert eng.physics.closed


def test_transforms_are_views_into_the_pose_table_and_survive_growth():
    with make_engine() as eng:
        entities = [eng.spawn(Transform(position=(i, 0, 0))) for i in range(300)]
        poses = eng.world.poses
        assert poses.capacity >= 300
        t = eng.world.component_for_entity(entities[7], Transform)
        poses.position[poses.row_of[entities[7]]] = (9, 9, 9)
        assert t.position.tolist() == [9, 9, 9]
        assert eng.world.component_for_entity(entities[299], Transform).position[0] == 299
        eng.world.delete_entity(entities[7])
        assert t.position.tolist() == [9, 9, 9]  # detached copy keeps its values


def test_request_quit_ends_the_run_after_the_frame():
    with make_engine() as eng:
        eng.add_system(system(Phase.RENDER)(lambda e, dt: e.frame == 6 and e.request_quit()))
        eng.run(frames=100)
        assert eng.frame == 7


def test_bodies_without_a_transform_simulate_and_the_others_still_sync():
    with make_engine() as eng:
        bare = eng.spawn(Physical())  # no Transform: starts at the origin, nothing to sync
        ball = eng.spawn(Transform(position=(0, 0, 10)), Physical())
        eng.run(frames=30)
        assert sorted(eng.physics.snapshot.bodies.keys.tolist()) == sorted([bare, ball])
        assert eng.world.component_for_entity(ball, Transform).position[2] < 10.0


def test_debug_mode_stops_a_system_that_touches_what_it_does_not_declare():
    @system(Phase.SCRIPT, reads=(Name,))
    def sneaky(e, dt):
        for _, (t,) in e.world.get_components(Transform):
            t.position[2] += 1.0
        e.spawn(Physical())

    for debug in (True, False):
        with make_engine(debug=debug) as eng:
            eng.spawn(Transform())
            eng.add_system(sneaky)
            if debug:
                with pytest.raises(SystemFailure, match=r"sneaky touched Physical, Transform "
                                   r"without declaring it \(it declares reads: Name; "
                                   r"writes: nothing\)"):
                    eng.step()
            else:
                eng.step()  # the check costs nothing when it is off


def test_debug_mode_stops_a_system_that_changes_a_transform_it_declares_only_reading():
    @system(Phase.SCRIPT, reads=(Transform,))
    def nudge(e, dt):
        if e.frame == 2:
            for _, t in e.world.get_component(Transform):
                t.orientation[0] = float("nan")  # in place: no add, no remove, no query of it

    @system(Phase.SCRIPT, reads=(Transform,), writes=(Transform,))
    def honest(e, dt):
        for _, t in e.world.get_component(Transform):
            t.position[0] += 1.0

    with make_engine(debug=True) as eng:
        eng.spawn(Transform())
        eng.add_system(honest)
        eng.add_system(nudge)
        eng.run(frames=2)  # reading alone, and a declared write, pass
        with pytest.raises(SystemFailure, match=r"nudge touched Transform without declaring "
                           r"it \(it declares reads: Transform; writes: nothing\)"):
            eng.step()
