"""The engine's own blocks go through the same registry as a content folder's
(components.blocks declares them beside their component; engine.scene.blocks registers
them): typed keys with units and examples, a block inside another, build and save
functions, and the key reference generated from it (issue 32)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import engine.scene.schema as sc
from components import Wheelchair
from components.blocks import DECLARED, BlockDeclaration, BuildContext, Key, declare
from engine.app import EngineConfig
from engine.scene import SceneError, instantiate, keys, spec_from_text, write_state
from engine.scene.blocks import BLOCKS, BlockError, builtin, from_content, unregister
from systems import create_engine


@dataclass(slots=True)
class Rig:
    height: float = 1.0


@dataclass(slots=True)
class Brake:
    force: float = 0.0
    worn: float = 0.0


def _rig(v: Mapping[str, Any], ctx: BuildContext) -> list[Any] | None:
    if v["Height"] > 10:
        ctx.error("Height", f"rig '{ctx.owner}' is too tall")
        return None
    return [Rig(float(v["Height"]))]


def _brake(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    return [Brake(float(v["Force"]), float(v["Worn"]))]


@pytest.fixture
def rig() -> Iterator[None]:
    """A top-level Rig block with a Brake block inside it, declared as the engine's are."""
    declare(BlockDeclaration("Rig", (Key("Height", "float", 1.0, "the rig's height", unit="m",
                                         example="2.5"),), _rig, "a test rig",
                             inside=("Scene",)))
    declare(BlockDeclaration("Brake", (
        Key("Force", "float", 0.0, "how hard it holds", unit="N", low=0.0),
        Key("Worn", "float", 0.0, "how worn it is (written by --save-state)")), _brake,
        "the rig's brake", inside=("Rig",), saves=Brake,
        save=lambda brake: {"Worn": brake.worn}))
    yield
    unregister("Brake")
    unregister("Rig")


def test_the_engines_blocks_are_registered_documented_and_not_content() -> None:
    wheelchair = BLOCKS["Wheelchair"]
    assert builtin(wheelchair) and not from_content("Wheelchair")
    assert wheelchair.component is Wheelchair and "Wheelchair" in sc.SCHEMAS["Object"]
    page = keys.reference_markdown()
    assert "## Wheelchair" in page and "`Lag [0.0012 -0.0004]`" in page
    assert "m/s, at the rim" in keys.block_text("Wheelchair")


def test_a_block_inside_another_builds_onto_its_entity(rig: None, tmp_path: Path) -> None:
    spec = spec_from_text('Rig { ID "r" Height 2 Brake { Force 30 } }\n', tmp_path)
    (made,) = [e for e in spec.entities if e.id == "r"]
    assert {type(c) for c in made.components} >= {Rig, Brake}
    assert next(c for c in made.components if isinstance(c, Brake)).force == 30.0
    assert "Inside Rig: the rig's brake." in keys.reference_markdown()
    assert "m, the rig's height" in keys.block_text("Rig") and "Height 2.5" in \
        keys.block_text("Rig")


def test_a_nested_blocks_mistakes_are_told_at_their_lines(rig: None, tmp_path: Path) -> None:
    with pytest.raises(SceneError) as bad_key:
        spec_from_text('Rig { ID "r"\n  Brake { Forse 30 } }\n', tmp_path, path="m.scene")
    assert "m.scene:2:11: error: unknown key 'Forse' in Brake (did you mean 'Force'?)" in \
        str(bad_key.value)
    with pytest.raises(SceneError) as low:
        spec_from_text('Rig { ID "r"\n  Brake { Force -1 } }\n', tmp_path, path="m.scene")
    assert "m.scene:2:17: error: Brake: Force must be at least 0, got -1" in str(low.value)
    with pytest.raises(SceneError) as told:
        spec_from_text('Rig { ID "r"\n  Height 12 }\n', tmp_path, path="m.scene")
    assert "m.scene:2:10: error: rig 'r' is too tall" in str(told.value)


def test_a_save_function_writes_the_live_value_back(rig: None, tmp_path: Path) -> None:
    text = 'Rig { ID "r" Brake { Force 30 Worn 0.25 } }\n'
    spec = spec_from_text(text, tmp_path, np.random.default_rng(1),
                          path=str(tmp_path / "m.scene"))
    with create_engine(EngineConfig(fast=True)) as engine:
        ids = instantiate(engine, spec)
        engine.world.component_for_entity(ids["r"], Brake).worn = 0.75
        saved = write_state(engine)
    assert "Worn 0.75" in saved and "Force 30" in saved
    again = spec_from_text(saved, tmp_path)
    (made,) = [e for e in again.entities if e.id == "r"]
    assert next(c for c in made.components if isinstance(c, Brake)).worn == 0.75


def test_a_declaration_in_no_known_place_is_refused() -> None:
    with pytest.raises(BlockError, match="cannot stand inside"):
        declare(BlockDeclaration("Lost", (), _brake, inside=("Nowhere",)))
    with pytest.raises(BlockError, match="exists already"):
        declare(BlockDeclaration("Joint", (), _brake))
    with pytest.raises(BlockError, match="no type"):
        declare(BlockDeclaration("Odd", (Key("X", "color"),), _brake))


def test_a_joint_is_a_declared_block_that_makes_no_entity_of_its_own(tmp_path: Path) -> None:
    """Joint goes through the registry (entity=False): its build hands the context a
    joint between bodies by ID, with the bodies' poses as reference, and a saved state
    writes it back under the ID its place gave it."""
    text = ('Object { ID "a" Position [0 0 1] PhysicalAttributes { Mass 1 } }\n'
            'Object { ID "b" Position [1 0 1] PhysicalAttributes { Mass 1 } }\n'
            'Joint { Type "Hinge" Bodies ["a" "b"] Low -30 }\n')
    joint = BLOCKS["Joint"]
    assert builtin(joint) and not joint.entity and "Joint" in sc.SCHEMAS["Scene"]
    spec = spec_from_text(text, tmp_path, np.random.default_rng(1),
                          path=str(tmp_path / "m.scene"))
    assert [e.id for e in spec.entities] == ["a", "b"]
    (js,) = spec.joints
    assert (js.id, js.bodies, js.joint.low) == ("joint0", ("a", "b"), pytest.approx(-np.pi / 6))
    assert js.joint.reference == ((0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0),
                                  (1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0))
    with create_engine(EngineConfig(fast=True)) as engine:
        instantiate(engine, spec)
        saved = write_state(engine)
    assert 'ID "joint0"' in saved
    with pytest.raises(SceneError, match="no PhysicalAttributes"):
        spec_from_text(text.replace("PhysicalAttributes { Mass 1 }", "VisualAttributes { }", 1),
                       tmp_path)


def test_a_setting_block_fills_the_scene_and_a_second_id_is_claimed_once(tmp_path: Path
                                                                         ) -> None:
    """Anomalies, Measure and PostPass make no entity: their builds fill the scene's lists
    (anomalies in the vocabulary's order), and two anomalies with one ID are told at the
    second in that order, naming where the first is."""
    text = ('Object { ID "ball" Position [0 0 1] }\n'
            'Measure { ID "height" Object "ball" }\n'
            'Hemianopia { ID "h" Side "left" }\n'
            'DoubleVision { }\n'
            'PostPass { ID "grey" File "grey.frag" Uniform { ID "amount" Value 0.5 } }\n')
    (tmp_path / "grey.frag").write_text("void main() {}\n")
    spec = spec_from_text(text, tmp_path, path=str(tmp_path / "m.scene"))
    assert [e.id for e in spec.entities] == ["ball"]
    assert [(m.id, m.object, m.value) for m in spec.measures] == [("height", "ball", "z")]
    assert [a.id for a in spec.anomalies] == ["double_vision", "h"]  # vocabulary order
    (post,) = spec.post_passes
    assert (post.id, post.uniforms, post.origin) == ("grey", {"amount": 0.5},
                                                    f"{tmp_path / 'm.scene'}:5")
    with pytest.raises(SceneError) as twice:
        spec_from_text(text + 'Neglect { ID "h" }\n', tmp_path, path="m.scene")
    # Neglect comes before Hemianopia in the vocabulary: the Hemianopia is the second
    assert "m.scene:3:12: error: a second anomaly 'h' (the first is at m.scene:6:9)" in \
        str(twice.value)


def test_a_refused_declaration_leaves_the_one_it_clashed_with() -> None:
    joint = BLOCKS["Joint"]
    with pytest.raises(BlockError, match="exists already"):
        declare(BlockDeclaration("Joint", (), _brake))
    assert DECLARED["Joint"].build is joint.hook and BLOCKS["Joint"] is joint
