"""No function outside the tests grows past 60 lines unless it is listed, with its reason
(tools/long_functions.py)."""

from __future__ import annotations

from pathlib import Path

from tools.long_functions import ALLOWED, LIMIT, check, cython_functions, python_functions


def test_no_function_is_long_unless_allowed_and_the_list_holds_only_long_ones() -> None:
    assert check() == []
    assert len(ALLOWED) <= 10  # shrinks as functions are split; never grows


def body(lines: int, indent: str = "    ") -> str:
    return "".join(f"{indent}x = {i}\n" for i in range(lines))


def test_the_checker_measures_python_and_cython_and_reports_each_problem(tmp_path: Path):
    engine = tmp_path / "engine"
    engine.mkdir()
    (engine / "a.py").write_text(
        "class A:\n    @staticmethod\n    def long():\n" + body(LIMIT - 1, " " * 8)
        + "\n\ndef short():\n" + body(3))
    (engine / "b.pxi").write_text(
        "cdef extern from 'x.h':\n    int f(int)\n\n"
        "cdef int compiled(int n,\n                  int m) noexcept nogil:\n"
        + body(LIMIT) + "    # a comment past the end does not count\n\n"
        "cdef double declared(double x)\n")
    (python,) = [f for f in python_functions(engine / "a.py") if f.name == "A.long"]
    assert python.line == 2 and python.length == LIMIT + 1  # decorator to last line
    (cython,) = cython_functions(engine / "b.pxi")
    assert (cython.name, cython.line, cython.length) == ("compiled", 4, LIMIT + 2)
    problems = check(tmp_path, {"engine/gone.py::f": "was long"})
    assert problems == [
        f"engine/a.py:2: A.long is {LIMIT + 1} lines (at most {LIMIT}): split it, or say "
        "in ALLOWED why not",
        f"engine/b.pxi:4: compiled is {LIMIT + 2} lines (at most {LIMIT}): split it, or say "
        "in ALLOWED why not",
        "engine/gone.py::f: allowed as long but no longer is (or is gone); take it off "
        "ALLOWED",
    ]
    allowed = {"engine/a.py::A.long": "a reason", "engine/b.pxi::compiled": "a reason"}
    assert check(tmp_path, allowed) == [
        "engine/a.py:2: A.long is allowed to be long; say why in a '# Long: ...' line above "
        "it",
        "engine/b.pxi:4: compiled is allowed to be long; say why in a '# Long: ...' line "
        "above it"]
    (engine / "b.pxi").write_text((engine / "b.pxi").read_text().replace(
        "cdef int compiled", "# Long: a reason\ncdef int compiled"))
    assert len(check(tmp_path, allowed)) == 1  # a.py's still lacks its comment
