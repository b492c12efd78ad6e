"""Blocks declared by a feature beside its component (engine.scene.blocks), a content
folder's own systems included: checked at their lines, documented, built, saved and
continued, as the engine's own blocks are."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

import engine.scene.schema as sc
from engine.scene import blocks
from engine.scene.blocks import BlockError, key, register, scene_block

ROOT = Path(__file__).resolve().parents[2]
POOL = ROOT / "content" / "pool"


def colosseum(*args: object, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=120, cwd=cwd or ROOT)


def _heights(saved: Path) -> dict[str, float]:
    """Each object's height in a saved state."""
    out, name = {}, None
    for line in saved.read_text().splitlines():
        line = line.strip()
        if line.startswith("ID "):
            name = line.split('"')[1]
        elif line.startswith("Position [") and name is not None and name not in out:
            out[name] = float(line.removeprefix("Position [").rstrip("]").split()[2])
    return out


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_the_pool_floats_what_archimedes_says(tmp_path: Path, backend: str):
    """A 500 kg/m³ ball floats with its centre at the surface; a 240 kg/m³ cube rides
    with 24 % of it under; steel sinks to the floor: the pool's own block and system."""
    saved = tmp_path / "pool.scene"
    result = colosseum("run", POOL, "--seconds", "8", "--fast", "--headless",
                       "--backend", backend, "--save-state", saved, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    z = _heights(saved)
    assert z["pine ball"] == pytest.approx(0.5, abs=0.002 if backend == "ode" else 0.01)
    assert z["steel ball"] == pytest.approx(0.1, abs=0.003)
    if backend == "ode":  # the plane's pymunk backend floats a square, not a cube
        assert z["cork"] == pytest.approx(0.5 + 0.15 - 0.24 * 0.3, abs=0.002)
    # the saved state keeps the block and continues from it
    text = saved.read_text()
    written = [line for line in text.splitlines() if line.strip().startswith("Buoyancy {")]
    assert len(written) == 3 and "Density 1000" in text
    again = colosseum("run", saved, "--seconds", "1", "--fast", "--headless",
                      "--backend", backend, cwd=tmp_path)
    assert again.returncode == 0, again.stderr


def test_check_tells_a_wrong_key_and_a_value_out_of_range_at_their_lines(tmp_path: Path):
    folder = tmp_path / "pool"
    (folder / "systems").mkdir(parents=True)
    (folder / "systems" / "buoyancy.py").write_text(
        (POOL / "systems" / "buoyancy.py").read_text())
    ball = 'Object { ID "a" Size [0.2] PhysicalAttributes { Geometry { Primitive "sphere" } }\n'
    (folder / "main.scene").write_text(ball + '  Buoyancy { Densty 900 } }\n')
    result = colosseum("check", folder)
    out = result.stdout + result.stderr
    assert result.returncode == 1
    assert "main.scene:2:14: error: unknown key 'Densty' in Buoyancy (did you mean " \
           "'Density'?)" in out
    (folder / "main.scene").write_text(ball + '  Buoyancy { Density -3 } }\n')
    result = colosseum("check", folder)
    out = result.stdout + result.stderr
    assert result.returncode == 1
    assert "main.scene:2:22: error: Buoyancy: Density must be at least 0, got -3" in out


def test_keys_documents_a_content_folders_block():
    result = colosseum("keys", "Buoyancy", "--content", POOL)
    assert result.returncode == 0
    assert "Density" in result.stdout and "kg/m³, the liquid's density" in result.stdout
    unknown = colosseum("keys", "Buoyancy")  # without the folder it is not known
    assert unknown.returncode == 2


def test_a_block_name_the_engine_uses_is_refused():
    @dataclass
    class Mine:
        strength: float = key(1.0, "N")

    with pytest.raises(BlockError, match="'Hand' exists already"):
        register("Hand", Mine)
    with pytest.raises(BlockError, match="CamelCase"):
        register("my_block", Mine)


def test_a_top_level_block_is_an_entity_named_by_its_id(tmp_path: Path):
    from engine.scene import spec_from_text

    @scene_block("Weather", inside=("Scene",), doc="the day's weather")
    @dataclass
    class Weather:
        wind: tuple = key((0.0, 0.0, 0.0), "m/s, the wind")
        rain: bool = key(False, "whether it rains")

    try:
        spec = spec_from_text('Weather { ID "today" Wind [3 0 0] Rain 1 }\n', tmp_path)
        made = [e for e in spec.entities if e.id == "today"]
        assert made and any(isinstance(c, Weather) and c.wind == (3.0, 0.0, 0.0) and c.rain
                            for c in made[0].components)
    finally:
        blocks.unregister("Weather")
    assert "Weather" not in blocks.BLOCKS and "Weather" not in sc.SCHEMAS["Scene"]


def test_a_content_folders_block_stays_out_of_the_engines_reference():
    """Loaded in this process, the pool's block checks its scene but is not the engine's:
    the scene-keys page and the plain block list leave it out."""
    from engine.scene import keys, load_scene

    load_scene(POOL)
    assert "Buoyancy" in keys.blocks(content=True) and "Buoyancy" not in keys.blocks()
    assert "Buoyancy" not in keys.reference_markdown()


_LAPS = '''"""A lap's checkpoints: numbered alone, told at their lines where the numbers clash."""
from dataclasses import dataclass

from components.blocks import BlockDeclaration, Key, declare


@dataclass
class Checkpoint:
    number: int
    of: int = 0  # how many the lap has: known once every block is built


def build(values, ctx):
    gate = Checkpoint(int(values["Number"]))
    ctx.gathered("checkpoints").append((gate, ctx))
    return [gate]


def finish(parts, ctx):
    seen = set()
    for gate, at in ctx.gathered("checkpoints"):
        gate.of = len(parts)
        if gate.number in seen:
            at.error("Number", f"checkpoint {gate.number} is given twice")
        seen.add(gate.number)


declare(BlockDeclaration("Checkpoint", inside=("Scene",), build=build, finish=finish,
                         doc="a gate of the lap", keys=(
                             Key("Number", "int", 1, "its place in the lap"),)))
'''


def test_a_content_folders_block_has_a_finish_step_after_every_block(tmp_path: Path):
    """A content folder's systems/*.py declares a top-level block whose finish step sees
    every block's parts (each gate learns how many the lap has) and tells a clash at the
    line of the block that made it, as the engine's Input does."""
    from engine.scene import check, load_spec

    folder = tmp_path / "laps"
    (folder / "systems").mkdir(parents=True)
    (folder / "systems" / "laps.py").write_text(_LAPS)
    (folder / "main.scene").write_text('Checkpoint { ID "a" Number 1 }\n'
                                       'Checkpoint { ID "b" Number 2 }\n'
                                       'Checkpoint { ID "c" Number 3 }\n')
    try:
        spec = load_spec(folder)
        gates = {e.id: c for e in spec.entities for c in e.components
                 if type(c).__name__ == "Checkpoint"}
        assert {k: (g.number, g.of) for k, g in gates.items()} == {
            "a": (1, 3), "b": (2, 3), "c": (3, 3)}
        assert blocks.from_content("Checkpoint")  # not among the engine's own blocks
        (folder / "main.scene").write_text('Checkpoint { ID "a" Number 1 }\n'
                                           'Checkpoint { ID "b" Number 1 }\n')
        told = [(Path(d.path).name, d.line, d.col, d.severity, d.message)
                for d in check(folder / "main.scene")]
        assert told == [("main.scene", 2, 28, "error", "checkpoint 1 is given twice")]
    finally:
        blocks.unregister("Checkpoint")
