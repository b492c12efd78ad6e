"""A canonical dump of the world a scene file builds: the safety net of a change to the
scene format's code (``python -m tools.scene_dump`` writes the golden dumps).

Every scene file in ``content/`` and ``tests/`` and a few saved states are built into
a :class:`~engine.scene.SceneSpec`; the dump lists its entities (each component's type
and field values), joints, materials, world settings, inputs, anomalies and experiment,
entities by ID and their components by type, fields at their defaults left out, floats
rounded, mappings sorted, places and caches left out. A change that claims to
load "the scene files and saved states of today unchanged" must leave every dump equal
to the one committed under ``tests/scene/data/golden/`` (``tests/scene/test_golden.py``).
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
GOLDEN = ROOT / "tests" / "scene" / "data" / "golden"
STATES = GOLDEN / "states"
#: Content folders whose saved state (after a few frames) is kept as a golden input too.
SAVED = ("demo", "hands", "stroke", "avatars", "pool", "multiuser")
FRAMES = 5
#: Fields of a spec that are places, caches or the parsed text, not the built world; and
#: lookup tables the building used, whose results are dumped (shader programs' files,
#: masses from a material's density).
_SKIP = {"loc", "db", "assets", "content_dir", "problems", "shader_files", "dense_materials"}
DIGITS = 9


def scene_files() -> list[Path]:
    """Every scene file of content/ and tests/ (sorted), and the golden saved states."""
    found = [*ROOT.glob("content/**/*.scene"), *ROOT.glob("tests/**/*.scene")]
    return sorted(p for p in found if STATES not in p.parents) + sorted(STATES.glob("*.scene"))


def canonical(value: Any, root: Path = ROOT) -> Any:
    """``value`` as plain JSON data: dataclasses (and slotted classes) by type and field,
    floats to 9 significant digits, sets and mappings sorted, paths relative to ``root``."""
    if isinstance(value, enum.Enum):
        return canonical(value.value, root)
    if isinstance(value, str):
        return value.replace(str(root) + "/", "")
    if isinstance(value, bool | int) or value is None:
        return value
    if isinstance(value, float | np.floating):
        return _number(float(value))
    if isinstance(value, np.ndarray | np.generic):
        return canonical(value.tolist(), root)
    if isinstance(value, type):
        return value.__name__
    if isinstance(value, Path):
        return _path(value, root)
    if isinstance(value, dict):
        return {str(k): canonical(v, root) for k, v in sorted(value.items(), key=_key)}
    if isinstance(value, set | frozenset):
        return sorted((canonical(v, root) for v in value), key=repr)
    if isinstance(value, list | tuple):
        return [canonical(v, root) for v in value]
    return {"type": type(value).__name__, **{
        name: canonical(getattr(value, name), root) for name in _fields(value)
        if name not in _SKIP and not _default(value, name)}}


def _default(value: Any, name: str) -> bool:
    """Whether dataclass field ``name`` holds its default: left out of the dump, so a
    field a component gains (with a default that changes nothing) leaves dumps alone."""
    if not dataclasses.is_dataclass(value):
        return False
    f = next(f for f in dataclasses.fields(value) if f.name == name)
    if f.default is not dataclasses.MISSING:
        default = f.default
    elif f.default_factory is not dataclasses.MISSING:
        default = f.default_factory()
    else:
        return False
    mine = getattr(value, name)
    if isinstance(mine, np.ndarray) or isinstance(default, np.ndarray):
        return False
    try:
        return type(mine) is type(default) and bool(mine == default)
    except (TypeError, ValueError):
        return False


def _key(item: tuple[Any, Any]) -> str:
    return repr(item[0])


def _number(x: float) -> Any:
    if not math.isfinite(x):
        return repr(x)
    return 0.0 if x == 0.0 else float(f"{x:.{DIGITS}g}")


def _path(p: Path, root: Path) -> str:
    try:
        return p.resolve().relative_to(root).as_posix()
    except ValueError:
        return p.name


def _fields(value: Any) -> list[str]:
    if dataclasses.is_dataclass(value):
        return [f.name for f in dataclasses.fields(value)]
    slots = [s for cls in type(value).__mro__ for s in getattr(cls, "__slots__", ())]
    if slots:
        return sorted(s for s in slots if not s.startswith("_"))
    return sorted(k for k in vars(value) if not k.startswith("_"))


def dump(path: Path) -> Any:
    """The canonical world scene file ``path`` builds, or its first error's message."""
    from engine.scene import load_spec
    from engine.scene.diagnostics import SceneError

    try:
        spec = load_spec(path)
    except SceneError as exc:
        first = exc.diagnostics[0]
        return {"error": f"{Path(first.path).name}:{first.line}: {first.message}"}
    return _sorted(_linked(canonical(spec)))


#: A spec's references from one entity's component to another object, by ID, set when
#: the scene is instantiated: (spec field, component type, component field).
_REFERENCES = (("camera_follow", "Camera", "follow"), ("display_heads", "Display", "head"),
               ("hand_frames", "Hand", "frame"))


def _linked(world: dict[str, Any]) -> dict[str, Any]:
    """Each reference written into the field it sets (``"@ID"``), as instantiate will: the
    world holds the link, wherever the spec keeps it until then (a table of its own, or
    the generic ``links`` of declared blocks)."""
    found = [(source, kind, name, target) for field, kind, name in _REFERENCES
             for source, target in world.pop(field, {}).items()]
    found += [(link["entity"], link["component"], link["field"], link["target"])
              for link in world.pop("links", [])]
    by_id = {e["id"]: e for e in world.get("entities", [])}
    for source, kind, name, target in found:
        for component in by_id[source].get("components", []) if source in by_id else ():
            if component["type"] == kind:
                component[name] = f"@{target}"
    return world


def _sorted(world: dict[str, Any]) -> dict[str, Any]:
    """Entities by ID and each one's components by type: an entity's components are a
    set (the ECS keeps them by type), and which of two top-level blocks is made first
    changes entity numbers, not the world."""
    entities = world.get("entities", [])
    for entity in entities:
        entity.get("components", []).sort(key=lambda c: c["type"])
    entities.sort(key=lambda e: (e["id"], json.dumps(e, sort_keys=True)))
    return world


def golden_name(path: Path) -> str:
    """The golden dump's file name for scene ``path``."""
    return path.relative_to(ROOT).as_posix().replace("/", "__") + ".json"


def save_states() -> None:
    """Run each content folder a few frames and keep its ``--save-state`` (the golden
    saved states: written by today's code, they must load unchanged later)."""
    STATES.mkdir(parents=True, exist_ok=True)
    sessions = tempfile.mkdtemp(prefix="colosseum-golden-")
    for name in SAVED:
        out = STATES / f"{name}.scene"
        subprocess.run([sys.executable, "-m", _cli(), "run", str(ROOT / "content" / name),
                        "--headless", "--fast", "--frames", str(FRAMES), "--sound", "null",
                        "--no-xr", "--seed", "1", "--sessions", sessions,
                        "--save-state", str(out)],
                       check=True, cwd=ROOT)
        # the comments name the folder it was saved from: kept relative, as the data is
        out.write_text(out.read_text(encoding="utf-8").replace(f"{ROOT}/", ""),
                       encoding="utf-8")


def _cli() -> str:
    """The module ``colosseum`` runs (the application package's, where it has moved)."""
    return "app.cli" if (ROOT / "app" / "cli.py").is_file() else "engine.cli"


def main(argv: list[str]) -> int:
    """Write the golden dumps (with ``--states``, the saved states first)."""
    if "--states" in argv:
        save_states()
    GOLDEN.mkdir(parents=True, exist_ok=True)
    for path in scene_files():
        text = json.dumps(dump(path), indent=1, sort_keys=True, ensure_ascii=False)
        (GOLDEN / golden_name(path)).write_text(text + "\n", encoding="utf-8")
        print(golden_name(path))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
