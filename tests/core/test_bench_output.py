"""``colosseum bench ... --json`` and ``--plot`` (our figure beside its reference, from one
run), and progress shown on a terminal only."""

from __future__ import annotations

import json
import os
import pty
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from app.bench import BENCHMARKS, FIGURES, measure, report


def colosseum(*args: object, **kw: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=300, **kw)


@pytest.mark.parametrize("what", list(BENCHMARKS))
def test_every_benchmark_gives_figures_beside_their_references(what: str) -> None:
    rows = measure(what, quick=True)
    data = report(what, rows, quick=True)
    assert json.loads(json.dumps(data)) == data  # plain data
    assert data["figures"], f"{what}: no figure found in its rows (FIGURES out of date?)"
    for figure in data["figures"]:
        assert figure["ours"] > 0 and figure["reference"] > 0
        assert figure["ratio"] == pytest.approx(figure["ours"] / figure["reference"])
        assert figure["unit"] and figure["reference_is"]
    assert set(FIGURES) == set(BENCHMARKS)


def test_json_alone_on_stdout_and_a_plot_file(tmp_path: Path) -> None:
    plot = tmp_path / "out" / "scheduler.png"
    plot.parent.mkdir()
    result = colosseum("bench", "scheduler", "--quick", "--json", "--plot", plot)
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)  # nothing but the JSON
    assert data["benchmark"] == "scheduler" and len(data["figures"]) == 2
    assert [f["label"] for f in data["figures"]] == ["serial, 10 systems",
                                                     "threaded, 10 systems"]
    with Image.open(plot) as image:
        assert image.format == "PNG" and image.size[0] >= 600
        colours = np.unique(np.asarray(image.convert("RGB")).reshape(-1, 3), axis=0)
        assert len(colours) > 10  # bars, not a blank page


def test_json_to_a_file_keeps_the_table(tmp_path: Path) -> None:
    out = tmp_path / "b.json"
    result = colosseum("bench", "scripting", "--quick", "--json", out)
    assert result.returncode == 0, result.stderr
    assert "colosseum bench scripting" in result.stdout and "reference" in result.stdout
    assert json.loads(out.read_text())["rows"][0]["benchmark"].startswith("onUpdate")
    missing = colosseum("bench", "scripting", "--quick", "--plot", tmp_path / "no" / "p.png")
    assert missing.returncode == 2 and "does not exist" in missing.stderr


def _on_a_terminal(*args: object) -> str:
    """stderr of the command when it is a terminal (a pseudo-terminal)."""
    main, side = pty.openpty()
    try:
        proc = subprocess.Popen([sys.executable, "-m", "app.cli", *map(str, args)],
                                stdout=subprocess.DEVNULL, stderr=side, stdin=subprocess.DEVNULL)
        os.close(side)
        chunks = []
        while True:
            try:
                chunk = os.read(main, 65536)
            except OSError:  # the other end closed
                break
            if not chunk:
                break
            chunks.append(chunk)
        assert proc.wait(timeout=120) == 0
    finally:
        os.close(main)
    return b"".join(chunks).decode("utf-8", "replace")


def test_a_limited_run_shows_a_bar_on_a_terminal_and_nothing_in_a_pipe() -> None:
    shown = _on_a_terminal("run", "--frames", "120", "--fast", "--headless")
    assert "running" in shown and "100%" in shown and "rtf" in shown  # bar, status text
    piped = colosseum("run", "--frames", "120", "--fast", "--headless")
    assert "running" not in piped.stderr and "100%" not in piped.stderr
    lines = colosseum("run", "--frames", "120", "--headless", "--progress")  # paced: > 1 s
    assert re.search(r"t=\s*\d+\.\d\ds frame\s+\d+  rtf", lines.stderr)  # a status line


def test_a_bench_shows_a_spinner_on_a_terminal() -> None:
    assert "bench scheduler" in _on_a_terminal("bench", "scheduler", "--quick")


def test_the_help_names_every_benchmark() -> None:
    shown = colosseum("bench", "--help")
    assert shown.returncode == 0
    listed = set(re.findall(r"[a-z]+", " ".join(shown.stdout.split())))
    assert set(BENCHMARKS) <= listed, set(BENCHMARKS) - listed


def test_a_table_per_kind_of_row_with_no_blank_column(capsys: pytest.CaptureFixture[str]
                                                       ) -> None:
    """Rows of two kinds print as two tables, each with only its own columns, under its
    title; rows without a kind are grouped by their columns."""
    from app.bench import kinds, print_table

    step = "one step, ms/step; reference: plain C"
    rows = [{"kind": step, "N": 100, "ours ms": 1.5, "C ms": 1.25},
            {"N": 100, "readback us": 3.0},
            {"kind": step, "N": 500, "ours ms": 7.5, "C ms": 6.0},
            {"N": 500, "readback us": 9.0}]
    assert [(kind, [r["N"] for r in group]) for kind, group in kinds(rows)] == [
        (step, [100, 500]), ("", [100, 500])]
    print_table(rows)
    lines = capsys.readouterr().out.splitlines()
    assert lines[1] == step and "kind" not in lines[2]
    assert lines[2].split() == ["N", "ours", "ms", "C", "ms"]
    assert lines[4].split() == ["100", "1.5", "1.25"]  # no blank cells to skip
    blank = lines.index("", 2)
    assert lines[blank + 1].split() == ["N", "readback", "us"]
    assert lines[blank + 3].split() == ["100", "3"] and len(lines) == blank + 5


def test_bench_physics_prints_its_step_and_readback_tables_apart() -> None:
    """No column of one table is blank in the other's rows (they were one table)."""
    from app.bench import kinds
    from app.bench.physics import READBACK_KIND, STEP_KIND

    rows = measure("physics", quick=True)
    grouped = dict(kinds(rows))
    assert list(grouped) == [STEP_KIND, READBACK_KIND]
    for group in grouped.values():
        assert all(set(row) == set(group[0]) for row in group)
    assert "ms/step" in STEP_KIND and "plain C" in STEP_KIND
