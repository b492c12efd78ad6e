"""The sample models, written once per test session by app/bench/interchange_samples.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.bench import interchange_samples


@pytest.fixture(scope="session")
def samples(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding every sample model (shapes.glb, joints.glb, ...)."""
    folder = tmp_path_factory.mktemp("models")
    for name, make in interchange_samples.SAMPLES.items():
        make(folder / name)
    return folder


@pytest.fixture
def models(samples: Path, tmp_path: Path) -> Path:
    """A test's own copy of the sample folder (tests write scene files beside them)."""
    for path in samples.iterdir():
        (tmp_path / path.name).write_bytes(path.read_bytes())
    return tmp_path
