"""User shader programs: the scene format's VertexShader, FragmentShader, ShaderProgram and
ShaderState (paper Listings 3 and 4), compiled with clear errors and a safe fallback.

The scene factory fills a :class:`ShaderLibrary` of plain declarations; the renderer compiles
it with a :class:`ShaderManager`. A shader that does not compile or link is reported as
``file:line:col: error: message`` (from the driver's log) and every object using it is drawn
with the default material instead. Uniforms are changed at run time with
:meth:`ShaderManager.set_uniform` (the Lua API calls it).

Shaders may be modern GLSL (``#version 330`` or later, declaring the engine inputs listed in
:mod:`services.render.glsl`) or fixed-function-era GLSL (no ``#version``, using ``gl_Vertex``,
``gl_NormalMatrix``, ``ftransform()``, ``gl_FragColor``, ``gl_LightSource[i]``...), which is
mapped onto the engine's inputs so shaders written for the paper's OpenSceneGraph work.
"""

from __future__ import annotations

import difflib
import logging
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from services.render import glsl

log = logging.getLogger("colosseum.render")

UniformValue = float | int | bool | tuple[float, ...] | list[float]


@dataclass(slots=True)
class VertexShader:
    """``VertexShader { ID "toon_vertex" File "shaders/toon.vert" }``.

    ``file`` is resolved against the content folder; ``source`` (inline GLSL) wins over it.
    ``origin`` is where the declaration sits (``main.scene:12:3``), for error messages.
    """

    id: str
    file: str | None = None
    source: str | None = None
    origin: str = ""


@dataclass(slots=True)
class FragmentShader:
    """``FragmentShader { ID "toon_fragment" File "shaders/toon.frag" }``."""

    id: str
    file: str | None = None
    source: str | None = None
    origin: str = ""


@dataclass(slots=True)
class ShaderProgram:
    """``ShaderProgram { ID "toon" VertexShader "toon_vertex" FragmentShader "..." Enable 1 }``.

    A missing ``vertex_shader`` uses the engine's default vertex stage; a disabled program
    draws its objects with the default material.
    """

    id: str
    vertex_shader: str | None = None
    fragment_shader: str | None = None
    enable: bool = True
    origin: str = ""


@dataclass(slots=True)
class Uniform:
    """``Uniform { ID "DiffuseColor" Value [0 0.25 1] }``."""

    id: str
    value: UniformValue = 0.0


@dataclass(slots=True)
class ShaderState:
    """``ShaderState { ID "toon" ShaderProgram "toon" Uniform {...} ... }``: a program plus
    the values of its uniforms; objects reference it with ``VisualAttributes { ShaderState }``.
    """

    id: str
    program: str
    uniforms: list[Uniform] = field(default_factory=list)
    origin: str = ""


@dataclass(slots=True)
class ShaderLibrary:
    """All shader declarations of a scene; the factory inserts it as an engine resource."""

    vertex_shaders: list[VertexShader] = field(default_factory=list)
    fragment_shaders: list[FragmentShader] = field(default_factory=list)
    programs: list[ShaderProgram] = field(default_factory=list)
    states: list[ShaderState] = field(default_factory=list)


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One problem in a shader, at a place in a file."""

    file: str
    line: int
    col: int
    message: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: error: {self.message}"


class ShaderError(Exception):
    """A shader that cannot be used; ``diagnostics`` has file:line:col for each problem."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        self.diagnostics = diagnostics
        super().__init__("\n".join(str(d) for d in diagnostics))


# Driver log formats: Mesa "0:12(5): error: msg", NVIDIA "0(12) : error C0000: msg",
# AMD/Intel "ERROR: 0:12: msg".
_LOG_PATTERNS = (
    re.compile(r"^\s*\d+:(?P<line>\d+)\((?P<col>\d+)\):\s*(?:error|warning):\s*(?P<msg>.*)$"),
    re.compile(r"^\s*\d+\((?P<line>\d+)\)\s*:\s*error\s*(?P<msg>.*)$"),
    re.compile(r"^\s*ERROR:\s*\d+:(?P<line>\d+):\s*(?P<msg>.*)$"),
)
_VERSION = re.compile(r"^\s*#\s*version\s+(\d+)(.*)$", re.MULTILINE)


def parse_driver_log(log_text: str, files: dict[str, str]) -> list[Diagnostic]:
    """Diagnostics from a moderngl compile/link error, attributed to the failing stage's file.

    ``files`` maps moderngl's stage names (``vertex_shader``, ``fragment_shader``) to paths.
    """
    stage = None
    out: list[Diagnostic] = []
    for raw in log_text.splitlines():
        line = raw.strip()
        if line in files:
            stage = line
            continue
        if not line or set(line) == {"="}:
            continue
        for pattern in _LOG_PATTERNS:
            m = pattern.match(line)
            if m:
                col = int(m.groupdict().get("col") or 0)
                out.append(Diagnostic(files.get(stage or "", "?"), int(m["line"]), col,
                                      m["msg"].strip()))
                break
    if not out:  # a link error or an unknown log format: keep the whole text
        text = " ".join(x.strip() for x in log_text.splitlines() if x.strip())
        names = " + ".join(files.values())
        out.append(Diagnostic(names, 0, 0, text))
    return out


def is_legacy(source: str) -> bool:
    """True for fixed-function-era GLSL: no ``#version``, or a version below 330."""
    m = _VERSION.search(source)
    return m is None or int(m.group(1)) < 330 or "compatibility" in m.group(2)


def _strip_version(source: str) -> str:
    """Blank out the ``#version`` line, keeping line numbers."""
    return _VERSION.sub("", source, count=1)


def prepare_vertex(source: str) -> str:
    """Vertex source ready for a core 3.3 context (legacy built-ins mapped, lines kept)."""
    if not is_legacy(source):
        return source
    return (glsl.LEGACY_VERTEX_PRELUDE + "#line 1\n" + _strip_version(source)
            + "\n" + glsl.LEGACY_VERTEX_EPILOGUE)


def prepare_fragment(source: str) -> str:
    """Fragment source ready for a core 3.3 context (legacy built-ins mapped, lines kept)."""
    if not is_legacy(source):
        return source
    return glsl.LEGACY_FRAGMENT_PRELUDE + "#line 1\n" + _strip_version(source)


def compile_program(ctx: Any, vertex: str, fragment: str, vertex_name: str,
                    fragment_name: str) -> Any:
    """A moderngl Program, or :class:`ShaderError` with file:line:col from the driver log."""
    import moderngl

    try:
        return ctx.program(vertex_shader=prepare_vertex(vertex),
                           fragment_shader=prepare_fragment(fragment))
    except moderngl.Error as exc:
        raise ShaderError(parse_driver_log(
            str(exc), {"vertex_shader": vertex_name, "fragment_shader": fragment_name})) from exc


def _as_uniform_value(value: UniformValue) -> Any:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, int | float):
        return value
    values = tuple(float(v) for v in value)
    return values[0] if len(values) == 1 else values


def write_uniform(program: Any, name: str, value: UniformValue) -> bool:
    """Set a uniform if the program has it (compilers drop unused ones); False if it has not."""
    member = program.get(name, None)
    if member is None or not hasattr(member, "value"):
        return False
    value = _as_uniform_value(value)
    dims = getattr(member, "dimension", 1)
    given = len(value) if isinstance(value, tuple) else 1
    if given != dims and getattr(member, "array_length", 1) == 1:
        raise ValueError(f"uniform {name!r} takes {dims} values, got {given}")
    if getattr(member, "fmt", "f").endswith("i") and not isinstance(value, tuple):
        value = int(value)
    member.value = value
    return True


#: Per-object matrix uniforms a simple (non-instanced) shader may use instead of ``i_model``;
#: objects drawn with such a program get one draw call each.
PER_OBJECT_UNIFORMS = tuple(glsl.PER_OBJECT_UNIFORMS)
#: Uniforms no user value is needed for: the engine's, and GLSL's own.
_SUPPLIED = frozenset(glsl.ENGINE_UNIFORMS) | frozenset(glsl.PER_OBJECT_UNIFORMS)
#: A uniform's declaration: at a line's start or after another statement on its line
#: (``in vec3 p; uniform mat4 m;``), its first name (``uniform mat4 a, b;``: ``a``).
_DECLARED = re.compile(r"(?:^|;)[ \t]*uniform\s+(?:(?:lowp|mediump|highp)\s+)?\w+\s+(\w+)",
                       re.MULTILINE)


#: A line or block comment of GLSL.
_COMMENT = re.compile(r"//[^\n]*|/\*.*?\*/", re.DOTALL)
#: A declaration at a line's start or after another statement: ``uniform mat4 a, b[2];``
#: and ``in vec3 p;`` (``layout(...)`` and precision qualifiers allowed); not a block.
_DECLARATION = re.compile(
    r"(?:^|;)[ \t]*(?:layout\s*\([^)]*\)\s*)?(uniform|in|attribute)\s+"
    r"(?:(?:lowp|mediump|highp|flat|smooth|noperspective)\s+)*(\w+)\s+([\w\s,\[\]]+);",
    re.MULTILINE)


def _uncommented(source: str) -> str:
    """``source`` with its comments blanked (newlines kept, so lines still count)."""
    return _COMMENT.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), source)


def unset_message(name: str, program_id: str) -> str:
    """What is wrong with a uniform ``name`` a program uses that nothing sets (the run-time
    warning and ``colosseum check`` say the same)."""
    close = difflib.get_close_matches(name, sorted(_SUPPLIED), n=1, cutoff=0.5)
    hint = f"; did you mean {close[0]!r}, which the engine supplies?" if close else ""
    return (f"uniform {name!r} of program {program_id!r} is never set: the engine does not "
            f"supply it and no ShaderState gives it a value, so it stays 0 (a zero matrix "
            f"draws nothing; a script's setUniform is the only other way){hint}")


def unset_in_source(program_id: str, stages: list[tuple[str, str, str]],
                    given: set[str]) -> list[tuple[str, int, str]]:
    """What :meth:`ShaderManager` warns about when it draws, found from the GLSL source
    alone (no GPU: ``colosseum check``): the uniforms a program declares and uses that
    neither the engine nor its ShaderStates (``given``) set, and the vertex stage's inputs
    the engine never feeds (it gives :data:`glsl.VERTEX_INPUTS` and
    :data:`glsl.INSTANCE_INPUTS`). ``stages`` are (kind "vertex"/"fragment", file name,
    source); the result is (file, line, message) per problem, in file order. A name that
    is declared but never used is left alone, as the compiler drops it."""
    inputs = {**glsl.VERTEX_INPUTS, **glsl.INSTANCE_INPUTS}
    texts = [(kind, file, _uncommented(source)) for kind, file, source in stages]
    uses: dict[str, int] = {}
    for _, _, text in texts:
        for word in re.findall(r"\b\w+\b", text):
            uses[word] = uses.get(word, 0) + 1
    found: list[tuple[str, int, str]] = []
    told: set[str] = set()
    for kind, file, text in texts:
        for m in _DECLARATION.finditer(text):
            qualifier, names = m.group(1), m.group(3)
            line = text.count("\n", 0, m.start(3)) + 1
            for name in (n.split("[")[0].strip() for n in names.split(",")):
                if not name or name in told:
                    continue
                declared = len(re.findall(rf"\b{name}\b", m.group(0)))
                if uses.get(name, 0) <= declared:  # declared only: the compiler drops it
                    continue
                if qualifier == "uniform":
                    if name.startswith(("gl_", "c_")) or name in _SUPPLIED or name in given:
                        continue
                    told.add(name)
                    found.append((file, line, unset_message(name, program_id)))
                elif kind == "vertex" and qualifier in ("in", "attribute") and \
                        not is_legacy(stages[[s[1] for s in stages].index(file)][2]) and \
                        name not in inputs:
                    told.add(name)
                    close = difflib.get_close_matches(name, sorted(inputs), n=1, cutoff=0.5)
                    hint = f"; did you mean {close[0]!r}?" if close else ""
                    found.append((file, line, (
                        f"vertex input {name!r} of program {program_id!r} is never set: the "
                        f"engine feeds only {', '.join(inputs)}, so it reads 0{hint}")))
    return found


@dataclass(slots=True)
class CompiledState:
    """A shader state ready to draw with: its program and current uniform values."""

    id: str
    program_id: str
    program: Any
    uniforms: dict[str, UniformValue]
    per_object: bool = False


class ShaderManager:
    """Compiles a :class:`ShaderLibrary` and keeps each state's uniforms, settable at run time.

    Problems never raise out of :meth:`load`: they are logged and kept in :attr:`errors`, and
    :meth:`state` returns None for a state that must fall back to the default material.
    """

    def __init__(self, ctx: Any, root: str | Path = ".") -> None:
        self.ctx = ctx
        self.root = Path(root)
        self.errors: list[str] = []
        self._states: dict[str, CompiledState | None] = {}
        self._uniforms: dict[str, dict[str, UniformValue]] = {}
        self._programs: dict[str, Any] = {}
        #: Program ID -> its stages' (file name, source), for messages about them.
        self._sources: dict[str, tuple[tuple[str, str], ...]] = {}

    def _read(self, decl: VertexShader | FragmentShader) -> tuple[str, str]:
        if decl.source is not None:
            return decl.source, decl.file or f"<{decl.id}>"
        if not decl.file:
            raise ShaderError([Diagnostic(decl.origin or f"<{decl.id}>", 0, 0,
                                          f"shader {decl.id!r} names no File")])
        path = self.root / decl.file
        try:
            return path.read_text(), str(path)
        except OSError as exc:
            where = decl.origin or str(path)
            raise ShaderError([Diagnostic(where, 0, 0, f"cannot read shader file {path}: "
                                          f"{exc.strerror or exc}")]) from exc

    def _report(self, message: str) -> None:
        self.errors.append(message)
        log.error("%s", message)

    def load(self, library: ShaderLibrary) -> None:
        """Compile every enabled program and prepare every state (errors are recorded)."""
        vertex = {v.id: v for v in library.vertex_shaders}
        fragment = {f.id: f for f in library.fragment_shaders}
        for decl in library.programs:
            if not decl.enable:
                continue
            try:
                self._programs[decl.id] = self._build(decl, vertex, fragment)
            except ShaderError as exc:
                self._report(f"{exc}\n  (program {decl.id!r} falls back to the default material)")
        programs = {p.id: p for p in library.programs}
        for state in library.states:
            self._uniforms[state.id] = {u.id: u.value for u in state.uniforms}
            prog = self._programs.get(state.program)
            if prog is None:
                if state.program not in programs:
                    hint = _did_you_mean(state.program, programs)
                    self._report(f"{state.origin or state.id}: error: shader state {state.id!r} "
                                 f"names unknown ShaderProgram {state.program!r}{hint}")
                self._states[state.id] = None
                continue
            per_object = any(prog.get(n, None) is not None for n in PER_OBJECT_UNIFORMS)
            compiled = CompiledState(state.id, state.program, prog, self._uniforms[state.id],
                                     per_object)
            for name in compiled.uniforms:
                if prog.get(name, None) is None:
                    log.warning("%s: shader state %r sets uniform %r that program %r does not use",
                                state.origin or state.id, state.id, name, state.program)
            self._states[state.id] = compiled
        for program_id in self._programs:
            self._warn_unset(program_id, [s for s in library.states if s.program == program_id])

    def _warn_unset(self, program_id: str, states: list[ShaderState]) -> None:
        """Warn once per uniform a program uses that nothing sets: not the engine (see
        :data:`glsl.ENGINE_UNIFORMS`), not its shader states. It stays 0, and a matrix of
        zeros draws nothing: the object silently disappears otherwise."""
        program = self._programs[program_id]
        given = {u.id for state in states for u in state.uniforms}
        for name in program:
            member = program.get(name, None)
            if not hasattr(member, "value") or name.startswith(("gl_", "c_")) or \
                    name in _SUPPLIED or name in given or name.split("[")[0] in _SUPPLIED:
                continue
            where = next((f"{file}:{source.count(chr(10), 0, m.start()) + 1}"
                          for file, source in self._sources[program_id]
                          for m in _DECLARED.finditer(source) if m.group(1) == name),
                         self._sources[program_id][-1][0])
            log.warning("%s: %s", where, unset_message(name, program_id))

    def _build(self, decl: ShaderProgram, vertex: dict[str, VertexShader],
               fragment: dict[str, FragmentShader]) -> Any:
        where = decl.origin or decl.id
        if decl.fragment_shader is None:
            raise ShaderError([Diagnostic(where, 0, 0,
                                          f"program {decl.id!r} names no FragmentShader")])
        if decl.fragment_shader not in fragment:
            raise ShaderError([Diagnostic(where, 0, 0, f"unknown FragmentShader "
                                          f"{decl.fragment_shader!r}"
                                          f"{_did_you_mean(decl.fragment_shader, fragment)}")])
        fs, fs_name = self._read(fragment[decl.fragment_shader])
        stages: tuple[tuple[str, str], ...] = ((fs_name, fs),)
        if decl.vertex_shader is None:
            vs, vs_name = glsl.DEFAULT_USER_VERTEX, "<default vertex stage>"
        elif decl.vertex_shader not in vertex:
            raise ShaderError([Diagnostic(where, 0, 0, f"unknown VertexShader "
                                          f"{decl.vertex_shader!r}"
                                          f"{_did_you_mean(decl.vertex_shader, vertex)}")])
        else:
            vs, vs_name = self._read(vertex[decl.vertex_shader])
            stages = ((vs_name, vs), *stages)
        self._sources[decl.id] = stages
        return compile_program(self.ctx, vs, fs, vs_name, fs_name)

    def has_state(self, state_id: str) -> bool:
        return state_id in self._states

    def state(self, state_id: str) -> CompiledState | None:
        """The compiled state, or None when its objects must use the default material."""
        return self._states.get(state_id)

    def set_uniform(self, state_id: str, name: str, value: UniformValue) -> None:
        """Change a uniform of a shader state at run time (called from Lua).

        Raises KeyError for an unknown state and ValueError for a uniform its program does not
        have; the new value shows from the next frame.
        """
        if state_id not in self._uniforms:
            raise KeyError(f"unknown shader state {state_id!r}"
                           f"{_did_you_mean(state_id, self._uniforms)}")
        compiled = self._states.get(state_id)
        if compiled is not None and compiled.program.get(name, None) is None:
            names = [n for n in compiled.program if not n.startswith(("u_", "c_", "gl_"))]
            raise ValueError(f"shader state {state_id!r}: program {compiled.program_id!r} has no "
                             f"uniform {name!r}{_did_you_mean(name, names)}")
        if compiled is not None:
            write_uniform(compiled.program, name, value)  # validates the value's size now
        self._uniforms[state_id][name] = value

    def apply(self, compiled: CompiledState) -> None:
        """Write a state's uniform values into its program before drawing with it."""
        for name, value in compiled.uniforms.items():
            write_uniform(compiled.program, name, value)

    def release(self) -> None:
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()
        self._states.clear()


def _did_you_mean(name: str, choices: Any) -> str:
    close = difflib.get_close_matches(name, list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""
