"""The scene description format: text -> SceneDB -> checked -> entity specs -> entities.

Typical use::

    db = load_scene("content/demo", rng)          # parse + schema check (SceneError)
    spec = build_specs(db, "content/demo")        # components per object (pure)
    ids = instantiate(engine, spec)               # entities; object ID -> entity id

See :mod:`engine.scene.schema` for every key, its default and the units.


Its names load on first use (:mod:`engine.lazy`): ``colosseum keys`` reads the schema
without the factory, the loader or the writer.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.lazy import lazy_exports

if TYPE_CHECKING:
    from engine.scene.bench import bench_scene, generate_scene
    from engine.scene.db import Block, Entry, SceneDB, Value
    from engine.scene.diagnostics import Diagnostic, Loc, Report, SceneError, render_all
    from engine.scene.factory import (
        EntitySpec,
        JointSpec,
        SceneIds,
        SceneSpec,
        build_specs,
        instantiate,
    )
    from engine.scene.loader import (
        check,
        format_scene,
        load_scene,
        load_spec,
        scene_path,
        spec_from_text,
        validated,
    )
    from engine.scene.parser import Limits, parse_file, parse_text
    from engine.scene.snapshot import write_state
    from engine.scene.writer import write

__all__ = [
    "Block",
    "Diagnostic",
    "Entry",
    "EntitySpec",
    "JointSpec",
    "Limits",
    "Loc",
    "Report",
    "SceneDB",
    "SceneError",
    "SceneIds",
    "SceneSpec",
    "Value",
    "bench_scene",
    "build_specs",
    "check",
    "format_scene",
    "generate_scene",
    "instantiate",
    "load_scene",
    "load_spec",
    "parse_file",
    "parse_text",
    "render_all",
    "scene_path",
    "spec_from_text",
    "validated",
    "write",
    "write_state",
]

__getattr__, __dir__ = lazy_exports(__name__, {
    "engine.scene.bench": ("bench_scene", "generate_scene"),
    "engine.scene.db": ("Block", "Entry", "SceneDB", "Value"),
    "engine.scene.diagnostics": ("Diagnostic", "Loc", "Report", "SceneError", "render_all"),
    "engine.scene.factory": ("EntitySpec", "JointSpec", "SceneIds", "SceneSpec", "build_specs",
                             "instantiate"),
    "engine.scene.loader": ("check", "format_scene", "load_scene", "load_spec", "scene_path",
                            "spec_from_text", "validated"),
    "engine.scene.parser": ("Limits", "parse_file", "parse_text"),
    "engine.scene.snapshot": ("write_state",),
    "engine.scene.writer": ("write",)})
