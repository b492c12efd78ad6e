"""Mutated models, images and sounds end in a loaded asset or a message: short fixed-seed
runs of tools/fuzz.py's models, images and sounds targets."""

from __future__ import annotations

import pytest

from tools.fuzz_assets import IMAGES, MODELS, SOUNDS


@pytest.mark.parametrize(("target", "inputs"), [(MODELS, 120), (IMAGES, 120), (SOUNDS, 60)],
                         ids=["models", "images", "sounds"])
def test_fuzzed_assets_load_or_are_told(target, inputs, fuzz_briefly):
    fuzz_briefly(target, inputs)
