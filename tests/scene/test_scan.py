"""The compiled plain-entry scanner (engine/scene/_scan.pyx) reads exactly what the regex one does.

Both must give the same SceneDB, places, expression texts, token counts and
diagnostics, on well-formed and on broken text. Skipped when the extension is
not built (then the regex scanner is the only one, and every other test uses it).
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_fuzz import ALPHABET, mutated

from engine.scene import Block, Entry, Limits, SceneError, Value, generate_scene, parse_text
from engine.scene import parser as scene_parser

compiled = pytest.importorskip("engine.scene._scan")


def _dump(x: Any) -> Any:
    """Every field of a SceneDB node (an unset one raises), places as plain tuples."""
    if isinstance(x, Value | Entry | Block):
        return type(x).__name__, tuple((f.name, _dump(getattr(x, f.name))) for f in fields(x))
    if isinstance(x, list):
        return [_dump(item) for item in x]
    if isinstance(x, tuple):  # a Loc
        return type(x).__name__, tuple(x)
    return type(x).__name__, repr(x)


def _parse(text: str, limits: Limits | None) -> Any:
    try:
        db = parse_text(text, "scan.scene", np.random.default_rng(0), limits)
    except SceneError as exc:
        return "error", exc.diagnostics
    return _dump(db.root), db.warnings


def assert_same(text: str, limits: Limits | None = None) -> None:
    fast = _parse(text, limits)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(scene_parser, "scan_plain", scene_parser._scan_plain)
        slow = _parse(text, limits)
    assert fast == slow


def test_compiled_scanner_is_the_one_used():
    assert scene_parser.scan_plain is compiled.scan_plain


@pytest.mark.parametrize("text", [
    generate_scene(30),
    'a 2\nV [1 -2 +3 .5 1. 1e3 2E-2 -0 -0.0 12345678901234567 1e999]\nW [ ]\nZ []\n',
    "a 2\nb -1\nV [a*2 -a/2 +a+1 a-1 pi e 3*a 1.5/a 2/0 a*b q]\nX [a 1e400*2 -b]\n",
    'S ["x" "y"]\nT "a\\"b"\nU \u201cq\u201d\nN 12345678901234567890\nM 1e999\n',
    "O {\n  A 1 B { C [1 2] }\n  D 2 // c\n}\n}\nE 1 + 2\nF {}\n",
    "K 1 2\nL 1\n.5\nM [1\n2]\nN [1  2 ]\nP [1 2x]\nQ 3 x\nR 4.e5\n",
])
def test_same_entries_on_examples(text):
    assert_same(text)


def test_same_entries_at_the_token_and_nesting_limits():
    text = generate_scene(3) + "A [1 -2 x*2]\nB { C { D { E 1 } } }\n"
    for max_tokens in (1, 2, 3, 7, 20, 50, 133, 134, 135):
        assert_same(text, Limits(max_tokens=max_tokens))
    for max_nesting in (1, 2, 3):
        assert_same(text, Limits(max_nesting=max_nesting))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(ALPHABET, max_size=80).map(" ".join))
def test_same_entries_on_token_soup(text):
    assert_same(text)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_same_entries_on_mutated_files(text):
    assert_same(text)
