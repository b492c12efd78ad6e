"""The README's "Running content" commands, run as written in a fresh temporary folder
(issue 31): each test starts from an empty folder, makes what the command needs the way a
new user would (``colosseum new``, a model in ``models/``, the bundled content copied in),
and runs the command line as the README prints it, with ``.venv/bin/colosseum`` being this
checkout's. Where a README line runs without a limit (the demo, a served scene) a
``--frames``/``--seconds`` limit is added; where it would take minutes (100 seeds of a
sweep) it runs fewer; the port of ``serve``/``join`` is a free one on 127.0.0.1. Each
change is named at its test.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "gltf-physics"
BIN = Path(sys.executable).parent / "colosseum"
#: No README command may take longer than this here (a hang fails, never blocks CI).
LIMIT_S = 120


def readme_commands() -> list[str]:
    """The command lines of the README's "Running content" block (README.md, or a page of
    docs/ it moved to: the block that scaffolds my_sim), without their comments."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    for page in pages:
        text = page.read_text(encoding="utf-8")
        for block in re.findall(r"```sh\n(.*?)```", text, re.DOTALL):
            if "colosseum new my_sim" in block and "colosseum import models/" in block:
                return [line.split("  #")[0].strip() for line in block.splitlines()
                        if line.startswith(".venv/bin/colosseum")]
    raise AssertionError("no page has the README's 'Running content' block")


#: Every README command line here, and the test that runs it.
COVERED = {
    ".venv/bin/colosseum run": "test_run_the_demo",
    ".venv/bin/colosseum run content/demo --mode threaded --seconds 5 --stats stats.json":
        "test_run_threaded_with_stats",
    ".venv/bin/colosseum run my_sim --backend pymunk": "test_new_check_fmt_run_export",
    ".venv/bin/colosseum new my_sim": "test_new_check_fmt_run_export",
    ".venv/bin/colosseum check my_sim": "test_new_check_fmt_run_export",
    ".venv/bin/colosseum check my_sim --format json": "test_new_check_fmt_run_export",
    ".venv/bin/colosseum fmt my_sim/main.scene": "test_new_check_fmt_run_export",
    ".venv/bin/colosseum keys Camera": "test_keys",
    ".venv/bin/colosseum import models/room.glb -o my_sim/main.scene":
        "test_import_into_a_new_folder_then_run",
    ".venv/bin/colosseum export my_sim -o my_sim.glb": "test_new_check_fmt_run_export",
    ".venv/bin/colosseum bench scheduler": "test_bench_scheduler",
    ".venv/bin/colosseum bench physics --json b.json --plot b.png": "test_bench_physics",
    ".venv/bin/colosseum score session.input": "test_score",
    ".venv/bin/colosseum serve content/multiuser": "test_serve_and_join",
    ".venv/bin/colosseum join tcp://127.0.0.1:5555 --user alice": "test_serve_and_join",
    ".venv/bin/colosseum sweep my_sim --param mass=1,2 --seeds 0..99 --frames 600 "
    "--out results": "test_sweep",
}


def test_every_readme_command_has_its_test() -> None:
    commands = readme_commands()
    missing = [c for c in commands if c not in COVERED]
    assert not missing, f"README commands no test runs: {missing}"
    assert set(COVERED) <= set(commands), (
        f"tested but no longer in the README: {sorted(set(COVERED) - set(commands))}")
    here = globals()
    assert all(name in here for name in COVERED.values())


def colosseum(line: str, cwd: Path, extra: str = "", expect: int | None = 0,
              timeout: float = LIMIT_S) -> subprocess.CompletedProcess[str]:
    """Run a command line as written in ``cwd`` (``extra`` appended), checking its exit
    code."""
    argv = shlex.split(line) + shlex.split(extra)
    assert argv[0] == ".venv/bin/colosseum"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    done = subprocess.run([str(BIN), *argv[1:]], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env=env)
    if expect is not None:
        assert done.returncode == expect, (
            f"{line} {extra}: exit {done.returncode}\n{done.stdout[-3000:]}"
            f"\n{done.stderr[-3000:]}")
    return done


@pytest.fixture
def fresh(tmp_path: Path) -> Path:
    folder = tmp_path / "fresh"
    folder.mkdir()
    return folder


def copy_content(name: str, into: Path) -> None:
    shutil.copytree(ROOT / "content" / name, into / "content" / name,
                    ignore=shutil.ignore_patterns("__pycache__"))


def saved_objects(scene: Path) -> list[str]:
    return re.findall(r'^Object \{\s*ID "([^"]+)"', scene.read_text(encoding="utf-8"),
                      re.MULTILINE)


def test_run_the_demo(fresh: Path) -> None:
    """The bundled demo runs from any folder (it runs until closed: 30 frames here)."""
    colosseum(".venv/bin/colosseum run", fresh, "--frames 30 --fast")


def test_run_threaded_with_stats(fresh: Path) -> None:
    copy_content("demo", fresh)
    colosseum(".venv/bin/colosseum run content/demo --mode threaded --seconds 5 "
              "--stats stats.json", fresh)
    stats = json.loads((fresh / "stats.json").read_text())
    assert stats["sim_seconds"] == pytest.approx(5, abs=0.1)


def test_new_check_fmt_run_export(fresh: Path) -> None:
    colosseum(".venv/bin/colosseum new my_sim", fresh)
    colosseum(".venv/bin/colosseum run my_sim --backend pymunk", fresh, "--frames 30 --fast")
    checked = colosseum(".venv/bin/colosseum check my_sim", fresh)
    assert "0 error(s)" in checked.stderr
    report = json.loads(colosseum(".venv/bin/colosseum check my_sim --format json",
                                  fresh).stdout)
    assert report["errors"] == 0
    text = colosseum(".venv/bin/colosseum fmt my_sim/main.scene", fresh).stdout
    assert 'ID "ball"' in text
    colosseum(".venv/bin/colosseum export my_sim -o my_sim.glb", fresh)
    assert (fresh / "my_sim.glb").read_bytes()[:4] == b"glTF"
    from tests.interchange import gltf_schema

    if gltf_schema.available():  # valid against the extensions' schemas
        assert gltf_schema.problems(fresh / "my_sim.glb") == []


def test_keys(fresh: Path) -> None:
    out = colosseum(".venv/bin/colosseum keys Camera", fresh).stdout
    assert "LookAt" in out


def _room(models: Path) -> Path:
    """models/room.glb: a room of bodies, joints and a ground, as Blender 4.4's physics
    add-on lays it out (app/bench/interchange_samples.py)."""
    from app.bench.interchange_samples import blender

    models.mkdir(parents=True, exist_ok=True)
    return blender(models / "room.glb")


def test_import_into_a_new_folder_then_run(fresh: Path) -> None:
    """``import -o my_sim/main.scene`` makes my_sim and copies the model in beside the scene
    (a scene names only files in its content folder), so ``run my_sim`` has every body."""
    _room(fresh / "models")
    done = colosseum(".venv/bin/colosseum import models/room.glb -o my_sim/main.scene", fresh)
    assert (fresh / "my_sim" / "room.glb").read_bytes() == \
        (fresh / "models" / "room.glb").read_bytes()
    scene = (fresh / "my_sim" / "main.scene").read_text()
    assert '"room.glb"' in scene and "../" not in scene, done.stderr
    imported = saved_objects(fresh / "my_sim" / "main.scene")
    assert imported
    # the folder alone, elsewhere, runs too: it carries its model
    shutil.copytree(fresh / "my_sim", fresh / "moved" / "my_sim")
    run = colosseum(".venv/bin/colosseum run my_sim", fresh, "--frames 20 --fast "
                    "--save-state state.scene")
    assert "error" not in run.stderr.lower(), run.stderr
    assert set(imported) <= set(saved_objects(fresh / "state.scene"))
    colosseum(".venv/bin/colosseum run my_sim", fresh / "moved", "--frames 5 --fast")
    # importing again (the model changed) merges, and takes the new copy
    again = colosseum(".venv/bin/colosseum import models/room.glb -o my_sim/main.scene",
                      fresh)
    assert "0 added" in again.stderr


@pytest.mark.parametrize("model", ["WaterWheel/WaterWheel.gltf"])
def test_import_a_gltf_with_its_buffers(fresh: Path, model: str) -> None:
    """A .gltf comes with its buffers and images: all are copied beside the scene."""
    source = SHARED / "khr" / model
    if not source.is_file():
        pytest.skip(f"{source} is not here (../shared/gltf-physics)")
    shutil.copytree(source.parent, fresh / "models")
    line = ".venv/bin/colosseum import models/room.glb -o my_sim/main.scene"
    argv = shlex.split(line.replace("models/room.glb", f"models/{source.name}"))
    done = subprocess.run([str(BIN), *argv[1:]], cwd=fresh, capture_output=True, text=True,
                          timeout=LIMIT_S)
    assert done.returncode == 0, done.stderr
    assert (fresh / "my_sim" / "WaterWheel.bin").is_file()
    run = subprocess.run([str(BIN), "run", "my_sim", "--frames", "5", "--fast"], cwd=fresh,
                         capture_output=True, text=True, timeout=LIMIT_S)
    assert run.returncode == 0, run.stderr[-3000:]


def test_bench_scheduler(fresh: Path) -> None:
    """With ``--quick`` (fewer sizes and steps): the full table takes half a minute."""
    out = colosseum(".venv/bin/colosseum bench scheduler", fresh, "--quick").stdout
    assert out.strip()


def test_bench_physics(fresh: Path) -> None:
    """With ``--quick``: the full benchmark takes over three minutes."""
    colosseum(".venv/bin/colosseum bench physics --json b.json --plot b.png", fresh,
              "--quick")
    assert json.loads((fresh / "b.json").read_text())
    assert (fresh / "b.png").read_bytes()[:4] == b"\x89PNG"


def test_score(fresh: Path) -> None:
    """A recorded session of the stroke simulator (which keeps a session log), scored."""
    copy_content("stroke", fresh)
    record = subprocess.run([str(BIN), "run", "content/stroke", "--frames", "30", "--fast",
                             "--record", "session.input"], cwd=fresh, capture_output=True,
                            text=True, timeout=LIMIT_S)
    assert record.returncode == 0, record.stderr[-3000:]
    out = colosseum(".venv/bin/colosseum score session.input", fresh).stdout
    assert "session log:" in out


def _free_port() -> int:
    while True:
        with socket.socket() as a:
            a.bind(("127.0.0.1", 0))
            port = a.getsockname()[1]
        with socket.socket() as b:  # PORT+1 is the control socket
            try:
                b.bind(("127.0.0.1", port + 1))
            except OSError:
                continue
        return port


@pytest.mark.parametrize("form", ["folder", "scene file"])
def test_serve_and_join(fresh: Path, form: str) -> None:
    """``serve`` and ``join`` take the same PATH: a content folder, or a .scene file."""
    copy_content("multiuser", fresh)
    port = _free_port()
    path = "content/multiuser" if form == "folder" else "content/multiuser/main.scene"
    serve = ".venv/bin/colosseum serve content/multiuser"
    join = ".venv/bin/colosseum join tcp://127.0.0.1:5555 --user alice"
    argv = shlex.split(serve.replace("content/multiuser", path))
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    server = subprocess.Popen([str(BIN), *argv[1:], "--bind", f"tcp://127.0.0.1:{port}",
                               "--seconds", "5"], cwd=fresh, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env=env)
    try:
        time.sleep(1.5)
        argv = shlex.split(join.replace("5555", f"{port} {path}")) + ["--frames", "30",
                                                                      "--headless"]
        node = subprocess.run([str(BIN), *argv[1:]], cwd=fresh, capture_output=True,
                              text=True, timeout=LIMIT_S, env=env)
        assert node.returncode == 0, node.stderr[-3000:]
        assert "joined" in node.stderr
    finally:
        out, err = server.communicate(timeout=LIMIT_S)
    assert server.returncode == 0, err[-3000:]


def test_sweep(fresh: Path) -> None:
    """The scaffold declares the variable ``mass`` the README sweeps (2 seeds and 60 frames
    here instead of 100 and 600: 400 runs take minutes)."""
    colosseum(".venv/bin/colosseum new my_sim", fresh)
    line = (".venv/bin/colosseum sweep my_sim --param mass=1,2 --seeds 0..99 --frames 600 "
            "--out results")
    argv = shlex.split(line.replace("0..99", "0..1").replace("600", "60"))
    done = subprocess.run([str(BIN), *argv[1:], "--workers", "1"], cwd=fresh,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    rows = (fresh / "results" / "results.csv").read_text().splitlines()
    assert len(rows) == 1 + 4


# -- exit codes ------------------------------------------------------------------------------

BROKEN = """\
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object {
  ID "ball"
  Positon [0 0 3]
  PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" } }
}
Object { ID "box" Position [2 0 1] PhysicalAttributes { Mass 1 Geometry { Primitive "box" } } }
"""


def test_run_exits_1_after_running_without_broken_parts(fresh: Path) -> None:
    """The README: exit 1 means errors in the content. The run goes on without the broken
    object, and says so at the end with exit code 1."""
    (fresh / "my_sim").mkdir()
    (fresh / "my_sim" / "main.scene").write_text(BROKEN)
    done = subprocess.run([str(BIN), "run", "my_sim", "--frames", "10", "--fast",
                           "--save-state", "state.scene"], cwd=fresh, capture_output=True,
                          text=True, timeout=LIMIT_S)
    assert done.returncode == 1, done.stderr
    assert "Positon" in done.stderr and "exit code 1" in done.stderr
    assert saved_objects(fresh / "state.scene") == ["ground", "box"]  # it ran without ball
    (fresh / "my_sim" / "main.scene").write_text(BROKEN.replace("Positon", "Position"))
    done = subprocess.run([str(BIN), "run", "my_sim", "--frames", "10", "--fast"], cwd=fresh,
                          capture_output=True, text=True, timeout=LIMIT_S)
    assert done.returncode == 0, done.stderr


def test_run_exits_1_when_objects_were_refused(fresh: Path) -> None:
    """A scene whose objects name a file outside the content folder: each is refused, the
    run goes on with the rest and exits 1."""
    _room(fresh / "models")
    (fresh / "my_sim").mkdir()
    (fresh / "my_sim" / "main.scene").write_text(
        'Object { ID "box" Position [2 0 1] PhysicalAttributes { Mass 1 Geometry { '
        'Primitive "box" } } }\n'
        'Object { ID "room" VisualAttributes { Geometry { File "../models/room.glb" } } }\n')
    done = subprocess.run([str(BIN), "run", "my_sim", "--frames", "5", "--fast"], cwd=fresh,
                          capture_output=True, text=True, timeout=LIMIT_S)
    assert done.returncode == 1, done.stderr
    assert "outside the content folder" in done.stderr


# -- check reads shaders --------------------------------------------------------------------

VERT = """#version 330
uniform mat4 u_projection;   // the engine supplies u_proj
uniform mat4 u_view;
uniform float unused_here;
in vec3 in_position;
in vec3 in_normals;          // the engine feeds in_normal
in mat4 i_model;
out vec3 v_normal;
void main() {
    v_normal = in_normals;
    gl_Position = u_projection * u_view * i_model * vec4(in_position, 1.0);
}
"""
FRAG = """#version 330
uniform vec3 tint;
uniform vec3 glow;
in vec3 v_normal;
out vec4 color;
void main() { color = vec4(tint + glow * v_normal, 1.0); }
"""
SHADED = """\
VertexShader { ID "v" File "shaders/toon.vert" }
FragmentShader { ID "f" File "shaders/toon.frag" }
ShaderProgram { ID "toon" VertexShader "v" FragmentShader "f" }
ShaderState { ID "toon" ShaderProgram "toon" Uniform { ID "tint" Value [1 0 0] } }
Object { ID "a" VisualAttributes { Geometry { Primitive "box" } ShaderState "toon" } }
"""


def test_check_reports_what_a_shader_is_never_given(fresh: Path) -> None:
    """Without a GPU: a uniform nothing sets (with the engine's closest name), a vertex
    input the engine never feeds; not the uniforms a ShaderState sets or the engine
    supplies, not one declared and never used."""
    (fresh / "my_sim" / "shaders").mkdir(parents=True)
    (fresh / "my_sim" / "shaders" / "toon.vert").write_text(VERT)
    (fresh / "my_sim" / "shaders" / "toon.frag").write_text(FRAG)
    (fresh / "my_sim" / "main.scene").write_text(SHADED)
    done = subprocess.run([str(BIN), "check", "my_sim", "--format", "json"], cwd=fresh,
                          capture_output=True, text=True, timeout=LIMIT_S)
    assert done.returncode == 0, done.stderr  # warnings: it still runs
    told = {(Path(d["path"]).name, d["line"], d["message"].split("'")[1])
            for d in json.loads(done.stdout)["diagnostics"]}
    assert told == {("toon.vert", 2, "u_projection"), ("toon.vert", 6, "in_normals"),
                    ("toon.frag", 3, "glow")}
    text = subprocess.run([str(BIN), "check", "my_sim"], cwd=fresh, capture_output=True,
                          text=True, timeout=LIMIT_S).stderr
    assert "did you mean 'u_proj'" in text and "did you mean 'in_normal'" in text
    # a headless run draws nothing, so no program is compiled: it says the same
    run = subprocess.run([str(BIN), "run", "my_sim", "--frames", "3", "--fast", "--headless"],
                         cwd=fresh, capture_output=True, text=True, timeout=LIMIT_S)
    assert run.returncode == 0, run.stderr
    assert "did you mean 'u_proj'" in run.stderr
