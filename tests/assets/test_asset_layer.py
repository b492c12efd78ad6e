"""The asset layer: one read per file for render, physics and sound; loaders by extension
that an author can add; the dependencies each format really needs."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hostile import cube, knock
from PIL import Image
from test_hostile_assets import CAMERA, GROUND, content, engine_for

from components import Physical
from engine.assets import AssetError, Assets, register_loader, unregister_loader
from engine.assets.geometry import convex_hull
from engine.assets.loaders import MODEL_EXTENSIONS, load_trimesh_model
from engine.scene import Loc, instantiate, load_spec
from systems.render import RenderSystem
from systems.sound import SoundSystem

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def counted_obj() -> Iterator[list[Path]]:
    """Every .obj read goes through a counting loader (the built-in one, counted)."""
    reads: list[Path] = []

    def counting(path: Path) -> object:
        reads.append(path)
        return load_trimesh_model(path)

    register_loader("model", ".obj")(counting)
    yield reads
    register_loader("model", ".obj")(load_trimesh_model)


def test_a_model_drawn_and_collided_by_two_objects_is_read_once(tmp_path: Path,
                                                                  counted_obj: list[Path]):
    Image.new("RGB", (4, 4), (200, 40, 40)).save(tmp_path / "red.png")
    cube(tmp_path / "crate.obj")
    knock(tmp_path / "knock.wav")
    crate = ('Object {{ ID "{id}" Position [{x} 0 2] Sound {{ File "knock.wav" AutoPlay 1 }}\n'
             '  VisualAttributes {{ Texture "red.png" Geometry {{ File "crate.obj" '
             'Scale [{s} {s} {s}] }} }}\n'
             '  PhysicalAttributes {{ Geometry {{ File "crate.obj" Scale [{s} {s} {s}] '
             'ParseMethod "ConvexHull" }} }} }}')
    folder = content(tmp_path, [GROUND, crate.format(id="a", x=-1, s=1),
                                crate.format(id="b", x=1, s=0.5), CAMERA], {})
    spec = load_spec(folder)
    assert spec.problems == []
    with engine_for(folder) as engine:
        instantiate(engine, spec)
        engine.run(frames=5)
        renderer = engine.resource(RenderSystem).renderer
        assert renderer is not None and renderer.errors == []
        assert engine.resource(SoundSystem).manager.stats()["played"] == 2
        assets = engine.resource(Assets)
        hulls = [c.shapes[0] for _, c in engine.world.get_component(Physical)
                 if c.shapes[0].kind == "hull"]
    assert counted_obj == [folder / "crate.obj"]  # visual and hull, both objects, both scales
    assert assets is spec.assets and assets.loads == {
        (folder / name).resolve(): 1 for name in ("crate.obj", "red.png", "knock.wav")}
    extents = sorted(float(np.ptp(h.vertices[:, 0])) for h in hulls)
    assert extents == pytest.approx([0.5, 1.0])  # one read, a hull per scale


def test_a_gltf_node_or_mesh_reads_the_texture_coordinates_the_whole_file_does():
    """glTF's v runs down from the image's top row, a MeshPart's up. Drawn whole (through
    trimesh) or as a node or a mesh of it (engine/assets/gltf.py, as imported scenes draw
    their bodies), each vertex of the walker's textured shirt reads the same texel; the
    node path read v upside down."""
    from collections import Counter

    def places(parts: tuple) -> tuple[list, list, Counter]:
        keys = [tuple(np.round(v, 6)) for part in parts for v in part.vertices]
        return keys, [uv for part in parts for uv in part.uv], Counter(keys)

    assets = Assets(ROOT / "content" / "avatars" / "models")
    keys, uvs, counts = places(assets.model("walker.glb").parts)
    whole = dict(zip(keys, uvs, strict=True))
    for ref in ('walker.glb#["walker"]', 'walker.glb#mesh["walker"]'):
        keys, uvs, seen = places(assets.model(ref).parts)
        # a point where two tubes meet (caps, joins) has one texel per tube: left out
        once = [i for i, k in enumerate(keys) if seen[k] == 1 and counts[k] == 1]
        assert len(once) > 500
        np.testing.assert_allclose([whole[keys[i]] for i in once], [uvs[i] for i in once],
                                   atol=1e-6)


def test_an_author_registers_a_format_in_the_content_systems(tmp_path: Path):
    """A loader for a new extension, in the content's own systems/ module, reads the scene's
    model for `check` and for a run that draws it; its failure is told like any other."""
    folder = content(tmp_path / "sim", [
        GROUND,
        'Object { ID "wedge" Position [0 0 1] VisualAttributes { Geometry { File "w.tri" } }\n'
        '  PhysicalAttributes { Geometry { File "w.tri" ParseMethod "Box" } } }',
        'Object { ID "odd" Position [2 0 1] VisualAttributes { Geometry { File "odd.tri" } } }',
        CAMERA], {})
    (folder / "w.tri").write_text("0 0 0  1 0 0  0 1 0\n0 0 0  0 1 0  0 0 1\n")
    (folder / "odd.tri").write_text("0 0 zero\n")
    (folder / "systems").mkdir()
    (folder / "systems" / "tri.py").write_text(textwrap.dedent('''\
        from engine.assets import ModelAsset, mesh_part, register_loader

        @register_loader("model", ".tri")
        def load_tri(path):
            rows = [[float(x) for x in line.split()] for line in path.read_text().splitlines()]
            points = [row[i:i + 3] for row in rows for i in (0, 3, 6)]
            return ModelAsset(path, (mesh_part(points, [[3 * k, 3 * k + 1, 3 * k + 2]
                                                        for k in range(len(rows))]),))

        def build(engine):
            pass
        '''))
    check = subprocess.run([sys.executable, "-m", "app.cli", "check", str(folder)],
                           capture_output=True, text=True, timeout=120)
    assert check.returncode == 1, check.stderr
    assert check.stderr.count("error:") == 1 and '"odd.tri"' in check.stderr
    assert "could not convert string to float: 'zero'" in check.stderr
    shot = tmp_path / "shot.png"
    run = subprocess.run([sys.executable, "-m", "app.cli", "run", str(folder), "--headless",
                          "--frames", "3", "--fast", "--sound", "null", "--size", "64x48",
                          "--screenshot", str(shot)], capture_output=True, text=True, timeout=120)
    # it ran without the broken object, and says the content had an error (exit 1)
    assert run.returncode == 1 and "Traceback" not in run.stderr, run.stderr
    assert "wedge" not in run.stderr and "object 'odd' is left out" in run.stderr


def test_an_unknown_extension_names_the_formats_there_are(tmp_path: Path):
    (tmp_path / "cow.osg").write_text("osg")
    with pytest.raises(AssetError) as info:
        Assets(tmp_path).model("cow.osg")
    assert info.value.reason.startswith("unsupported model format '.osg'; supported: ")
    assert all(ext in info.value.reason for ext in MODEL_EXTENSIONS)
    unregister_loader("model", ".nothing")  # forgetting what is not there is no error


def test_a_failure_is_cached_and_told_at_each_place_that_asks(tmp_path: Path):
    (tmp_path / "gone.obj").write_text("")
    assets = Assets(tmp_path)
    first, second = (_failure(lambda w=w: assets.model("gone.obj", w))
                     for w in (Loc("a.scene", 3, 7), Loc("b.scene", 9, 1)))
    assert str(first).startswith("a.scene:3:7: error: cannot load model \"gone.obj\"")
    assert str(second).startswith("b.scene:9:1: error:") and second.reason == first.reason
    assert sum(assets.loads.values()) == 0  # refused before a loader ran; not asked again
    assert str(_failure(lambda: assets.model("gone.obj"))).startswith("a.scene:3:7:")


def _failure(load: object) -> AssetError:
    with pytest.raises(AssetError) as info:
        load()  # type: ignore[operator]
    return info.value


_BALL = trimesh.creation.icosphere(subdivisions=2, radius=1.0)  # convex: its own hull


@pytest.mark.parametrize("points, expected_volume", [
    (_BALL.vertices, _BALL.volume),
    (np.array([[0, 0, 0], [2, 0, 0], [0, 3, 0], [0, 0, 4], [0.1, 0.1, 0.1]]), 2 * 3 * 4 / 6),
    (trimesh.creation.box(extents=(1, 2, 3)).vertices * (1, -1, 1), 6.0),
])
def test_convex_hull_is_closed_outward_and_encloses_the_volume(points, expected_volume):
    vertices, faces = convex_hull(np.asarray(points))
    hull = trimesh.Trimesh(vertices, faces, process=False)
    assert hull.is_watertight and hull.is_winding_consistent
    assert hull.volume > 0  # outward winding: the signed volume is positive
    assert hull.volume == pytest.approx(expected_volume, rel=1e-9)


@pytest.mark.parametrize("points", [
    [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 3, 0]],
    [[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]],
])
def test_convex_hull_refuses_points_that_enclose_no_volume(points):
    with pytest.raises(ValueError, match="(enclose no volume|distinct points)"):
        convex_hull(np.asarray(points, float))


def test_every_model_format_loads_without_networkx_or_lxml(tmp_path: Path):
    """The dependencies we dropped: every built-in format, its physics shapes and the
    renderer's parts, in a Python where importing networkx or lxml fails."""
    script = textwrap.dedent(f'''\
        import importlib.abc, sys
        class Refuse(importlib.abc.MetaPathFinder):
            def find_spec(self, name, path, target=None):
                if name.split(".")[0] in ("networkx", "lxml"):
                    raise ModuleNotFoundError(name, name=name)
        sys.meta_path.insert(0, Refuse())
        import trimesh
        from services.render.meshes import from_part
        from engine.scene import spec_from_text
        folder = {str(tmp_path)!r}
        for ext in {MODEL_EXTENSIONS!r}:
            trimesh.creation.box(extents=(1, 2, 3)).export(f"{{folder}}/box{{ext}}")
            for method in ("ConvexHull", "TriangleMesh", "Box"):
                spec = spec_from_text(
                    f'Object {{{{ VisualAttributes {{{{ Geometry {{{{ File "box{{ext}}" }}}} }}}}'
                    f' PhysicalAttributes {{{{ Geometry {{{{ File "box{{ext}}" '
                    f'ParseMethod "{{method}}" }}}} }}}} }}}}', folder)
                assert spec.problems == [], spec.problems
                for part in spec.assets.model(f"box{{ext}}").parts:
                    from_part(part)
        print("ok", sorted(m for m in sys.modules if m.startswith(("networkx", "lxml"))))
        ''')
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            timeout=120, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok []"
