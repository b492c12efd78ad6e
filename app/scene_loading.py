"""What the CLI does with scene files: load into an engine, check, format, save state.

Kept apart from :mod:`engine.scene` (the format itself) so the format has no
knowledge of command lines, exit codes or terminals.
"""

from __future__ import annotations

import copy
import re
import sys
import time
from collections.abc import Collection, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from engine.content import Content
from engine.files import file_mode, write_atomic
from engine.scene.diagnostics import MAX_PER_FILE, Loc
from engine.scene.skipping import broken_parts, described, skip

if TYPE_CHECKING:
    from engine.app import Engine, EngineConfig
    from engine.scene import SceneSpec

#: Parts a run skips at most before it gives up on the scene (a file that is mostly wrong
#: is better fixed than run).
MAX_SKIPPED = 1000


class SceneLoadError(Exception):
    """The scene has errors; ``str()`` is the full report, every error with its place."""


@dataclass(slots=True)
class LoadedScene:
    spec: SceneSpec
    #: The content folder the scene runs in (a saved state's ``Content``, else its folder).
    content: Content
    #: Errors in the content told while loading (broken parts skipped, objects whose files
    #: could not be used): a run goes on without those parts and exits 1 at the end.
    errors: int = 0

    def configure(self, config: EngineConfig, backend: str | None = None,
                  dt: float | None = None) -> None:
        """Apply the scene's World settings; command-line flags win over the file. The
        components the scene makes are named too: a feature's plugin waits for its first
        one where the scene has none (systems.FEATURES)."""
        config.backend = backend or self.spec.backend
        config.dt = dt or self.spec.time_step
        config.max_dt = max(config.max_dt, config.dt)
        config.world = self.spec.world
        config.options["components"] = frozenset(
            type(c).__name__ for entity in self.spec.entities for c in entity.components)

    def instantiate(self, engine: Engine) -> None:
        from engine.scene import instantiate

        instantiate(engine, self.spec)


def load_content_scene(content: Content, seed: int = 0,
                       params: dict[str, str] | None = None,
                       allow: Iterable[Path] = (), skip_broken: bool = False) -> LoadedScene:
    """The content's scene, built; its ``systems/*.py`` are imported first, so asset
    loaders they register read the scene's files. A saved state runs in the content
    folder it names (``Content``). ``params`` set scene variables (``--param``). Files it
    names lie in that folder or one of ``allow`` (``--allow-path``). With ``skip_broken``
    (``colosseum run``) the errors are printed and the parts they lie in left out
    (engine.scene.skipping); without it they raise SceneLoadError."""
    from engine.content import ContentError
    from engine.scene import SceneError
    from engine.scene.diagnostics import Reporter
    from engine.scene.params import ParamError

    skipped: dict[Loc, str] = {}
    told: list[SceneError] = []
    while True:
        try:
            content, spec = _build(content, np.random.default_rng(seed), params, allow,
                                   skipped)
            break
        except (ContentError, ParamError) as exc:
            raise SceneLoadError(str(exc)) from exc
        except SceneError as exc:
            parts = broken_parts(exc.db, exc.places) if skip_broken and exc.db else []
            fresh = [p for p in parts if p.loc not in skipped]
            if not fresh or len(skipped) + len(fresh) > MAX_SKIPPED:
                why = [] if not fresh else [
                    f"colosseum: not run: more than {MAX_SKIPPED} broken parts of the scene "
                    f"({len(skipped) + len(fresh)}); colosseum check lists the errors"]
                raise SceneLoadError("\n".join([*(e.render() for e in told), exc.render(),
                                                 *why])) from exc
            told.append(exc)
            skipped.update((p.loc, described(p)) for p in fresh)
    for exc in told:
        print(exc.render(), file=sys.stderr)
    if skipped:
        listed = sorted(skipped)
        parts = "".join(f"\n  {skipped[loc]}" for loc in listed[:MAX_PER_FILE])
        if len(listed) > MAX_PER_FILE:
            parts += f"\n  and {len(listed) - MAX_PER_FILE} more"
        print(f"colosseum: the run goes on without {len(skipped)} broken part(s) of the "
              f"scene (the errors above; colosseum check lists them):{parts}",
              file=sys.stderr)
    errors = max(sum(len(exc.places) for exc in told), len(skipped))
    if spec.db is not None:  # warnings, and assets that failed (what they left out)
        for said in Reporter([*spec.db.warnings, *spec.problems]).diagnostics:
            print(said.render(spec.db.sources.get(said.path)), file=sys.stderr)
            errors += said.is_error
    return LoadedScene(spec, content, errors)


def content_engine(path: str | Path, seed: int = 0) -> Engine:
    """An engine running ``path`` (a content folder or scene file, a saved state too) as
    ``colosseum run PATH --fast --headless`` sets it up: the scene's World settings, the
    default plugins, the folder's ``systems/``, the scene loaded. Raises SceneLoadError
    (the scene's mistakes) or ContentError (a path that is no content)."""
    from engine.app import EngineConfig
    from engine.content import load_systems, resolve
    from systems import create_engine

    scene = load_content_scene(resolve(path), seed)
    config = EngineConfig(content_dir=scene.content.folder, seed=seed, fast=True,
                          headless=True)
    scene.configure(config)
    engine = create_engine(config)
    load_systems(engine, scene.content.folder)
    scene.instantiate(engine)
    return engine


class SceneWatcher:
    """The files a built scene came from (scene texts, included files, model files its
    Model blocks import, every model, image and sound it read) and when each was last
    changed: :meth:`changed` tells which changed since (``colosseum run --watch``).

    A scene text ``colosseum import`` wrote (its ``.imported`` base beside it) depends on
    the model it came from as a ``Model { Import 1 }`` block does: :meth:`reimport` runs
    that import again when the model changed, merged as ``colosseum import`` merges it
    (the author's edits kept), so physics edited in the model arrives with its looks."""

    def __init__(self, spec: SceneSpec) -> None:
        texts = {Path(p) for p in (spec.db.sources if spec.db is not None else ())}
        files = set(texts)
        if spec.assets is not None:
            files |= set(spec.assets.loads)
        if spec.db is not None:
            files |= {spec.content_dir / file for file in _model_files(spec.db.root.entries)
                      if spec.content_dir is not None}
        #: model file -> the scene texts imported from it
        self.imports: dict[Path, list[Path]] = {}
        for text in texts:
            model = imported_from(text)
            if model is not None:
                self.imports.setdefault(model, []).append(text.resolve())
        files |= set(self.imports)
        self.stamps = {f.resolve(): _stamp(f) for f in files if f.is_file()}
        self._looked = time.monotonic()

    def changed(self) -> list[Path]:
        return [f for f, stamp in self.stamps.items() if _stamp(f) != stamp]

    def poll(self, engine: object = None, interval: float = 0.5) -> bool:
        """Whether a file changed, looking at most every ``interval`` wall seconds (an
        ``until`` for ``Engine.run``)."""
        now = time.monotonic()
        if now - self._looked < interval:
            return False
        self._looked = now
        return bool(self.changed())

    def reimport(self) -> list[Path]:
        """Import each changed model again into the scene texts imported from it (merged,
        as ``colosseum import MODEL -o SCENE``); the scene texts rewritten. What the import
        leaves out is told on stderr, as the command tells it."""
        rewritten = []
        changed = set(self.changed())
        for model, scenes in self.imports.items():
            if model.resolve() not in changed:
                continue
            for scene in scenes:
                before = _stamp(scene)
                import_path(model, scene)
                if _stamp(scene) != before:
                    rewritten.append(scene)
        return rewritten


#: The first line ``colosseum import`` writes (model.py's header): the model's name.
_IMPORTED_FROM = re.compile(r"^// Imported from (.+) \((?:glTF|Collada); read: .*\) by "
                            r"colosseum import\.$")


def imported_from(scene: Path) -> Path | None:
    """The model a scene text was imported from, when ``colosseum import`` wrote it and
    keeps its base (``SCENE.imported``, whose first line names the model relative to the
    scene's folder) and the model is there; else None."""
    from engine.interchange.merge import BASE_SUFFIX

    base = scene.with_name(scene.name + BASE_SUFFIX)
    try:
        with base.open(encoding="utf-8") as f:
            first = f.readline().rstrip("\n")
    except (OSError, UnicodeDecodeError):
        return None
    found = _IMPORTED_FROM.match(first)
    if found is None:
        return None
    model = (scene.parent / found.group(1)).resolve()
    return model if model.is_file() else None

def _model_files(entries: list) -> list[str]:
    """The files of every ``Model`` block, included files' too (not spliced away)."""
    found = []
    for e in entries:
        if e.key == "Model" and e.value.kind == "STRUCTURE":
            file = e.value.data.get("File")
            if isinstance(file, str):
                found.append(file)
        elif e.key == "Include" and e.included is not None:
            found += _model_files(e.included.entries)
    return found


def _stamp(path: Path) -> tuple[int, int] | None:
    try:
        info = path.stat()
    except OSError:
        return None
    return info.st_mtime_ns, info.st_size


def _build(content: Content, rng: np.random.Generator | None, params: dict[str, str] | None = None,
           allow: Iterable[Path] = (), skipped: Collection[Loc] = ()
           ) -> tuple[Content, SceneSpec]:
    """Parse, leave out the parts at ``skipped``, find the content folder, import its
    systems, check and build. Raises SceneError (the scene's mistakes; its ``db`` the
    scene as parsed when it parsed), ContentError (its systems') or ParamError."""
    from engine.content import import_systems
    from engine.scene import SceneError, build_specs, parse_file, parse_text, validated
    from engine.scene.loader import content_folder
    from engine.scene.params import with_params

    db = parse_text(with_params(content.scene, params), str(content.scene), rng,
                    allow=allow) if params else parse_file(content.scene, rng, allow=allow)
    skip(db, skipped)
    parsed = copy.copy(db)  # the top-level parts as parsed, before Model blocks expand
    parsed.root = copy.copy(db.root)
    parsed.root.entries = list(db.root.entries)
    content = Content(content_folder(db), content.scene)
    import_systems(content.folder)
    try:
        spec = build_specs(validated(db, content.folder, allow=allow), content.folder)
    except SceneError as exc:
        exc.db = parsed
        raise
    return content, spec


def check_path(path: Path, output: str = "text", allow: Iterable[Path] = ()) -> int:
    """Report every diagnostic of a scene; the exit code says how it went.

    ``output`` "text": ``path:line:col: severity: message`` with the line and a caret,
    then the counts, on stderr. "json": one JSON object on stdout (``errors`` and
    ``warnings``, all counted; ``diagnostics``, those shown: objects with ``path line
    col severity message``) for editors and CI. Exit codes: 0 no errors (warnings
    allowed), 1 errors, 2 no such file or folder. Files the scene names must lie in its
    content folder or one of ``allow`` (``--allow-path``), as for a run.
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
        content, spec = _build(resolve(path), None, allow=allow)  # the parser's seed-0 rng
        assert spec.db is not None
        report = Report(Reporter([*spec.db.warnings, *spec.problems,
                                  *shader_diagnostics(spec, content.folder)]).diagnostics,
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


def shader_diagnostics(spec: SceneSpec, folder: Path) -> list:
    """Warnings, from the GLSL source alone (no GPU), about what a run that draws would
    warn about: uniforms of a program that nothing sets, vertex inputs the engine never
    feeds (:func:`services.render.shaders.unset_in_source`), at the shader file's line."""
    if not spec.shader_programs:  # the renderer's modules only for a scene with shaders
        return []
    from engine.scene import Diagnostic
    from engine.scene.diagnostics import WARNING
    from services.render.glsl import DEFAULT_USER_VERTEX
    from services.render.shaders import unset_in_source

    found = []
    for program_id, program in spec.shader_programs.items():
        if not program.enabled or program.fragment is None:
            continue
        stages = []
        for kind, file in (("vertex", program.vertex), ("fragment", program.fragment)):
            if file is None:
                stages.append((kind, "<default vertex stage>", DEFAULT_USER_VERTEX))
                continue
            try:
                stages.append((kind, str(file), (folder / file).read_text(encoding="utf-8")))
            except (OSError, UnicodeDecodeError):
                break  # the scene's check tells a shader file it cannot read
        else:
            given = {name for state in spec.shader_states.values()
                     if state.program == program_id for name in state.uniforms}
            for file, line, message in unset_in_source(str(program_id), stages, given):
                found.append(Diagnostic(file, line, 1, WARNING, message))
    return found


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


def import_path(model: Path, out: Path | None, force: bool = False) -> int:
    """``colosseum import``: the model's scene blocks written to ``out`` (stdout when
    None). An existing ``out`` is merged with the new import, keeping the author's edits
    (:mod:`engine.interchange.merge`); one no import wrote is replaced only with
    ``force`` (keeping a ``.bak``). 1 when parts of the model were left out."""
    import os

    from engine.assets import AssetError, Assets
    from engine.interchange import FORMATS, import_model
    from engine.scene import SceneError, render_all, write

    if not model.is_file():
        print(f"colosseum: error: {model}: no such file", file=sys.stderr)
        return 2
    if model.suffix.lower() not in FORMATS:
        print(f"colosseum: error: {model}: not a model to import (expected "
              f"{', '.join(FORMATS)})", file=sys.stderr)
        return 2
    folder = Path.cwd() if out is None else out.parent.resolve()
    if out is not None:
        placed = _import_target(model, out, folder, force)
        if isinstance(placed, int):
            return placed
        model = placed
    file_ref = Path(os.path.relpath(model.resolve(), folder)).as_posix()
    try:
        imported = import_model(file_ref, file_ref, Assets(folder), root=folder, header=True)
    except AssetError as exc:
        print(f"colosseum: error: {exc.message}", file=sys.stderr)
        return 1
    except SceneError as exc:
        print(exc.render(), file=sys.stderr)
        return 1
    text = write(imported.db)
    if imported.problems:
        print(render_all(imported.problems, imported.db.sources), file=sys.stderr)
    failed = 1 if any(d.is_error for d in imported.problems) else 0
    if out is None:
        sys.stdout.write(text)
        return failed
    return _write_import(model, out, text, force) or failed


def _import_target(model: Path, out: Path, folder: Path, force: bool) -> Path | int:
    """Make ``out``'s folder and bring the model into it (confinement); an exit code when
    that fails or ``out`` is not an import's to replace."""
    from engine.interchange.merge import BASE_SUFFIX

    try:  # `import MODEL -o my_sim/main.scene` makes the content folder my_sim
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f"colosseum: error: {out}: cannot make folder {out.parent} "
              f"({exc.strerror or exc})", file=sys.stderr)
        return 2
    base_path = out.with_name(out.name + BASE_SUFFIX)
    if out.exists() and not force and not base_path.is_file():
        print(f"colosseum: error: {out} exists and no import wrote it (there is no "
              f"{base_path.name}); nothing is overwritten: give --force to replace it "
              f"(a .bak is kept)", file=sys.stderr)
        return 1
    try:  # a model outside the scene's folder is copied in beside it (confinement)
        return bring_in(model, folder, replace=force or base_path.is_file())
    except OSError as exc:
        print(f"colosseum: error: {exc}", file=sys.stderr)
        return 1


def _write_import(model: Path, out: Path, text: str, force: bool) -> int:
    """Write the import to ``out``, merged with the author's edits since the last import
    (its base beside it), the former file kept as ``.bak``; 1 when they do not parse."""
    from engine.interchange.merge import BASE_SUFFIX, merge
    from engine.scene import SceneError, parse_file, parse_text, write

    base_path = out.with_name(out.name + BASE_SUFFIX)
    text_out = text
    if out.exists() and not force:
        try:
            result = merge(parse_file(base_path), parse_file(out), parse_text(text, str(out)))
        except SceneError as exc:
            print(exc.render(), file=sys.stderr)
            print(f"colosseum: error: {out} (or {base_path.name}) does not parse; nothing is "
                  f"overwritten", file=sys.stderr)
            return 1
        text_out = write(result.db)
        for note in result.kept:
            print(f"{out}: kept: {note}", file=sys.stderr)
        print(f"{out}: {result.added} added, {result.updated} updated, {result.removed} "
              f"removed from {model.name}", file=sys.stderr)
    original = out.read_text(encoding="utf-8") if out.exists() else None
    if original is not None and original != text_out:
        out.with_name(out.name + ".bak").write_text(original, encoding="utf-8")
    write_atomic(out, text_out)
    write_atomic(base_path, text)
    return 0


def model_files(model: Path) -> list[Path]:
    """The files a model is made of, relative to its folder: itself and, for a ``.gltf``,
    the buffers and images its ``uri``s name beside or below it (not ``data:`` URIs)."""
    import json
    from urllib.parse import unquote

    files = [Path(model.name)]
    if model.suffix.lower() != ".gltf":
        return files
    try:
        document = json.loads(model.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return files  # the import tells what is wrong with it
    for kind in ("buffers", "images"):
        for item in document.get(kind) or ():
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:") or "://" in uri:
                continue
            name = Path(unquote(uri))
            if not name.is_absolute() and ".." not in name.parts and \
                    (model.parent / name).is_file():
                files.append(name)
    return files


def bring_in(model: Path, folder: Path, replace: bool = False) -> Path:
    """``model`` as a file inside ``folder``: itself when it lies there already, else a
    copy beside the scene (``folder/NAME``, a glTF's buffers and images with it), since a
    scene may name only files in its content folder. A different file of that name is
    replaced only when ``replace`` (an earlier import's copy, or ``--force``); else
    OSError."""
    import shutil

    source = model.resolve()
    if source.is_relative_to(folder.resolve()):
        return model
    target = folder / model.name
    for name in model_files(model):
        src, dst = model.parent / name, folder / name
        if dst.exists() and not replace and dst.read_bytes() != src.read_bytes():
            raise OSError(f"{dst} exists and is not {src}; nothing is overwritten: give "
                          f"--force to replace it with a copy of the model")
    for name in model_files(model):
        dst = folder / name
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(model.parent / name, dst)
    print(f"colosseum: copied {model} into {folder} (a scene names only files in its "
          f"content folder); import {model} -o again to bring in its changes",
          file=sys.stderr)
    return target


def export_path(scene: Path, out: Path) -> int:
    """``colosseum export``: a scene file or content folder (a saved state too) as glTF with
    physics extensions; what glTF cannot say is told."""
    from engine.content import ContentError, resolve
    from engine.scene import render_all
    from services.export import export_gltf

    if out.suffix.lower() not in (".glb", ".gltf"):
        print(f"colosseum: error: {out}: the output must end in .glb or .gltf", file=sys.stderr)
        return 2
    if not out.parent.is_dir():
        print(f"colosseum: error: {out}: folder {out.parent} does not exist", file=sys.stderr)
        return 2
    try:
        loaded = load_content_scene(resolve(str(scene)))
    except (ContentError, SceneLoadError) as exc:
        print(exc, file=sys.stderr)
        return 1
    told = export_gltf(loaded.spec, out)
    if told:
        print(render_all(told), file=sys.stderr)
    print(f"wrote {out}", file=sys.stderr)
    return 0
