"""What the CLI does with scene files: load into an engine, check, format, save state.

Kept apart from :mod:`engine.scene` (the format itself) so the format has no
knowledge of command lines, exit codes or terminals.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from engine.content import Content
from engine.files import file_mode, write_atomic

if TYPE_CHECKING:
    from engine.app import Engine, EngineConfig
    from engine.scene import SceneSpec

class SceneLoadError(Exception):
    """The scene has errors; ``str()`` is the full report, every error with its place."""


@dataclass(slots=True)
class LoadedScene:
    spec: SceneSpec
    #: The content folder the scene runs in (a saved state's ``Content``, else its folder).
    content: Content

    def configure(self, config: EngineConfig, backend: str | None = None,
                  dt: float | None = None) -> None:
        """Apply the scene's World settings; command-line flags win over the file."""
        config.backend = backend or self.spec.backend
        config.dt = dt or self.spec.time_step
        config.max_dt = max(config.max_dt, config.dt)
        config.world = self.spec.world

    def instantiate(self, engine: Engine) -> None:
        from engine.scene import instantiate

        instantiate(engine, self.spec)


def load_content_scene(content: Content, seed: int = 0,
                       params: dict[str, str] | None = None) -> LoadedScene:
    """The content's scene, built; its ``systems/*.py`` are imported first, so asset
    loaders they register read the scene's files. A saved state runs in the content
    folder it names (``Content``). ``params`` set scene variables (``--param``)."""
    from engine.content import ContentError
    from engine.scene import SceneError
    from engine.scene.diagnostics import Reporter
    from engine.scene.params import ParamError

    try:
        content, spec = _build(content, np.random.default_rng(seed), params)
    except (ContentError, ParamError) as exc:
        raise SceneLoadError(str(exc)) from exc
    except SceneError as exc:
        raise SceneLoadError(exc.render()) from exc
    if spec.db is not None:  # warnings, and assets that failed (what they left out)
        for told in Reporter([*spec.db.warnings, *spec.problems]).diagnostics:
            print(told.render(spec.db.sources.get(told.path)), file=sys.stderr)
    return LoadedScene(spec, content)


def _build(content: Content, rng: np.random.Generator,
           params: dict[str, str] | None = None) -> tuple[Content, SceneSpec]:
    """Parse, find the content folder, import its systems, check and build. Raises
    SceneError (the scene's mistakes), ContentError (its systems') or ParamError."""
    from engine.content import import_systems
    from engine.scene import build_specs, parse_file, parse_text, validated
    from engine.scene.params import with_params
    from engine.scene.snapshot import content_folder

    db = parse_text(with_params(content.scene, params), str(content.scene), rng) if params \
        else parse_file(content.scene, rng)
    content = Content(content_folder(db), content.scene)
    import_systems(content.folder)
    spec = build_specs(validated(db, content.folder), content.folder)
    return content, spec


def check_path(path: Path, output: str = "text") -> int:
    """Report every diagnostic of a scene; the exit code says how it went.

    ``output`` "text": ``path:line:col: severity: message`` with the line and a caret,
    then the counts, on stderr. "json": one JSON object on stdout (``errors`` and
    ``warnings``, all counted; ``diagnostics``, those shown: objects with ``path line
    col severity message``) for editors and CI. Exit codes: 0 no errors (warnings
    allowed), 1 errors, 2 no such file or folder.
    """
    from engine.scene import Diagnostic, Report
    from engine.scene.paths import NOT_FOUND, file_problem

    if file_problem(path) == NOT_FOUND:
        message = "no such file or folder"
        if output == "json":
            missing = Diagnostic(str(path), 1, 1, "error", message)
            print(Report([missing]).to_json())
        else:
            print(f"colosseum: error: {path}: {message}", file=sys.stderr)
        return 2
    from engine.content import ContentError, resolve
    from engine.scene import SceneError
    from engine.scene.diagnostics import Reporter

    try:  # as a run reads it: the content's asset loaders first, a saved state's folder
        _, spec = _build(resolve(path), np.random.default_rng(0))
        assert spec.db is not None
        report = Report(Reporter([*spec.db.warnings, *spec.problems]).diagnostics,
                        spec.db.sources)
    except ContentError as exc:
        report = Report([Diagnostic(str(path), 1, 1, "error", str(exc))])
    except SceneError as exc:
        report = Report(exc.diagnostics, exc.sources)
    errors, warnings = report.counts()
    if output == "json":
        print(report.to_json())
    else:
        if report.diagnostics:
            print(report.render(), file=sys.stderr)
        print(f"{path}: {errors} error(s), {warnings} warning(s)", file=sys.stderr)
    return 1 if errors else 0


def format_path(path: Path, write: bool = False) -> int:
    """Print the canonical form, or rewrite the file in place keeping a ``.bak``.

    The rewritten file and its ``.bak`` keep the file's mode.
    """
    from engine.scene import SceneError, format_scene, scene_path
    from engine.scene.paths import NOT_FOUND, file_problem

    if file_problem(path) == NOT_FOUND:
        print(f"colosseum: error: {path}: no such file or folder", file=sys.stderr)
        return 2
    try:
        text = format_scene(path)
    except SceneError as exc:
        print(exc.render(), file=sys.stderr)
        return 1
    if not write:
        sys.stdout.write(text)
        return 0
    target = scene_path(path)
    original = target.read_text(encoding="utf-8")
    if original != text:
        mode = file_mode(target)
        write_atomic(target.with_name(target.name + ".bak"), original, mode)
        write_atomic(target, text, mode)
    return 0


def save_state(engine: Engine, path: Path) -> None:
    """Write the running simulation as a scene file that continues where it stopped."""
    from engine.scene import write_state

    config_dir = engine.config.content_dir
    if config_dir is not None and path.resolve() == (config_dir / "main.scene").resolve():
        raise OSError(f"{path}: refusing to overwrite the scene being run; choose another file")
    write_atomic(path, write_state(engine, path))
