"""Bad input: random and mutated files raise only SceneError, never hang, point inside the file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from engine.scene import SceneError, build_specs, parse_text, validated

DATA = Path(__file__).parent / "data"
SEEDS = [(DATA / "listing1.scene").read_text(), (DATA / "paper" / "main.scene").read_text(),
         (DATA / "representative" / "main.scene").read_text()]
ALPHABET = st.sampled_from(list('{}[]()",/*+-^ \n\t\u201c\u201d\\.e0123456789aZ_#$') +
                           ["Object", "ID", "Include", "Size", "//", "/*", "*/", "Geometry",
                            "Primitive", "sphere", "1e999", "randInterval(", "Joint"])


def pipeline(text: str) -> None:
    """Everything a load does short of creating entities."""
    db = validated(parse_text(text, "fuzz.scene", np.random.default_rng(0)),
                   DATA / "representative")
    build_specs(db, DATA / "representative")


def assert_only_scene_errors_inside(text: str) -> None:
    try:
        pipeline(text)
    except SceneError as exc:
        assert exc.errors, "a SceneError always carries an error"
        lines = text.split("\n")
        for d in exc.diagnostics:
            assert d.path == "fuzz.scene"
            assert 1 <= d.line <= len(lines), d
            assert 1 <= d.col <= len(lines[d.line - 1]) + 1, d
            assert str(exc)  # renders


@settings(max_examples=300, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=300))
def test_random_text(text):
    assert_only_scene_errors_inside(text)


@settings(max_examples=300, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(ALPHABET, max_size=80).map(" ".join))
def test_random_token_soup(text):
    assert_only_scene_errors_inside(text)


@st.composite
def mutated(draw):
    text = draw(st.sampled_from(SEEDS))
    for _ in range(draw(st.integers(1, 6))):
        i = draw(st.integers(0, len(text)))
        j = min(len(text), i + draw(st.integers(0, 12)))
        op = draw(st.sampled_from(["delete", "insert", "replace", "duplicate"]))
        if op == "delete":
            text = text[:i] + text[j:]
        elif op == "insert":
            text = text[:i] + draw(ALPHABET) + text[i:]
        elif op == "replace":
            text = text[:i] + draw(ALPHABET) + text[j:]
        else:
            text = text[:j] + text[i:j] + text[j:]
    return text


@settings(max_examples=400, deadline=2000, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_content_files(text):
    assert_only_scene_errors_inside(text)
