"""The --stats file: every key documented with its unit, the file valid against the schema
(docs/stats.schema.json), and drawing counted when a --screenshot is the only frame drawn."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import jsonschema

from engine.stats import STATS_SCHEMA, stats_markdown
from tools.docs import DOCS, manual_pages


def test_the_pages_are_generated_from_the_schema_and_linked() -> None:
    assert (DOCS / "STATS.md").read_text(encoding="utf-8") == stats_markdown()
    assert json.loads((DOCS / "stats.schema.json").read_text(encoding="utf-8")) == STATS_SCHEMA
    jsonschema.Draft202012Validator.check_schema(STATS_SCHEMA)
    assert "STATS.md" in manual_pages()  # in the manual's navigation (mkdocs.yml)


def test_a_headless_screenshot_run_writes_valid_stats_with_its_drawing_counted(
        tmp_path: Path) -> None:
    """Headless, only the --screenshot frame is drawn (at the end): it used to show as
    zero render time; now it counts."""
    stats, shot = tmp_path / "stats.json", tmp_path / "shot.png"
    result = subprocess.run([sys.executable, "-m", "app.cli", "run", "--frames", "30",
                             "--fast", "--headless", "--screenshot", shot, "--stats", stats],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    data = json.loads(stats.read_text())
    jsonschema.validate(data, STATS_SCHEMA)
    assert shot.is_file()
    render = data["render"]
    assert render["frames_drawn"] == 1 and render["render_ms_mean"] > 0
    assert render["render_ms_last"] == render["render_ms_mean"] and render["draw_calls"] > 0
    assert data["frames"] == 30 and data["sim_seconds"] == 0.3  # the demo's 0.01 s step


def test_every_key_written_has_a_unit_in_the_schema() -> None:
    for name, spec in STATS_SCHEMA["properties"].items():
        for key, leaf in spec.get("properties", {name: spec}).items():
            assert "x-unit" in leaf and leaf["description"], (name, key)
