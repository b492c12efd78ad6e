"""Factory: a representative file becomes the right components; entities; snippets."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from components import (
    Camera,
    Controller,
    Hand,
    HandState,
    Joint,
    Light,
    Name,
    Physical,
    Script,
    Sound,
    Transform,
    Visual,
)
from engine.app import EngineConfig
from engine.scene import (
    SceneError,
    SceneIds,
    build_specs,
    instantiate,
    load_scene,
    load_spec,
    spec_from_text,
    write_state,
)
from systems import create_engine

DATA = Path(__file__).parent / "data"
CONTENT = Path(__file__).parents[2] / "content" / "demo"
REP = DATA / "representative"


def comps(spec, oid):
    (es,) = [e for e in spec.entities if e.id == oid]
    return {type(c): c for c in es.components}


@pytest.fixture(scope="module")
def rep():
    return load_spec(REP, np.random.default_rng(0))


def test_objects_get_the_components_they_declare(rep):
    # objects first, in the file's order (a saved state matches them to its blocks); the
    # top-level entities after them, in no order of note
    made = [e.id for e in rep.entities]
    assert made[:5] == ["ground", "crate", "door", "wheel", "right hand"]
    assert sorted(made[5:]) == ["eye", "light0", "push"]
    assert set(comps(rep, "door")) == {Name, Transform, Physical, Script}
    assert set(comps(rep, "wheel")) == {Name, Transform, Visual}
    assert set(comps(rep, "right hand")) == {Name, Transform, Visual, Physical, Hand, HandState}
    assert set(comps(rep, "crate")) == {Name, Transform, Visual, Physical, Sound}


def test_transform_units_and_orientation(rep):
    t = comps(rep, "crate")[Transform]
    np.testing.assert_allclose(t.position, (1, 2, 0.5))
    h = math.sqrt(0.5)
    np.testing.assert_allclose(t.orientation, (h, 0, 0, h), atol=1e-15)  # 90 deg about Z


def test_primitives_sizes_and_materials(rep):
    ground = comps(rep, "ground")
    assert ground[Physical].kind == "static"
    assert ground[Physical].shapes[0].kind == "plane"
    assert ground[Physical].shapes[0].size == (0.0, 0.0, 1.0, 0.0)
    assert ground[Visual].color == (0.3, 0.5, 0.3, 1.0)
    door = comps(rep, "door")[Physical]
    assert (door.mass, door.shapes[0].kind, door.shapes[0].size) == (4.0, "box", (1, 0.05, 2))
    assert (door.material.name, door.material.friction) == ("3", 0.2)
    wheel = comps(rep, "wheel")
    assert (wheel[Visual].shapes[0].kind, wheel[Visual].shapes[0].size) == ("cylinder",
                                                                          (0.3, 0.1))
    hand = comps(rep, "right hand")
    assert (hand[Hand].tracker, hand[Hand].glove, hand[Hand].max_force) == ("hand_r", "glove_r",
                                                                            100.0)
    # a hand without a body of its own gets a palm-sized box of 0.45 kg that floats
    body = hand[Physical]
    assert (body.mass, body.gravity, body.can_sleep) == (0.45, False, False)
    assert (body.shapes[0].kind, body.shapes[0].size) == ("box", (0.09, 0.18, 0.03))


def test_model_derived_physics_shape(rep):
    crate = comps(rep, "crate")
    assert crate[Visual].model == "models/cube.obj" and crate[Visual].scale == (.25, .25, .25)
    phys = crate[Physical]
    hull = phys.shapes[0]
    assert hull.kind == "hull" and len(hull.vertices) == 8
    np.testing.assert_allclose(np.abs(hull.vertices), 0.25)
    assert phys.mass is None and phys.material.density == 700.0  # mass from density
    assert crate[Sound].file == "sounds/knock.wav" and crate[Sound].gain == 0.5


def test_joints_world_cameras_lights_controllers(rep):
    (js,) = rep.joints
    j = js.joint
    assert js.bodies == ("door", None) and j.kind == "motorized_hinge"
    assert (j.low, j.high) == pytest.approx((-math.pi / 2, math.pi / 2))
    assert j.motor_velocity == pytest.approx(math.radians(45)) and j.motor_max_force == 10
    assert rep.world.iterations == 30 and rep.time_step == 0.005 and rep.backend == "ode"
    (pair,) = rep.world.material_pairs
    assert (pair.a, pair.b, pair.friction) == ("wood", "3", 0.05)
    assert comps(rep, "eye")[Camera].fov == 70
    follows = [(k.entity, k.field, k.target) for k in rep.links if k.component is Camera]
    assert follows == [("eye", "follow", "crate")]
    assert comps(rep, "light0")[Light].kind == "point"
    assert comps(rep, "push")[Controller].target == "motor:hinge"


def test_listing1_sphere_size_is_a_diameter():
    spec = build_specs(load_scene(DATA / "listing1.scene", np.random.default_rng(2)))
    es = spec.entities[0]
    size = load_scene(DATA / "listing1.scene", np.random.default_rng(2)).find("Object/Size")
    phys = {type(c): c for c in es.components}[Physical]
    assert phys.shapes[0].size == (size.data[0].data / 2,) and phys.mass == 1.1
    assert phys.material.name == "2"


@pytest.mark.parametrize(("method", "kind", "size"), [
    ("TriangleMesh", "mesh", ()), ("Box", "box", (1.0, 1.0, 1.0)),
    ("Sphere", "sphere", (math.sqrt(3) / 2,)),
])
def test_parse_methods(method, kind, size):
    spec = spec_from_text(
        'Object { VisualAttributes { Geometry { File "models/cube.obj" Scale [0.5 0.5 0.5] } }'
        f' PhysicalAttributes {{ Geometry {{ ParseMethod "{method}" }} }} }}', REP)
    shape = {type(c): c for c in spec.entities[0].components}[Physical].shapes[0]
    assert shape.kind == kind and shape.size == pytest.approx(size)
    if kind == "mesh":
        assert shape.vertices.shape == (8, 3) and shape.faces.shape == (12, 3)


def test_an_unreadable_model_is_told_at_its_file_and_its_object_left_out(tmp_path):
    (tmp_path / "bad.obj").write_text("this is not a model\n")
    spec = spec_from_text('Object {\n  PhysicalAttributes { Geometry { File "bad.obj" } }\n}\n'
                          'Object { ID "fine" }\n', tmp_path)
    (err,) = spec.problems
    assert (err.line, err.col) == (2, 40) and err.is_error
    assert err.message == (f'cannot load model "bad.obj" ({tmp_path / "bad.obj"}): the file '
                           f"holds no triangles; object 'object0' is left out")
    assert [(es.id, es.skipped, es.components) for es in spec.entities[:1]] == [
        ("object0", True, [])]
    assert not spec.entities[1].skipped


def test_defaults_make_a_short_file_work():
    spec = spec_from_text("Object { Position [0 0 5] }", DATA)
    c = {type(c): c for c in spec.entities[0].components}
    assert c[Physical].kind == "dynamic" and c[Physical].mass == 1.0
    assert c[Physical].shapes[0].kind == "box" and c[Visual].shapes[0].kind == "box"
    assert spec.world.gravity == (0.0, 0.0, -9.81)


def engine_for(spec):
    cfg = EngineConfig(backend="ode", dt=spec.time_step, fast=True, world=spec.world)
    return create_engine(cfg)


def test_instantiate_creates_entities_and_resolves_ids(rep):
    spec = load_spec(REP, np.random.default_rng(0))
    with engine_for(spec) as engine:
        ids = instantiate(engine, spec)
        world = engine.world
        assert world.component_for_entity(ids["crate"], Name).id == "crate"
        joint_entity = engine.resource(SceneIds).joints["hinge"]
        joint = world.component_for_entity(joint_entity, Joint)
        assert joint.body_a == ids["door"] and joint.body_b is None
        assert world.component_for_entity(ids["eye"], Camera).follow == ids["crate"]
        engine.run(frames=3)
        assert world.component_for_entity(ids["crate"], Transform).position[2] < 0.5


def test_a_file_with_errors_creates_nothing(tmp_path):
    (tmp_path / "main.scene").write_text('Object { ID "a" }\nObject { ID "b" Mass 3 }\n')
    with engine_for(spec_from_text("", tmp_path)) as engine:
        with pytest.raises(SceneError):
            instantiate(engine, load_spec(tmp_path))
        assert len(engine.world.get_component(Name)) == 0


def test_runtime_snippets_spawn_without_replacing_the_scene(tmp_path):
    spec = load_spec(REP, np.random.default_rng(0))
    with engine_for(spec) as engine:
        instantiate(engine, spec)
        extra = spec_from_text('Object { ID "dropped" Position [0 0 3] }', REP)
        ids = instantiate(engine, extra, as_scene=False)
        assert engine.resource(SceneIds).spec is spec
        assert engine.world.component_for_entity(ids["dropped"], Name).id == "dropped"


def test_a_snippet_spawned_again_may_declare_its_ids_again(tmp_path):
    """A script spawning the same snippet twice: its object and material IDs are its own."""
    snippet = ('Material { ID "wood" Friction 0.3 }\n'
               'Object { ID "plank" Position [0 0 1] PhysicalAttributes { Material "wood" } }')
    spec = load_spec(REP, np.random.default_rng(0))
    with engine_for(spec) as engine:
        instantiate(engine, spec)
        scene = engine.resource(SceneIds).spec
        for _ in range(2):
            extra = spec_from_text(snippet, REP, scene=scene, bodies={"plank": ((0, 0, 1),
                                                                              (1, 0, 0, 0))})
            instantiate(engine, extra, as_scene=False)
            assert comps(extra, "plank")[Physical].material.friction == 0.3


def test_snippets_include_relative_to_the_content_folder():
    spec = spec_from_text('Include "../include/materials.scene"\n'
                          'Object { ID "b" Position [0 0 height] '
                          'PhysicalAttributes { Material "rubber" } }', REP,
                          allow=[REP.parent / "include"])  # outside the folder: allowed
    c = comps(spec, "b")
    assert c[Transform].position[2] == 2.5 and c[Physical].material.bounce == 0.7


def test_saved_state_elsewhere_still_finds_its_assets(tmp_path):
    spec = load_spec(REP, np.random.default_rng(0))
    out = tmp_path / "saves" / "state.scene"
    out.parent.mkdir()
    with engine_for(spec) as engine:
        instantiate(engine, spec)
        engine.run(frames=5)
        out.write_text(write_state(engine, out))
    again = load_spec(out)  # raises if a model, sound or script is not found
    assert [e.id for e in again.entities] == [e.id for e in spec.entities]
    assert comps(again, "crate")[Physical].shapes[0].kind == "hull"


def test_a_scene_sound_is_placed_only_when_it_has_a_position(tmp_path):
    shutil.copy(CONTENT / "sounds" / "knock.wav", tmp_path / "hum.wav")
    spec = spec_from_text('Sound { ID "music" File "hum.wav" Loop 1 }\n'
                          'Sound { ID "tap" File "hum.wav" Position [1 2 3] }\n', tmp_path)
    kinds = {es.id: {type(c) for c in es.components} for es in spec.entities}
    assert Transform not in kinds["music"] and Sound in kinds["music"]
    assert Transform in kinds["tap"]


def test_mass_frame_keys_become_the_bodys_centre_and_principal_axes():
    spec = spec_from_text('''Object { ID "door" PhysicalAttributes { Mass 4
  CenterOfMass [0.3 0 -0.1] Inertia [0.5 0.4 0.2] InertiaOrientation [0 0 90]
  Geometry { Primitive "box" Size [1 0.1 2] } } }
Object { ID "plain" PhysicalAttributes { Mass 1 } }''', DATA)
    door, plain = (next(c for c in es.components if isinstance(c, Physical))
                   for es in spec.entities)
    assert door.center_of_mass == (0.3, 0.0, -0.1) and door.inertia == (0.5, 0.4, 0.2)
    np.testing.assert_allclose(door.inertia_rotation,
                               (math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)))
    assert plain.center_of_mass is None and plain.inertia is None


@pytest.mark.parametrize("keys, message", [
    ("Inertia [0.5 -1 0.2]", "Inertia must be moments of kg*m^2, 0 or more (0: infinite), "
                             "got -1"),
    ("CenterOfMass [0 0 1e9]", "CenterOfMass z = 1e+09 is outside the world"),
])
def test_a_mass_frame_no_body_can_have_is_told_at_its_number(keys, message):
    with pytest.raises(SceneError, match=re.escape(message)) as caught:
        spec_from_text(f'Object {{ ID "b" PhysicalAttributes {{ {keys} }} }}', DATA)
    assert caught.value.diagnostics[0].line == 1


def test_inertia_axes_without_moments_are_told_as_doing_nothing():
    spec = spec_from_text('Object { ID "b" PhysicalAttributes { InertiaOrientation [0 0 10] '
                          '} }', DATA)
    (told,) = spec.problems
    assert (told.severity, told.line) == ("warning", 1)
    assert "without Inertia it does nothing" in told.message


def test_a_joint_spring_is_in_si_units_on_the_joint():
    spec = spec_from_text('''Object { ID "lid" PhysicalAttributes { Mass 1 } }
Object { ID "cart" Position [2 0 0] PhysicalAttributes { Mass 1 } }
Joint { Type "Hinge" Bodies ["lid"] Axis [0 1 0]
  Spring { Stiffness 0.5 Damping 0.01 Target 30 } }
Joint { Type "Slider" Bodies ["cart"] Axis [1 0 0] Spring { Stiffness 20 MaxForce 4 } }''', DATA)
    hinge, rail = (js.joint.spring for js in spec.joints)
    per_radian = 180 / math.pi
    assert (hinge.stiffness, hinge.damping, hinge.target, hinge.max_force) == pytest.approx(
        (0.5 * per_radian, 0.01 * per_radian, math.radians(30), math.inf))
    assert (rail.stiffness, rail.damping, rail.target, rail.max_force) == (20, 0, 0, 4)


@pytest.mark.parametrize("joint, message", [
    ('Type "Ball" Spring { Stiffness 1 }', "a Ball joint takes no Spring"),
    ('Type "Hinge" Spring { Stiffness -1 }', "Spring Stiffness must be 0 or more, got -1"),
    ('Type "Hinge" Spring { Target 10 }', "a Spring needs a Stiffness or a Damping above 0"),
    ('Type "Slider" Spring { Damping 1 MaxForce 0 }', "Spring MaxForce must be above 0"),
])
def test_a_spring_that_cannot_act_is_told_at_its_block(joint, message):
    with pytest.raises(SceneError, match=message) as caught:
        spec_from_text(f'Object {{ ID "b" PhysicalAttributes {{ Mass 1 }} }}\n'
                       f'Joint {{ Bodies ["b"] {joint} }}', DATA)
    assert caught.value.diagnostics[0].line == 2
