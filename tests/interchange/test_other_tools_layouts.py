"""Files laid out as other tools write them, written by app/bench/interchange_samples.py (no
file another tool wrote is shipped): OMI physics as Godot 4.4 exports it, Collada physics
as Blender 2.42's exporter, ColladaMaya and Bullet's ColladaConverter write it. The scene
has what each file declares, counted from the file, and the bodies move as it means."""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest

from app.bench import interchange_samples as samples_
from components import Joint, Physical, Trigger
from engine.assets import Assets
from engine.assets.gltf import GltfDocument
from engine.interchange import import_model
from engine.rotation import quat_to_matrix
from engine.scene import load_spec
from tests.interchange.helpers import Run, import_scene

pytest.importorskip("engine.physics.ode3d")

BODY, JOINT = samples_.OMI_BODY, samples_.OMI_JOINT


def built(scene: Path) -> dict[str, int]:
    """What an imported scene holds: bodies that move, static bodies, their shapes,
    triggers and joints."""
    spec = load_spec(scene)
    comps = [{type(c): c for c in es.components} for es in spec.entities]
    solid = [c[Physical] for c in comps if Physical in c and Trigger not in c]
    return {"moving": sum(p.kind != "static" for p in solid),
            "static": sum(p.kind == "static" for p in solid),
            "shapes": sum(len(p.shapes) for p in solid),
            "triggers": sum(Trigger in c for c in comps),
            "joints": len(spec.joints)}


def omi_declared(path: Path) -> dict[str, int]:
    """What an OMI file declares, counted from its JSON: bodies with a dynamic or
    kinematic motion, static bodies (a static motion, or a collider with no motion above
    it), colliders, triggers (those not part of a compound one: listed in its ``nodes``,
    or under a trigger that gives neither a shape nor nodes) and joints."""
    doc = GltfDocument.read(path)
    ext = [n.get("extensions", {}) for n in doc.nodes]
    body = [e.get(BODY, {}) for e in ext]

    def above(i: int) -> list[int]:
        out, p = [], int(doc.parents[i])
        while p >= 0:
            out.append(p)
            p = int(doc.parents[p])
        return out

    motion = [b["motion"].get("type") if "motion" in b else None for b in body]
    parts = {n for b in body for n in b.get("trigger", {}).get("nodes", [])}
    parts |= {i for i in range(len(body)) if any(
        "trigger" in body[p] and not {"shape", "nodes"} & set(body[p]["trigger"])
        for p in above(i))}
    return {
        "moving": sum(m in ("dynamic", "kinematic") for m in motion),
        "static": sum(m == "static" or ("collider" in b and m is None and all(
            motion[p] is None for p in above(i))) for i, (m, b) in enumerate(
            zip(motion, body, strict=True))),
        "shapes": sum("collider" in b for b in body),
        "triggers": sum("trigger" in b and i not in parts for i, b in enumerate(body)),
        "joints": sum(JOINT in e for e in ext),
    }


@pytest.fixture
def godot(tmp_path: Path) -> Path:
    return samples_.godot_omi(tmp_path / "godot_omi.gltf")


def test_godots_omi_file_gives_what_it_declares(godot):
    """Godot's single-root marker is nothing to read, so nothing is told about it."""
    imported = import_model(godot.name, godot.name, Assets(godot.parent))
    assert [str(d) for d in imported.problems] == []
    counts = omi_declared(godot)
    assert counts["triggers"] == 4 and counts["joints"] == 1  # the layouts are there
    assert built(import_scene(godot)) == counts


def test_godots_capsules_of_one_radius_have_it(godot):
    """{radius, height} with the height over the caps (OMI before September 2024): a 0.5 m
    capsule of radius 0.05 is 0.1 across and 0.4 between its caps (it was the default
    radius, 1 m across)."""
    spec = load_spec(import_scene(godot))
    bodies = {es.id: c for es in spec.entities for c in es.components
              if isinstance(c, Physical)}
    for oid in ("LinkA", "LinkB"):
        (capsule,) = bodies[oid].shapes
        assert capsule.kind == "capsule"
        np.testing.assert_allclose(capsule.size, (samples_.LINK_RADIUS, samples_.LINK_HEIGHT
                                                  - 2 * samples_.LINK_RADIUS), atol=1e-6)


def test_godots_weld_holds_the_links_as_they_fall_onto_the_floor(godot):
    """One limit naming linear and angular axes at once welds (it was a ball joint): the
    second link keeps its place in the first's frame, and the pair comes to rest on the
    floor (top at 0) on the links' round ends, one radius up."""
    spec = load_spec(import_scene(godot))
    (joint,) = [js.joint for js in spec.joints]
    assert isinstance(joint, Joint) and joint.kind == "fixed"
    with Run.start(godot.with_suffix(".scene")) as run:
        def b_in_a() -> np.ndarray:
            turn = quat_to_matrix(run.transform("LinkA").orientation)
            return turn.T @ (run.position("LinkB") - run.position("LinkA"))

        start = b_in_a()
        run.step(2.0)
        np.testing.assert_allclose(b_in_a(), start, atol=2e-3)
        ends = []
        for oid in ("LinkA", "LinkB"):
            axis = quat_to_matrix(run.transform(oid).orientation)[:, 0]
            reach = (samples_.LINK_HEIGHT / 2 - samples_.LINK_RADIUS) * axis
            ends += [run.position(oid) + reach, run.position(oid) - reach]
            assert np.linalg.norm(run.velocity(oid)) < 0.05, oid  # at rest
        assert min(e[2] for e in ends) == pytest.approx(samples_.LINK_RADIUS, abs=0.01)


def collada_declared(path: Path) -> dict[str, int]:
    """What a Collada file's physics scenes instantiate, counted from its XML: rigid
    bodies that move or not (an instance's <dynamic> wins over its body's), their
    <shape>s, and rigid constraints. An instance finds its body by sid, else by name, else
    (naming none) as its model's only one."""
    root = ElementTree.parse(path).getroot()
    ns = root.tag[:root.tag.index("}") + 1]
    models = {m.get("id"): m for m in root.iter(f"{ns}physics_model")}
    counts = dict.fromkeys(("moving", "static", "shapes", "joints"), 0)
    for instance in root.iter(f"{ns}instance_physics_model"):
        bodies = list(models[(instance.get("url") or "").lstrip("#")].iter(f"{ns}rigid_body"))
        for ibody in instance.iter(f"{ns}instance_rigid_body"):
            name = ibody.get("body")
            if name:
                (body,) = [b for b in bodies if name in (b.get("sid"), b.get("name"))]
            else:
                (body,) = bodies
            flags = [el.text.strip() for el in (*ibody.iter(f"{ns}dynamic"),
                                                *body.iter(f"{ns}dynamic"))]
            counts["static" if flags[:1] == ["false"] else "moving"] += 1
            counts["shapes"] += len(body.findall(f"{ns}technique_common/{ns}shape"))
        counts["joints"] += len(instance.findall(f"{ns}instance_rigid_constraint"))
    return counts


LAYOUTS = {"blender": (samples_.blender_collada, samples_.BLENDER_COLLADA_REST),
           "maya": (samples_.maya_collada, samples_.MAYA_REST),
           "bullet": (samples_.bullet_collada, samples_.BULLET_REST)}


@pytest.mark.parametrize("layout", LAYOUTS)
def test_collada_as_other_tools_write_it_gives_what_it_declares(tmp_path, layout):
    """Blender 2.42 (bodies named, no sid; instances naming no body; <half_extends>: every
    body was left out), ColladaMaya, and Bullet (constraints of one attachment, all of
    one sid: both were left out)."""
    path = LAYOUTS[layout][0](tmp_path / f"{layout}.dae")
    imported = import_model(path.name, path.name, Assets(tmp_path))
    assert [str(d) for d in imported.problems if d.is_error] == []
    counts = built(import_scene(path))
    assert {k: counts[k] for k in ("moving", "static", "shapes", "joints")} == \
        collada_declared(path)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_collada_bodies_land_on_their_floor(tmp_path, layout):
    """Each falling body comes to rest on the static floor (top at 0) at its own half
    height: the file's units, axes and shape sizes (<half_extends> too) are read."""
    make, rest = LAYOUTS[layout]
    with Run.start(import_scene(make(tmp_path / f"{layout}.dae"))) as run:
        run.step(2.5)
        for oid, height in rest.items():
            assert run.position(oid)[2] == pytest.approx(height, abs=0.01), oid
            assert np.linalg.norm(run.velocity(oid)) < 0.05, oid


def test_bullets_one_sided_constraints_hold_each_bob_to_its_own_pivot(tmp_path):
    """Bullet's converter writes every constraint with one <attachment> and one sid: each
    instance is its own constraint, holding its bob to the world where the attachment
    starts. The bobs swing about their horizontal hinges, each pivot staying put."""
    path = samples_.bullet_collada(tmp_path / "bullet.dae")
    spec = load_spec(import_scene(path))
    assert sorted(js.bodies for js in spec.joints) == [("BobA", None), ("BobB", None)]
    reach = np.array([0.0, 0.0, samples_.BOB_REACH])  # the pivot above the bob, its axes
    with Run.start(path.with_suffix(".scene")) as run:
        start = {oid: run.position(oid) for oid in samples_.BOB_PIVOTS}
        swung = dict.fromkeys(start, 0.0)
        for _ in range(15):
            for oid, pivot in samples_.BOB_PIVOTS.items():
                turn = quat_to_matrix(run.transform(oid).orientation)
                np.testing.assert_allclose(run.position(oid) + turn @ reach, pivot, atol=0.01)
                swung[oid] = max(swung[oid], float(np.linalg.norm(run.position(oid) -
                                                                  start[oid])))
            run.step(0.1)
    for oid, distance in swung.items():
        # from 40 degrees out to the far side: the chord of 80 degrees, 0.64 m
        assert distance > 0.5, oid
