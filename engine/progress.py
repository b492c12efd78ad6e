"""Progress on a terminal: a bar for work of known length, a spinner for the rest (rich).

Drawn on stderr only when it is a terminal, so logs, pipes and CI stay clean; elsewhere
the calls cost nothing.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Protocol


class Report(Protocol):
    def __call__(self, done: float, text: str = "") -> None: ...


def on_terminal() -> bool:
    return sys.stderr.isatty()


@contextmanager
def progress(title: str, total: float | None = None, shown: bool | None = None
             ) -> Iterator[Report]:
    """A progress display for ``title``; yields ``report(done, text)``. ``total`` None
    shows a spinner with the elapsed time (work of unknown length)."""
    if not (on_terminal() if shown is None else shown):
        yield lambda done, text="": None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        Progress,
        SpinnerColumn,
        TaskProgressColumn,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = [SpinnerColumn(), TextColumn("{task.description}")]
    if total is not None:
        columns += [BarColumn(), TaskProgressColumn(), TimeRemainingColumn()]
    columns += [TimeElapsedColumn(), TextColumn("{task.fields[text]}")]
    with Progress(*columns, console=Console(stderr=True), transient=False) as bar:
        task = bar.add_task(title, total=total, text="")

        def report(done: float, text: str = "") -> None:
            bar.update(task, completed=done, text=text)

        yield report
