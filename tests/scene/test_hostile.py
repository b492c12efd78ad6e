"""Inputs that crashed, hung or blew up the parser: each is now a short report with places.

One test per case found by mutating scene files (issue 20): tracebacks from
expressions and file names, and reports that grew with the input (one error per bad
character, the whole line repeated under each error, every error shown). Each
report is checked for its exact places and counts; the time each takes is watched
by the fuzz run (tools/fuzz_scene.py), not here.
"""

from __future__ import annotations

import errno
import os
import tracemalloc
from pathlib import Path

import pytest

from engine.confine import OUTSIDE
from engine.scene import Limits, Loc, Report, SceneError, check, parse_file, parse_text
from engine.scene.diagnostics import LINE_WIDTH, MAX_PER_FILE, Omitted, Reporter
from engine.scene.paths import FOLDER


def errors(text: str, **kw) -> list[tuple[int, int, str]]:
    with pytest.raises(SceneError) as info:
        parse_text(text, "t.scene", **kw)
    return [(d.line, d.col, d.message) for d in info.value.errors]


def report_of(tmp_path: Path, text: str | bytes) -> Report:
    main = tmp_path / "main.scene"
    if isinstance(text, bytes):
        main.write_bytes(text)
    else:
        main.write_text(text, encoding="utf-8")
    return check(tmp_path)


# -- expressions ---------------------------------------------------------------------

def test_min_and_max_with_one_argument_are_errors_at_the_call():
    assert errors("x min(1)\ny 2*max(2)\n") == [
        (1, 3, "min() takes at least 2 arguments, got 1"),
        (2, 5, "max() takes at least 2 arguments, got 1")]
    assert parse_text("x min(4, 2, 3)\n").get("x") == 2.0


def test_a_backslash_at_a_line_end_does_not_carry_a_string_onto_the_next_line():
    # It did, and every later place was a line off.
    assert errors('a "x\\\n"\nb $\n') == [
        (1, 3, "string is not closed before the end of the line"),
        (2, 1, "string is not closed before the end of the line"),
        (2, 1, "expected a key name but found '\"'"),
        (3, 1, "key 'b' has no value"),
        (3, 3, "unexpected character '$'")]


def test_a_dot_before_a_bad_character_is_a_bad_run_not_a_number():
    assert errors("n .!\n") == [(1, 1, "key 'n' has no value"),
                                (1, 3, "unexpected characters '.!' (2 in a row)")]


# -- file names ----------------------------------------------------------------------

def test_nul_in_an_include_name_is_an_error_at_the_name(tmp_path):
    (err,) = report_of(tmp_path, 'a 1\nInclude "a\x00b.scene"\n').errors
    assert (err.line, err.col) == (2, 9)
    assert err.message == ('cannot include "a\x00b.scene": the file name contains a NUL '
                           "character")
    assert "\\x00" in err.head() and "\x00" not in err.head()  # escaped for the terminal


@pytest.mark.parametrize("entry", ["Include", "Script"])
def test_a_file_name_longer_than_the_os_allows(tmp_path, entry):
    (err,) = report_of(tmp_path, f'a 1\n{entry} "{"x" * 300}"\n').errors
    assert (err.line, err.col) == (2, len(entry) + 2)
    assert err.message.endswith(f'"{"x" * 40}...": {os.strerror(errno.ENAMETOOLONG)}')


@pytest.mark.parametrize(("entry", "what"), [("Include", "include"), ("Script", "use file")])
def test_includes_and_assets_through_a_symlink_loop(tmp_path, entry, what):
    (tmp_path / "x.scene").symlink_to(tmp_path / "y.scene")
    (tmp_path / "y.scene").symlink_to(tmp_path / "x.scene")
    (err,) = report_of(tmp_path, f'{entry} "x.scene"\n').errors
    assert err.message == f'cannot {what} "x.scene": {os.strerror(errno.ELOOP)}'


def test_a_folder_or_a_device_is_not_an_includable_file(tmp_path):
    (tmp_path / "parts").mkdir()
    os.mkfifo(tmp_path / "pipe")
    report = report_of(tmp_path, 'Include "parts"\nInclude "pipe"\nInclude "/dev/zero"\n')
    assert [d.message for d in report.errors] == [
        f'cannot include "parts": {FOLDER}',
        'cannot include "pipe": it is not a regular file',
        f'cannot include "/dev/zero": {OUTSIDE}']


def test_a_refused_oversized_file_is_not_read_again_to_show_a_line(tmp_path):
    big = tmp_path / "big.scene"
    big.write_text("a 1\n" * 100)
    with pytest.raises(SceneError) as info:
        parse_file(big, limits=Limits(max_bytes=100))
    (err,) = info.value.errors
    assert (err.line, err.col) == (1, 1) and "larger than the 100-byte limit" in err.message
    assert info.value.render() == err.head()  # no source line: the file was not read


# -- reports that grew with the input --------------------------------------------------

def test_a_megabyte_of_nul_bytes_is_one_error(tmp_path):
    report = report_of(tmp_path, b"\x00" * 1_000_000)
    (err,) = report.diagnostics
    assert (err.line, err.col, err.message) == (
        1, 1, "unexpected characters '\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00"
              "\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00\\x00...' (1000000 in a row)")
    assert len(report.render()) < 3 * LINE_WIDTH * 4  # the line is clipped, NULs escaped


@pytest.mark.parametrize("text", [
    "\x00" * 1_000_000, "." * 1_000_000, 'a "' + "b" * 1_000_000 + "\n",
    "a " + "@" * 1_000_000 + "\n", "a $\n" * 20_000], ids=[
    "NUL bytes", "dots", "an open string", "a bad run", "errors on every line"])
def test_a_megabyte_of_hostile_text_is_checked_in_little_memory(tmp_path, text):
    """Memory, not time (which the fuzz run watches): a backtracking repeat in the lexer
    kept a frame per character, 190 MB for one 1 MB line."""
    main = tmp_path / "main.scene"
    main.write_text(text, encoding="utf-8")
    tracemalloc.start()
    try:
        check(tmp_path).render()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 32_000_000  # a megabyte of input; one line of NULs took 193 MB


def test_a_long_line_is_clipped_around_the_column(tmp_path):
    run = "@" * 20_000
    report = report_of(tmp_path, f"a 1\nb {run} $ {run}\n")
    assert [(d.col, d.message) for d in report.errors] == [
        (1, "key 'b' has no value"),
        (3, "unexpected characters '@@@@@@@@@@@@@@@@@@@@...' (20000 in a row)"),
        (20_004, "unexpected character '$'"),
        (20_006, "unexpected characters '@@@@@@@@@@@@@@@@@@@@...' (20000 in a row)")]
    shown, caret = report.render().split("\n")[7:9]  # under the '$'
    assert len(shown) == 4 + 3 + LINE_WIDTH + 3 and shown.startswith("    ...")
    assert shown[caret.index("^")] == "$"


def test_errors_past_the_cap_are_counted_not_shown(tmp_path):
    report = report_of(tmp_path, "a $\n" * 100_000)
    shown = report.diagnostics[:-1]
    summary = report.diagnostics[-1]
    assert len(shown) == MAX_PER_FILE
    assert [(d.line, d.col) for d in shown[:4]] == [(1, 1), (1, 3), (2, 1), (2, 3)]
    assert isinstance(summary, Omitted) and summary.is_error
    assert (summary.line, summary.col, summary.errors) == (51, 1, 2 * 100_000 - MAX_PER_FILE)
    assert summary.message == (f"{2 * 100_000 - MAX_PER_FILE} more errors in this file not "
                               f"shown (the first {MAX_PER_FILE} are)")
    assert report.render().count("\n") == 3 * MAX_PER_FILE  # head, line and caret each


def test_thousands_of_unknown_keys_get_hints_only_where_shown(tmp_path):
    text = "".join(f"Object {{ Radius{i} 1 }}\n" for i in range(5_000))
    report = report_of(tmp_path, text)
    assert len(report.errors) == MAX_PER_FILE + 1
    assert report.errors[0].message == "unknown key 'Radius0' in Object"
    assert report.errors[-1].errors == 5_000 - MAX_PER_FILE


def test_the_cap_keeps_the_first_by_place_whatever_the_order_reported():
    report = Reporter()
    for line in range(300, 0, -1):
        report.error(Loc("f.scene", line, 1), f"e{line}")
    kept = report.diagnostics
    assert [d.line for d in kept[:-1]] == list(range(1, MAX_PER_FILE + 1))
    assert (kept[-1].line, kept[-1].errors) == (MAX_PER_FILE + 1, 300 - MAX_PER_FILE)
    # A later pass (validation) takes the parse's report over, counts included.
    later = Reporter(kept)
    later.warning(Loc("f.scene", 500, 1), "w")
    (summary,) = [d for d in later.diagnostics if isinstance(d, Omitted)]
    assert (summary.errors, summary.warnings) == (300 - MAX_PER_FILE, 1)


# -- hints by meaning ------------------------------------------------------------------

@pytest.mark.parametrize(("entry", "message"), [
    ("Object { Radius 0.5 }", "unknown key 'Radius' in Object (did you mean 'Size'? a "
                              "sphere's Size is its diameter: Size [1] for Radius 0.5)"),
    ("Object { Scale [2 2 2] }", "unknown key 'Scale' in Object (did you mean 'Size'? an "
                                 "Object's Size sizes its primitives; a model's Scale goes in "
                                 "its Geometry)"),
    ("Object { Color [1 0 0] }", "unknown key 'Color' in Object ('Color' goes in "
                                 "VisualAttributes { ... })"),
    ("Object { VisualAttributes { Colour [1 0 0] } }",
     "unknown key 'Colour' in VisualAttributes (did you mean 'Color'? RGB or RGBA, 0..1)"),
    ("Object { Rotation [0 0 90] }", "unknown key 'Rotation' in Object (did you mean "
                                     "'Orientation'? Euler angles in degrees [rx ry rz])"),
    ("Object { Mass 2 }", "unknown key 'Mass' in Object ('Mass' goes in PhysicalAttributes "
                          "{ ... })"),
    ("Object { PhysicalAttributes { Friction 0.2 } }",
     "unknown key 'Friction' in PhysicalAttributes ('Friction' is a key of Material and "
     "MaterialPair, not of PhysicalAttributes)"),
    ("Gravity [0 0 -1]", "unknown key 'Gravity' in Scene ('Gravity' goes in World { ... })"),
    ("Object { Positon [0 0 1] }", "unknown key 'Positon' in Object (did you mean "
                                   "'Position'?)"),
])
def test_unknown_keys_get_a_hint_by_meaning_place_or_spelling(tmp_path, entry, message):
    (err,) = report_of(tmp_path, entry + "\n").errors
    assert err.message == message
