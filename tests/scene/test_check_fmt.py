"""`colosseum check --format json` and `colosseum fmt --write`, through the CLI's main()."""

from __future__ import annotations

import json
import stat

import pytest

from app.cli import main

BROKEN = 'Object {\n  ID "a"\n  Radius 0.5\n}\nObject { ID "a" }\n'
TIDY = """\
// The floor and a ball.
spacing 1.5

Material { ID "rubber" Friction 0.9 Bounce 0.5 }
Object { ID "floor" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }


Object {
  ID "ball"
  Position [0 0 spacing]   // above the floor

  PhysicalAttributes { Mass 2 Material "rubber" Geometry { Primitive "sphere" } }
}
"""


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_check_json_lists_every_diagnostic_and_exits_1_on_errors(tmp_path, capsys):
    (tmp_path / "main.scene").write_text(BROKEN)
    code, out, err = run(capsys, "check", str(tmp_path), "--format", "json")
    report = json.loads(out)
    assert code == 1 and err == ""
    assert (report["errors"], report["warnings"]) == (2, 0)
    first, second = report["diagnostics"]
    assert first == {"path": str(tmp_path / "main.scene"), "line": 3, "col": 3,
                     "severity": "error",
                     "message": "unknown key 'Radius' in Object (did you mean 'Size'? a "
                                "sphere's Size is its diameter: Size [1] for Radius 0.5)"}
    assert (second["line"], second["col"]) == (5, 13)


def test_check_exit_codes_0_with_warnings_only_and_2_for_a_missing_path(tmp_path, capsys):
    (tmp_path / "main.scene").write_text("Material { ID 1 }\nMaterial { ID 2 Friction 2 }\n"
                                         "Object { PhysicalAttributes { Material 3 } }\n")
    code, out, _ = run(capsys, "check", str(tmp_path), "--format", "json")
    assert code == 0 and json.loads(out)["warnings"] == 1
    code, out, err = run(capsys, "check", str(tmp_path / "nope"), "--format", "json")
    assert code == 2 and json.loads(out)["diagnostics"][0]["message"] == (
        "no such file or folder")
    code, out, err = run(capsys, "check", str(tmp_path / "nope"))
    assert code == 2 and out == "" and "no such file or folder" in err


def test_check_text_shows_places_lines_and_carets_on_stderr(tmp_path, capsys):
    (tmp_path / "main.scene").write_text(BROKEN)
    code, out, err = run(capsys, "check", str(tmp_path))
    assert code == 1 and out == ""
    assert err.splitlines()[:3] == [
        f"{tmp_path / 'main.scene'}:3:3: error: unknown key 'Radius' in Object (did you "
        "mean 'Size'? a sphere's Size is its diameter: Size [1] for Radius 0.5)",
        "      Radius 0.5", "      ^"]
    assert err.splitlines()[-1] == f"{tmp_path}: 2 error(s), 0 warning(s)"


@pytest.mark.parametrize("mode", [0o644, 0o640, 0o600])
def test_fmt_write_keeps_the_mode_blank_lines_and_short_one_line_blocks(tmp_path, capsys,
                                                                        mode):
    scene = tmp_path / "main.scene"
    scene.write_text(TIDY)
    scene.chmod(mode)
    code, _, _ = run(capsys, "fmt", str(tmp_path), "--write")
    assert code == 0
    assert stat.S_IMODE(scene.stat().st_mode) == mode
    backup = tmp_path / "main.scene.bak"
    assert backup.read_text() == TIDY and stat.S_IMODE(backup.stat().st_mode) == mode
    assert scene.read_text() == """\
// The floor and a ball.
spacing 1.5

Material { ID "rubber" Friction 0.9 Bounce 0.5 }
Object { ID "floor" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }

Object {
  ID "ball"
  Position [0 0 spacing] // above the floor

  PhysicalAttributes { Mass 2 Material "rubber" Geometry { Primitive "sphere" } }
}
"""
    code, out, _ = run(capsys, "fmt", str(tmp_path))  # formatting again changes nothing
    assert code == 0 and out == scene.read_text()


def test_fmt_expands_one_line_blocks_that_are_long_or_hold_comments(tmp_path, capsys):
    long_block = "Object { " + " ".join(f'ID "{"x" * 20}{i}"' for i in range(5)) + " }"
    (tmp_path / "main.scene").write_text(f"{long_block}\nA {{ b 1 /* c */ }}\nC {{\n}}\n")
    code, out, _ = run(capsys, "fmt", str(tmp_path))
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == "Object {" and len(lines[1:6]) == 5 and lines[6] == "}"
    assert lines[7:] == ["A {", "  b 1 /* c */", "}", "C {}"]


def test_fmt_write_of_a_scene_file_leaves_a_canonical_one_untouched(tmp_path, capsys):
    scene = tmp_path / "other.scene"
    scene.write_text("a  1\n")
    assert run(capsys, "fmt", str(scene), "--write")[0] == 0
    assert scene.read_text() == "a 1\n"
    (tmp_path / "other.scene.bak").unlink()
    assert run(capsys, "fmt", str(scene), "--write")[0] == 0
    assert not (tmp_path / "other.scene.bak").exists()


def test_check_json_counts_the_errors_not_shown(tmp_path, capsys):
    (tmp_path / "main.scene").write_text("a $\n" * 1000)
    code, out, _ = run(capsys, "check", str(tmp_path), "--format", "json")
    report = json.loads(out)
    assert code == 1 and report["errors"] == 2000
    *shown, omitted = report["diagnostics"]
    assert len(shown) == 100 and omitted["errors"] == 1900
