"""Every scene file of today, and saved states written by today's code, build the same
world as when the golden dumps were taken (``python -m tools.scene_dump``, issue 32):
the net under moving the scene format's features onto the block registry."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tools.scene_dump import GOLDEN, ROOT, STATES, canonical, dump, golden_name, scene_files

pytest.importorskip("engine.physics.ode3d")

FILES = scene_files()


def test_every_scene_file_has_its_golden_dump() -> None:
    """A scene file added since is noticed (its dump is generated, not forgotten), and
    the saved states are among the inputs."""
    missing = [golden_name(p) for p in FILES if not (GOLDEN / golden_name(p)).exists()]
    assert not missing, f"run python -m tools.scene_dump: no golden dump for {missing}"
    assert len(list(STATES.glob("*.scene"))) >= 3


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_scene_builds_the_golden_world(path: Path) -> None:
    want = json.loads((GOLDEN / golden_name(path)).read_text(encoding="utf-8"))
    got = json.loads(json.dumps(dump(path), sort_keys=True, ensure_ascii=False))
    if got != want:
        pytest.fail(f"{path.relative_to(ROOT)} builds another world: "
                    f"{_first_difference(want, got)}")


def test_the_dump_sees_a_changed_value(tmp_path: Path) -> None:
    """The comparison can fail: one key changed in a scene changes its dump there."""
    source = (ROOT / "tests" / "scene" / "data" / "listing1.scene").read_text()
    assert "Mass" in source
    (tmp_path / "a.scene").write_text(source)
    (tmp_path / "b.scene").write_text(source.replace("Mass", "Mass 0.5 //", 1))
    a, b = dump(tmp_path / "a.scene"), dump(tmp_path / "b.scene")
    assert "error" not in a and "error" not in b
    assert a != b and "mass" in _first_difference(a, b)
    assert canonical(0.1 + 0.2) == canonical(0.3)  # rounding hides float noise only


def _first_difference(want: object, got: object, at: str = "") -> str:
    """Where two dumps part, as a path into them."""
    if isinstance(want, dict) and isinstance(got, dict):
        for k in sorted({*want, *got}):
            if want.get(k) != got.get(k):
                return _first_difference(want.get(k), got.get(k), f"{at}.{k}")
    if isinstance(want, list) and isinstance(got, list) and len(want) == len(got):
        for i, (w, g) in enumerate(zip(want, got, strict=True)):
            if w != g:
                return _first_difference(w, g, f"{at}[{i}]")
    return f"{at or 'top'}: was {str(want)[:200]}, is {str(got)[:200]}"
