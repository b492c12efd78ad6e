"""Lexer + parser: the paper's data types, expressions, comments, quotes, includes, limits."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from engine.scene import Limits, SceneError, parse_file, parse_text
from engine.scene.db import FLOAT, INT, STRING, STRINGVECTOR, STRUCTURE, VECTOR

DATA = Path(__file__).parent / "data"


def errors(text: str, **kw) -> list[tuple[int, int, str]]:
    with pytest.raises(SceneError) as info:
        parse_text(text, "t.scene", **kw)
    return [(d.line, d.col, d.message) for d in info.value.errors]


def test_every_data_type_parses_to_its_kind():
    db = parse_text('i 3\nf 2.5\ne 1e-3\nv [1 0 2.7]\nsv ["wheel_l" "wheel_r"]\n'
                    's "cow.obj"\nst { a 1 }\nx 2*i\nempty []\n')
    kinds = {e.key: e.value.kind for e in db}
    assert kinds == {"i": INT, "f": FLOAT, "e": FLOAT, "v": VECTOR, "sv": STRINGVECTOR,
                     "s": STRING, "st": STRUCTURE, "x": FLOAT, "empty": VECTOR}
    assert db.get("v") == (1, 0, 2.7)
    assert db.get("sv") == ("wheel_l", "wheel_r")
    assert db.get("x") == 6.0
    assert db.find("st/a").data == 1


def test_values_keep_file_line_and_column():
    db = parse_text("a 1\nObj {\n  Position [1 2 3]\n}\n", "f.scene")
    pos = db.find("Obj/Position")
    assert (pos.loc.path, pos.loc.line, pos.loc.col) == ("f.scene", 3, 12)
    assert (pos.data[2].loc.line, pos.data[2].loc.col) == (3, 17)
    assert db.root.entry("Obj").loc.line == 2


def test_repeated_keys_keep_order():
    db = parse_text('Object { ID "a" }\nx 1\nObject { ID "b" }\nObject { ID "c" }\n')
    assert [b.get("ID") for b in db.blocks("Object")] == ["a", "b", "c"]
    assert db.find("Object[1]/ID").data == "b"
    assert db.find("Object[c]/ID").data == "c"


@pytest.mark.parametrize(("expr", "value"), [
    ("1 + 2*3", 7.0), ("(1 + 2)*3", 9.0), ("2^3^2", 512.0), ("-2^2", -4.0),
    ("2^-1", 0.5), ("10/4", 2.5), ("7 - 2 - 1", 4.0), ("sqrt(16) + abs(-2)", 6.0),
    ("sin(pi/2)", 1.0), ("cos(0)", 1.0), ("deg(pi)", 180.0), ("rad(180)", math.pi),
    ("min(3, 1, 2)", 1.0), ("max(3, 1, 2)", 3.0), ("e", math.e), ("clamp(5, 0, 2)", 2.0),
    ("s*2 + t", 23.0), ("--s", 10.0),
])
def test_expressions_evaluate(expr, value):
    db = parse_text(f"s 10.0\nt 3\nx {expr}\n")
    assert db.get("x") == pytest.approx(value)


def test_expression_text_is_kept_for_the_writer():
    db = parse_text("s 10\nx (s + 1)*2\nv [s/2 -s 1]\n")
    assert db.find("x").expr == "(s + 1)*2"
    assert [i.expr for i in db.find("v").data] == ["s/2", "-s", None]


@pytest.mark.parametrize(("text", "items"), [
    ("[1 -2]", (1, -2)), ("[1 - 2]", (-1.0,)), ("[1-2]", (-1.0,)), ("[1 +2]", (1, 2)),
    ("[s -s]", (4.0, -4.0)), ("[(1) (2)]", (1, 2)), ("[-1 -2 -3]", (-1, -2, -3)),
    ("[10.2 34.2 s]", (10.2, 34.2, 4.0)), ("[sin (0) 1]", (0.0, 1)),
])
def test_vector_items_split_on_signs_like_the_paper(text, items):
    assert parse_text(f"s 4\nv {text}\n").get("v") == items


def test_variables_are_scoped_to_their_block_and_enclosing_blocks():
    db = parse_text("a 1\nB { a 5 c a*2 }\nd a*3\n")
    assert db.find("B/c").data == 10.0
    assert db.get("d") == 3.0
    assert errors("B { q 2 }\nd q\n")[0][:2] == (2, 3)


def test_random_functions_are_reproducible_with_a_seed():
    text = "v [randInterval(1, 2) randNormal(0, 1) randInt(1, 6)]\n"
    a = parse_text(text, rng=np.random.default_rng(7)).get("v")
    b = parse_text(text, rng=np.random.default_rng(7)).get("v")
    c = parse_text(text, rng=np.random.default_rng(8)).get("v")
    assert a == b != c
    assert 1 <= a[0] <= 2 and a[2] in (1, 2, 3, 4, 5, 6)


def test_listing1_as_printed():
    db = parse_file(DATA / "listing1.scene", np.random.default_rng(1))
    assert db.find("Object/Position").py() == (10.2, 34.2, 10.0)
    size = db.find("Object/Size").data[0]
    assert 5.0 <= size.data <= 10.0 and size.expr == "randInterval(s/2, s)"
    assert db.find("Object/PhysicalAttributes/Mass").data == 1.1
    assert db.find("Object/VisualAttributes/Geometry/Primitive").data == "sphere"


def test_paper_listings_with_typographic_quotes_load_with_a_warning():
    db = parse_file(DATA / "paper" / "main.scene")
    assert db.find("ShaderState/ID").data == "toon"
    assert db.find("ShaderState/ShaderProgram").data == "toon"
    assert db.find("Object[cow]/PhysicalAttributes/Geometry/ParseMethod").data == "TriangleMesh"
    assert [u.get("Value") for u in db.find("ShaderState").data.blocks("Uniform")] == [
        (0, 0.25, 1), (0.75, 0.75, 1), 0.95]
    quotes = [w for w in db.warnings if "typographic" in w.message]
    assert len(quotes) == 1 and (quotes[0].line, quotes[0].col) == (18, 6)


def test_comments_of_both_kinds_are_ignored_by_values():
    db = parse_text("a 1 // one\n/* block\n comment */ b /* inline */ 2\n")
    assert (db.get("a"), db.get("b")) == (1, 2)


def test_escapes_in_strings():
    db = parse_text(r's "a \"quoted\" \\ name\n"' + "\n")
    assert db.get("s") == 'a "quoted" \\ name\n'


def test_include_splices_entries_and_variables(tmp_path):
    db = parse_file(DATA / "include" / "main.scene")
    assert db.find("Object/Position").py() == (0, 0, 2.5)
    assert db.find("Material/ID").data == "rubber"
    mat = db.find("Material")
    assert mat.loc.path.endswith("materials.scene") and mat.loc.line == 2
    assert [e.key for e in db.root.entries] == ["Include", "Object"]


def test_include_cycle_is_an_error_naming_the_chain():
    with pytest.raises(SceneError) as info:
        parse_file(DATA / "cycle" / "a.scene")
    (err,) = info.value.errors
    assert err.path.endswith("b.scene") and (err.line, err.col) == (2, 9)
    assert "Include cycle: a.scene -> b.scene -> a.scene" in err.message


def test_missing_include_names_the_path_looked_for(tmp_path):
    (tmp_path / "m.scene").write_text('Include "nope.scene"\n')
    with pytest.raises(SceneError) as info:
        parse_file(tmp_path / "m.scene")
    assert str(tmp_path / "nope.scene") in info.value.errors[0].message


def test_deep_nesting_is_refused_with_a_limit_message():
    text = "a " + "{ b " * 5000 + "}" * 5000
    (err,) = [e for e in errors(text) if "limit" in e[2]]
    assert "nesting deeper than 64 levels" in err[2]
    assert "nesting deeper" in errors("x " + "(" * 3000 + "1" + ")" * 3000)[0][2]
    assert "nesting deeper" in errors("x " + "-" * 3000 + "1")[0][2]


def test_long_operator_chains_are_refused_not_crashed():
    msg = errors("x " + " + ".join(["1"] * 5000) + "\n")[0][2]
    assert "expression deeper than 256 operations" in msg


def test_token_and_size_limits(tmp_path):
    assert "more than 100 tokens" in errors("a 1\n" * 60, limits=Limits(max_tokens=100))[0][2]
    big = tmp_path / "big.scene"
    big.write_text("a 1\n" * 100)
    with pytest.raises(SceneError) as info:
        parse_file(big, limits=Limits(max_bytes=50))
    assert "400 bytes, larger than the 50-byte limit" in info.value.errors[0].message


def test_numbers_out_of_range_are_errors():
    assert "too large for a FLOAT" in errors("x 1e999\n")[0][2]
    assert "out of range" in errors("x 99999999999999999999\n")[0][2]
    assert "division by zero" in errors("x 1/0\n")[0][2]
    assert "math domain error" in errors("x sqrt(-1)\n")[0][2]
    assert "not a finite number" in errors("x 1e300*1e300\n")[0][2]


def test_query_helpers():
    db = parse_text('a 1\nObject { ID "x" Mass 2 }\nObject { ID "y" }\na 3\n')
    assert db.root.keys() == ["a", "Object", "Object", "a"]
    assert db.get("a") == 3 and db.get("missing", 7) == 7  # the last one wins
    assert [e.value.data.get("ID") for e in db.get_all("Object")] == ["x", "y"]
    assert db.find("Object[x]/Mass").data == 2 and db.find("Object[z]") is None
    assert db.find("Object[5]") is None and db.find("a/b") is None
