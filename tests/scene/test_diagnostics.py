"""Errors that teach: every error in one pass, exact places, carets, did-you-mean."""

from __future__ import annotations

from pathlib import Path

import pytest

from engine.scene import SceneError, check, parse_text, validated

DATA = Path(__file__).parent / "data"


def problems(text: str, tmp_path: Path, name: str = "main.scene") -> list:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return [d for d in check(path) if d.is_error]


BROKEN = """\
Material { ID "rubber" Friction 0.9 }
Object {
  ID "ball"
  Positon [0 0 1]
  Orientation "up"
  Size [1 2 3 4]
  VisualAttributes { Geometry { Primitive "sphere" } ShaderState "ton" }
  PhysicalAttributes { Mass "heavy" Material "ruber" Geometry { Primitive "spher" } }
  dynamic 1
}
ShaderState { ID "toon" ShaderProgram "toon_prog" }
ShaderProgram { ID "toon_prog" }
"""


def test_every_schema_error_is_reported_in_one_pass_with_its_place(tmp_path):
    errs = problems(BROKEN, tmp_path)
    got = [(d.line, d.col, d.message) for d in errs]
    assert got == [
        (4, 3, "unknown key 'Positon' in Object (did you mean 'Position'?)"),
        (5, 15, "'Orientation' expects VECTOR of 3 numbers, got STRING \"up\""),
        (6, 8, "'Size' expects VECTOR of 1, 2 or 3 numbers, got VECTOR of 4 numbers"),
        (7, 66, "unknown ShaderState 'ton' (did you mean 'toon'?)"),
        (8, 29, "'Mass' expects a number (INT or FLOAT), got STRING \"heavy\""),
        (8, 46, "unknown Material 'ruber' (did you mean 'rubber'?)"),
        (8, 75, "unknown Primitive \"spher\" (did you mean 'sphere'?); expected one of "
                "sphere, box, capsule, cylinder, plane"),
        (9, 3, "unknown key 'dynamic' in Object (did you mean 'Dynamic'?)"),
    ]


def test_rendering_shows_path_line_col_source_line_and_caret(tmp_path):
    (tmp_path / "main.scene").write_text(BROKEN)
    with pytest.raises(SceneError) as info:
        validated(parse_text(BROKEN, str(tmp_path / "main.scene")), tmp_path)
    text = str(info.value)
    first = text.splitlines()[:3]
    assert first[0] == (f"{tmp_path / 'main.scene'}:4:3: error: unknown key 'Positon' in "
                        "Object (did you mean 'Position'?)")
    assert first[1] == "      Positon [0 0 1]"
    assert first[2] == "      ^"


def test_every_syntax_error_is_reported_in_one_pass():
    text = 'a 1\nb [1 2\nc 3\nd "open\ne $\nf (1 + )\ng 5\n}\n'
    with pytest.raises(SceneError) as info:
        parse_text(text, "s.scene")
    got = [(d.line, d.col, d.message) for d in info.value.errors]
    assert got == [
        (2, 3, "'[' from line 2 is never closed with ']'"),
        (4, 3, "string is not closed before the end of the line"),
        (5, 1, "key 'e' has no value"),
        (5, 3, "unexpected character '$'"),
        (6, 8, "expected a number, name or '(' but found ')'"),
        (8, 1, "'}' without a matching '{'"),
    ]


def test_unclosed_brace_points_at_the_opening_brace():
    with pytest.raises(SceneError) as info:
        parse_text("Object {\n  ID \"x\"\n", "u.scene")
    (err,) = info.value.errors
    assert (err.line, err.col) == (1, 8) and "never closed" in err.message


def test_unknown_variable_suggests_a_name_or_quotes():
    with pytest.raises(SceneError) as info:
        parse_text("speed 3\nx sped*2\ny [1 box]\n", "v.scene")
    msgs = [d.message for d in info.value.errors]
    assert msgs[0] == "unknown variable 'sped' (did you mean 'speed'?)"
    assert msgs[1] == "unknown variable 'box' (a string needs quotes: \"box\")"


def test_function_arity_and_unknown_reference_suggestions(tmp_path):
    with pytest.raises(SceneError) as info:
        parse_text("x randInterval(1)\n", "f.scene")
    assert info.value.errors[0].message == "randInterval() takes 2 arguments, got 1"
    errs = problems('Object { ID "door" PhysicalAttributes {} }\n'
                    'Joint { Type "Hnge" Bodies ["dor"] }\n'
                    'Controller { Input "key:Up/Down" Target "motor:hinj" }\n'
                    'Joint { ID "hinge" Type "Hinge" Bodies ["door"] }\n', tmp_path)
    msgs = [d.message for d in errs]
    assert "unknown Type \"Hnge\" (did you mean 'Hinge'?)" in msgs[0]
    assert msgs[1] == "unknown Object 'dor' (did you mean 'door'?)"
    assert msgs[2] == "unknown Joint 'hinj' in controller target (did you mean 'hinge'?)"


def test_missing_assets_name_the_path_looked_for(tmp_path):
    errs = problems('Script "scripts/main.lua"\n'
                    'Object { Sound { File "sounds/bang.wav" } }\n', tmp_path)
    assert [(d.line, d.col) for d in errs] == [(1, 8), (2, 23)]
    assert errs[0].message == (f'file not found: "scripts/main.lua" (looked for '
                               f'{tmp_path / "scripts/main.lua"})')


def test_required_keys_duplicates_and_sizes(tmp_path):
    errs = problems('Joint { ID "j" }\nObject { ID "a" }\nObject { ID "a" }\n'
                    'Object { ID "c" Size [1 2 3] VisualAttributes { Geometry '
                    '{ Primitive "sphere" } } }\n'
                    'Object { ID "d" PhysicalAttributes { Geometry { Size [0 1] '
                    'Primitive "capsule" } } }\n', tmp_path)
    msgs = [(d.line, d.message) for d in errs]
    assert msgs == [
        (1, "Joint is missing required key 'Type'"),
        (1, "Joint is missing required key 'Bodies'"),
        (3, f"duplicate Object ID 'a' (first declared at {tmp_path / 'main.scene'}:2:13)"),
        (4, "Size of a sphere is [diameter], got 3 numbers"),
        (5, "Size must be positive, got 0"),
    ]


def test_a_clean_file_checks_without_errors():
    assert [d for d in check(DATA / "representative") if d.is_error] == []
    assert [d.severity for d in check(DATA / "listing1.scene")] == ["warning"]


def test_check_of_a_missing_folder_is_an_error(tmp_path):
    (d,) = check(tmp_path)
    assert d.is_error and "no main.scene" in d.message


def test_errors_in_an_included_file_point_into_that_file(tmp_path):
    (tmp_path / "main.scene").write_text('a 1\nInclude "parts.scene"\n')
    (tmp_path / "parts.scene").write_text('Object {\n  Mas 3\n}\n')
    report = check(tmp_path)
    (err,) = report.errors
    assert (Path(err.path).name, err.line, err.col) == ("parts.scene", 2, 3)
    assert report.render().splitlines()[1:] == ["      Mas 3", "      ^"]


def test_tabs_and_crlf_keep_the_caret_under_the_column():
    with pytest.raises(SceneError) as info:
        parse_text("a 1\r\n\tb $\r\n", "c.scene")
    errs = info.value.errors
    assert [(e.line, e.col, e.message) for e in errs] == [
        (2, 2, "key 'b' has no value"), (2, 4, "unexpected character '$'")]
    assert info.value.render().splitlines()[4:] == ["     b $", "       ^"]
