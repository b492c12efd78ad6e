"""The scene key reference is the schema's (docs/KEYS.md, ``colosseum keys``)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from engine.scene import parse_text, schema
from engine.scene.blocks import from_content
from engine.scene.keys import block_text, blocks, example, find_block, reference_markdown
from tools.docs import DOCS, manual_pages


def test_the_page_is_generated_from_the_schema_and_linked() -> None:
    assert (DOCS / "KEYS.md").read_text(encoding="utf-8") == reference_markdown(), \
        "docs/KEYS.md is stale: run python -m tools.docs"
    assert "KEYS.md" in manual_pages()  # in the manual's navigation (mkdocs.yml)


def test_every_key_has_a_meaning_and_an_example_that_parses() -> None:
    page = reference_markdown()
    for block in blocks():  # the engine's own (a content folder's are its own to document)
        assert f"## {block}\n" in page
        for key, field in schema.SCHEMAS[block].items():
            if field.struct and from_content(field.struct):
                continue
            assert field.doc, f"{block}/{key} has no meaning in the schema"
            assert f"| `{key}` |" in page
            text = example(block, key, field)
            if field.type != schema.STRUCT_T:
                parsed = parse_text(text + "\n")  # it is scene text
                assert parsed.root.entries[0].key == key


@pytest.mark.parametrize(("asked", "block"), [("camera", "Camera"), ("VisualAttributes", "Visual"),
                                             ("uniform", "Uniform")])
def test_keys_prints_a_block_by_its_name_or_the_key_that_opens_it(asked: str, block: str) -> None:
    result = subprocess.run([sys.executable, "-m", "app.cli", "keys", asked],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0
    assert find_block(asked) == block and result.stdout == block_text(block) + "\n"
    for key in schema.SCHEMAS[block]:
        assert f"\n  {key} " in result.stdout


def test_keys_without_a_block_lists_them_and_a_wrong_one_is_a_usage_error() -> None:
    listing = subprocess.run([sys.executable, "-m", "app.cli", "keys"], capture_output=True,
                             text=True, timeout=60)
    assert [line.split()[0] for line in listing.stdout.splitlines()[:len(blocks())]] == \
        blocks()
    wrong = subprocess.run([sys.executable, "-m", "app.cli", "keys", "Objekt"],
                           capture_output=True, text=True, timeout=60)
    assert wrong.returncode == 2 and "did you mean 'Object'?" in wrong.stderr
