"""The one fast path (the compiled scanner, engine/scene/_scan.pyx) reads exactly what the
token path, the reference parser, reads.

Both must give the same SceneDB, every field of every node (places, expression texts,
comments and blank lines, one-line blocks, includes), the same warnings, or the same
errors at the same places, on generated and mutated scenes and at the token and
nesting limits. Skipped when the extension is not built (then the token path reads
everything and there is nothing to compare).
"""

from __future__ import annotations

import random
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import engine.scene.parser as scene_parser
from engine.scene import Block, Entry, Limits, SceneError, Value, generate_scene, parse_text
from engine.scene.parser import token_path_only
from tools.fuzz_scene import mutate, prepare, scene_text

compiled = pytest.importorskip("engine.scene._scan")

#: Scenes per hypothesis example, and examples: 10,000 scenes in all, a few seconds.
SCENES_PER_EXAMPLE = 25
EXAMPLES = 400
LIMITS = [None, None, None, Limits(max_tokens=7), Limits(max_tokens=40),
          Limits(max_tokens=133), Limits(max_nesting=1), Limits(max_nesting=2),
          Limits(max_nesting=3)]


def _dump(x: Any) -> Any:
    """Every field of a SceneDB node (an unset one raises), places as plain tuples and
    comment lists and tuples alike."""
    if isinstance(x, Value | Entry | Block):
        return type(x).__name__, tuple((f.name, _dump(getattr(x, f.name))) for f in fields(x))
    if isinstance(x, list) and all(isinstance(c, str) for c in x):
        return "strings", tuple(x)
    if isinstance(x, list):
        return [_dump(item) for item in x]
    if isinstance(x, tuple) and all(isinstance(c, str) for c in x):
        return "strings", x
    if isinstance(x, tuple):  # a Loc
        return type(x).__name__, tuple(x)
    return type(x).__name__, repr(x)


def _parse(text: str, limits: Limits | None, base: Path) -> Any:
    try:
        db = parse_text(text, "scan.scene", np.random.default_rng(0), limits, base_dir=base)
    except SceneError as exc:
        return "error", exc.diagnostics
    return _dump(db.root), db.warnings


def assert_same(text: str, base: Path, limits: Limits | None = None) -> None:
    fast = _parse(text, limits, base)
    with token_path_only():
        reference = _parse(text, limits, base)
    assert fast == reference, f"fast path and token path differ on {text!r} ({limits})"


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Files the generated scenes' ``Include`` lines name (see tools.fuzz_scene)."""
    base = prepare(tmp_path_factory.mktemp("fast_path"))
    (base / "part.scene").write_text(generate_scene(2))
    return base


def test_the_compiled_scanner_is_the_fast_path():
    assert scene_parser.scan_plain is compiled.scan_plain


@pytest.mark.parametrize("text", [
    generate_scene(30),
    'a 2\nV [1 -2 +3 .5 1. 1e3 2E-2 -0 -0.0 12345678901234567 1e999]\nW [ ]\nZ []\n',
    "a 2\nb -1\nV [a*2 -a/2 +a+1 a-1 pi e 3*a 1.5/a 2/0 a*b q]\nX [a 1e400*2 -b]\n",
    'S ["x" "y"]\nT "a\\"b"\nU \u201cq\u201d\nN 12345678901234567890\nM 1e999\n',
    'S [ "a"  "b" ]\nT ["a" 1]\nU ["a"\n"b"]\nV ["a""b"]\nW ["a" \u201cq\u201d]\nX ["a\\"b"]\n'
    'Y ["a" "b" x]\nZ ["" "\u00e9"]\nA ["a"] B 2\n',
    "O {\n  A 1 B { C [1 2] }\n  D 2 // c\n}\n}\nE 1 + 2\nF {}\n",
    "K 1 2\nL 1\n.5\nM [1\n2]\nN [1  2 ]\nP [1 2x]\nQ 3 x\nR 4.e5\n",
    "a 1\n\n\nb { c 2 }\n// x\n\nd 3\nE {\n\n  f 1\n\n  g [1 2]\n\n}\nH { i 1\n}\n",
    'Include "part.scene"\n\nA { Include "part.scene" }\n',
])
def test_same_entries_on_examples(text, folder):
    assert_same(text, folder)


def test_same_entries_at_the_token_and_nesting_limits(folder):
    text = generate_scene(3) + "A [1 -2 x*2]\nB { C { D { E 1 } } }\n"
    for max_tokens in (1, 2, 3, 7, 20, 50, 133, 134, 135):
        assert_same(text, folder, Limits(max_tokens=max_tokens))
    for max_nesting in (1, 2, 3):
        assert_same(text, folder, Limits(max_nesting=max_nesting))


def test_same_scene_db_on_ten_thousand_generated_and_mutated_scenes(folder):
    """Each example draws a seed; its scenes are generated from the grammar and, two in
    three, mutated (tools.fuzz_scene), each read under one of ``LIMITS``."""
    scenes = []

    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None)
    @given(st.integers(0, 2**63 - 1))
    def batch(seed: int) -> None:
        rng = random.Random(seed)
        for _ in range(SCENES_PER_EXAMPLE):
            text = scene_text(rng)
            if rng.random() < 2 / 3:
                text = mutate(rng, text, rng.randrange(1, 6))
            assert_same(text, folder, rng.choice(LIMITS))
            scenes.append(text)

    batch()
    assert len(scenes) >= 10_000, f"only {len(scenes)} scenes compared"
