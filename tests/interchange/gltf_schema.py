"""What ``colosseum export`` writes, checked against the JSON schemas of
KHR_physics_rigid_bodies and KHR_implicit_shapes (../shared/gltf-physics/schemas, each
registered under its ``$id``; the core glTF schemas they refer to in ``schemas/core``).

:func:`problems` lists what does not validate; tests/conftest.py runs it over every file
an export writes during the tests (issue 31).
"""

from __future__ import annotations

import json
import struct
from functools import cache
from pathlib import Path
from typing import Any

SCHEMAS = Path(__file__).resolve().parents[3] / "shared" / "gltf-physics" / "schemas"
KHR = "KHR_physics_rigid_bodies"
SHAPES = "KHR_implicit_shapes"


def available() -> bool:
    return (SCHEMAS / "node.KHR_physics_rigid_bodies.schema.json").is_file()


@cache
def _validators() -> dict[str, Any]:
    from jsonschema import Draft202012Validator
    from referencing import Registry, Resource

    resources = []
    for path in sorted(SCHEMAS.rglob("*.json")):
        schema = json.loads(path.read_text(encoding="utf-8"))
        resources.append((schema.get("$id", path.name), Resource.from_contents(schema)))
    registry = Registry().with_resources(resources)

    def validator(name: str) -> Any:
        schema = json.loads((SCHEMAS / name).read_text(encoding="utf-8"))
        return Draft202012Validator(schema, registry=registry)

    return {"node": validator(f"node.{KHR}.schema.json"),
            "document": validator(f"glTF.{KHR}.schema.json"),
            "shapes": validator(f"glTF.{SHAPES}.schema.json")}


def document(path: Path) -> dict[str, Any]:
    """The JSON of a .glb or .gltf file."""
    data = path.read_bytes()
    if data[:4] == b"glTF":
        (length,) = struct.unpack("<I", data[12:16])
        return json.loads(data[20:20 + length])
    return json.loads(data)


def problems(path: Path) -> list[str]:
    """Every place of the file's physics extensions that does not validate: the
    document's KHR_physics_rigid_bodies and KHR_implicit_shapes, each node's
    KHR_physics_rigid_bodies; a geometry naming a node or mesh that is not there."""
    doc = document(path)
    v = _validators()
    found = []
    top = doc.get("extensions", {})
    for key, name in ((KHR, "document"), (SHAPES, "shapes")):
        if key in top:
            found += [f"extensions.{key}: {e.message}" for e in v[name].iter_errors(top[key])]
    nodes = doc.get("nodes", [])
    for i, node in enumerate(nodes):
        ext = node.get("extensions", {}).get(KHR)
        if ext is None:
            continue
        found += [f"nodes[{i}] ({node.get('name')}): {e.message}"
                  for e in v["node"].iter_errors(ext)]
        for part in ("collider", "trigger"):
            geometry = (ext.get(part) or {}).get("geometry", {})
            if "node" in geometry and not (0 <= geometry["node"] < len(nodes) and
                                           "mesh" in nodes[geometry["node"]]):
                found.append(f"nodes[{i}] ({node.get('name')}): its {part} names node "
                             f"{geometry['node']}, which holds no mesh")
    return found
