"""The colosseum command line, end to end in subprocesses."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from app.scaffold import scaffold


def colosseum(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=120)


@pytest.fixture()
def sim(tmp_path: Path) -> Path:
    return scaffold(tmp_path / "sim")


def test_new_scaffolds_a_folder_that_runs(sim: Path, tmp_path: Path):
    stats = tmp_path / "stats.json"
    result = colosseum("run", sim, "--seconds", "1.5", "--fast", "--stats", stats,
                       "--backend", "pymunk")
    assert result.returncode == 0, result.stderr
    assert "ball z=" in result.stdout  # the scaffold's custom Python system ran
    data = json.loads(stats.read_text())
    for key in ("frames", "sim_seconds", "wall_seconds", "real_time_factor", "physics_ms_mean",
                "physics_ms_p99", "frame_ms_mean", "bodies", "contacts"):
        assert key in data
    assert data["frames"] == 150 and data["sim_seconds"] == pytest.approx(1.5)
    assert data["bodies"] == 3 and data["contacts"] > 0
    assert data["backend"] == "pymunk"


def test_new_refuses_to_overwrite(sim: Path):
    result = colosseum("new", sim)
    assert result.returncode == 2
    assert "already exists" in result.stderr


@pytest.mark.parametrize("mode", ["serial", "threaded"])
def test_run_frames_in_both_modes(sim: Path, tmp_path: Path, mode: str):
    stats = tmp_path / "s.json"
    result = colosseum("run", sim, "--frames", "40", "--fast", "--mode", mode, "--stats", stats)
    assert result.returncode == 0, result.stderr
    data = json.loads(stats.read_text())
    assert data["frames"] == 40 and data["mode"] == mode


def test_usage_errors_exit_2(tmp_path: Path):
    assert colosseum("run", "--bogus").returncode == 2
    missing = colosseum("run", tmp_path / "nowhere")
    assert missing.returncode == 2 and "nowhere: no such file or folder" in missing.stderr
    (tmp_path / "empty").mkdir()
    empty = colosseum("run", tmp_path / "empty")
    assert empty.returncode == 2 and "has no main.scene" in empty.stderr
    assert colosseum("run", "--frames", "-3").returncode == 2
    assert colosseum("frobnicate").returncode == 2


def test_a_raising_custom_system_is_named_and_leaves_no_stats(sim: Path, tmp_path: Path):
    (sim / "systems" / "broken.py").write_text(
        "from engine import Phase, system\n\n"
        "@system(Phase.SCRIPT)\n"
        "def exploder(engine, dt):\n"
        "    if engine.frame == 10:\n"
        "        raise ZeroDivisionError('custom failure')\n\n"
        "def build(engine):\n"
        "    engine.add_system(exploder)\n")
    stats = tmp_path / "stats.json"
    result = colosseum("run", sim, "--frames", "100", "--fast", "--mode", "threaded",
                       "--stats", stats)
    assert result.returncode == 1
    assert "system 'exploder' raised" in result.stderr
    assert "ZeroDivisionError: custom failure" in result.stderr
    assert "broken.py" in result.stderr  # the traceback points into the author's file
    assert not stats.exists()
    assert list(tmp_path.glob(".stats.json*")) == []


def test_a_custom_system_that_fails_to_import_names_its_file(sim: Path):
    (sim / "systems" / "typo.py").write_text("def build(engine)\n    pass\n")
    result = colosseum("run", sim, "--frames", "5", "--fast")
    assert result.returncode == 1
    assert "typo.py" in result.stderr and "SyntaxError" in result.stderr


def test_scene_errors_are_reported_with_places_and_the_run_goes_on_without_them(sim: Path):
    """check stops at an error; run reports it, leaves out the part it lies in (the crate
    with a misspelt key; of World only its broken key), runs the rest and exits 1 (errors
    in the content, issue 31)."""
    scene = sim / "main.scene"
    scene.write_text(scene.read_text().replace('Mass mass', 'Mas mass')
                     .replace("TimeStep 0.01", "TimeStep 0"))
    checked = colosseum("check", sim)
    assert checked.returncode == 1 and "did you mean 'Mass'" in checked.stderr
    result = colosseum("run", sim, "--frames", "61", "--fast", "--save-state",
                       sim / "state.scene")
    assert result.returncode == 1, result.stderr
    assert "the content had 2 error(s)" in result.stderr
    assert re.search(r"main\.scene:\d+:\d+: error: unknown key 'Mas'", result.stderr)
    assert "did you mean 'Mass'" in result.stderr and "TimeStep must be" in result.stderr
    assert re.search(r'without 2 broken part\(s\).*\n  \S*main\.scene:2: TimeStep\n'
                     r'  \S*main\.scene:25: Object "crate"', result.stderr), result.stderr
    assert "ball z=" in result.stdout  # the rest ran, the World's gravity kept
    saved = (sim / "state.scene").read_text()
    assert '"ball"' in saved and '"crate"' not in saved and "Gravity [0 0 -9.81]" in saved
    assert "Traceback" not in result.stderr


def test_a_scene_that_does_not_parse_does_not_run(sim: Path):
    scene = sim / "main.scene"
    scene.write_text(scene.read_text().replace("Position [0 0 3]", "Position [0 0 3"))
    result = colosseum("run", sim, "--frames", "5", "--fast")
    assert result.returncode == 1 and "is never closed" in result.stderr
    assert "ball z=" not in result.stdout and "Traceback" not in result.stderr
    assert colosseum("check", sim).returncode == 1


def test_save_state_then_run_it_matches_an_uninterrupted_run(sim: Path, tmp_path: Path):
    from engine.scene import load_scene

    scene = sim / "main.scene"
    scene.write_text(scene.read_text().replace("TimeStep 0.01", "TimeStep 0.01 AutoSleep 0"))
    whole, first, rest = tmp_path / "whole.scene", tmp_path / "first.scene", tmp_path / "rest.scene"
    for args in ((sim, "--seconds", "3", "--save-state", whole),
                 (sim, "--seconds", "2", "--save-state", first),
                 (first, "--seconds", "1", "--save-state", rest)):
        result = colosseum("run", *args, "--fast")
        assert result.returncode == 0, result.stderr

    def positions(path: Path) -> dict[str, list[float]]:
        db = load_scene(path)
        assert db.find("World/Time").data == pytest.approx(3.0)
        return {o.value.data.find("ID").data: [v.data for v in o.value.data.find("Position").data]
                for o in db.root.get_all("Object")}

    a, b = positions(whole), positions(rest)
    assert a.keys() == b.keys() == {"ground", "ball", "crate"}
    for name in a:
        assert b[name] == pytest.approx(a[name], abs=1e-6), name


def test_the_bundled_demo_resumes_from_a_saved_state(tmp_path: Path):
    """Its scripts kick a ball and drop crates on the clock, so a state saved at 5 s and
    run 2 s more holds the same objects, where the 7 s run has them."""
    from engine.scene import load_scene

    demo = Path(__file__).resolve().parents[2] / "content" / "demo"
    whole, first, rest = tmp_path / "whole.scene", tmp_path / "first.scene", tmp_path / "rest.scene"
    for args in ((demo, "--seconds", "7", "--save-state", whole),
                 (demo, "--seconds", "5", "--save-state", first),
                 (first, "--seconds", "2", "--save-state", rest)):
        result = colosseum("run", *args, "--fast", "--sound", "null")
        assert result.returncode == 0, result.stderr

    def positions(path: Path) -> dict[str, list[float]]:
        return {o.value.data.find("ID").data: [v.data for v in o.value.data.find("Position").data]
                for o in load_scene(path).root.get_all("Object")}

    a, b = positions(whole), positions(rest)
    assert a.keys() == b.keys() and {"gift1", "gift2", "gift3", "ball"} <= a.keys()
    for name in a:
        assert b[name] == pytest.approx(a[name], abs=1e-6), name


def test_a_commands_path_may_come_after_its_options() -> None:
    from app.cli import parse_args

    args = parse_args(["join", "tcp://127.0.0.1:5555", "--user", "alice", "my_sim"])
    assert (args.address, args.user, args.path) == ("tcp://127.0.0.1:5555", "alice", "my_sim")
    assert parse_args(["join", "tcp://127.0.0.1:5555", "my_sim", "--user", "bob"]).path == \
        "my_sim"
    with pytest.raises(SystemExit):  # two paths: the second is not taken silently
        parse_args(["join", "tcp://127.0.0.1:5555", "a", "--user", "bob", "b"])


@pytest.mark.parametrize("argv", [
    ["run", "content/demo", "--frames", "3", "--headless", "--param", "n=2"],
    ["--log-level", "debug", "check", "x", "--format", "json"],
    ["--log-level=warning", "keys", "Object"],
    ["serve", "x", "--bind", "tcp://127.0.0.1:6000", "--barrier-wait", "0.2"],
    ["experiment", "run", "x", "--participant", "3", "--headless"],
    ["sweep", "x", "--out", "o", "--param", "a=1,2", "--frames", "5"],
    ["bench", "startup", "--quick"]])
def test_a_command_line_parses_as_with_every_command_built(argv: list[str]) -> None:
    """parse_args builds the named command's arguments alone; the result is the full
    parser's."""
    from app.cli import build_parser, parse_args

    assert parse_args(argv) == build_parser().parse_args(argv)


def test_a_command_without_its_arguments_gets_usage_not_a_traceback() -> None:
    """``experiment run`` takes neither --seconds nor --frames: its usage once failed on
    the empty group the two share."""
    result = colosseum("experiment", "run")
    assert result.returncode == 2
    assert "required: path, --participant" in result.stderr
    assert "Traceback" not in result.stderr
