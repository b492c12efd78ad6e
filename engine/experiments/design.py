"""An experiment's design: factors and levels, within and between participants, blocks,
trials per cell, practice trials, the ordering, adaptive staircases; and the plan of trials
one participant meets.

The plan is a pure function of the design and the participant number (1, 2, ...), so a
session can be run, resumed or replayed and always meets the same trials:

- the *within* factors' levels combine into cells (every combination, the first factor
  slowest), each met ``repeats`` times in each of ``blocks`` blocks;
- the *between* factors' combinations are groups: participant ``p`` is in group
  ``(p - 1) mod groups``;
- ``order``: ``random`` shuffles each block with a generator seeded by the design's seed,
  the participant and the block; ``latin`` and ``balanced`` give participant ``p`` the row
  ``((p - 1) // groups) mod rows`` of a Latin square or a balanced Latin square of the
  cells (engine.experiments.ordering), so each group goes through whole squares;
  ``fixed`` keeps the cells' order;
- ``practice`` trials come first (block 0), in the participant's order of cells, and are
  marked as practice;
- staircases follow the factorial blocks, one block each; their trials are made as the
  answers come (engine.experiments.staircase).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

from engine.experiments.ordering import random_order, square
from engine.experiments.staircase import StaircaseSpec

#: Levels that switch a factor's anomaly off.
OFF_LEVELS = ("off", "none")
RESETS = ("trial", "never")
END_ON = ("finish", "response")


@dataclass(frozen=True, slots=True)
class Factor:
    """``Factor { ID Levels Within Variable Anomaly Param }``."""

    id: str
    levels: tuple[str, ...]
    within: bool = True
    variable: str | None = None
    anomaly: str | None = None
    param: str | None = None


@dataclass(frozen=True, slots=True)
class Design:
    """An ``Experiment`` block, checked."""

    id: str
    factors: tuple[Factor, ...] = ()
    staircases: tuple[StaircaseSpec, ...] = ()
    order: str = "random"
    blocks: int = 1
    repeats: int = 1
    practice: int = 0
    timeout: float = 60.0
    reset: str = "trial"
    end_on: str = "finish"
    seed: int = 0
    track: tuple[str, ...] = ()
    track_camera: bool = False
    track_rate: float = 30.0
    pause: float = 0.0
    where: str = ""

    @property
    def within(self) -> tuple[Factor, ...]:
        return tuple(f for f in self.factors if f.within)

    @property
    def between(self) -> tuple[Factor, ...]:
        return tuple(f for f in self.factors if not f.within)

    def cells(self) -> list[dict[str, str]]:
        """Every combination of the within factors' levels (one empty cell without any)."""
        within = self.within
        return [dict(zip([f.id for f in within], combo, strict=True))
                for combo in itertools.product(*(f.levels for f in within))]

    def groups(self) -> list[dict[str, str]]:
        between = self.between
        return [dict(zip([f.id for f in between], combo, strict=True))
                for combo in itertools.product(*(f.levels for f in between))]

    def group(self, participant: int) -> dict[str, str]:
        """The between factors' levels of a participant."""
        groups = self.groups()
        return groups[(participant - 1) % len(groups)]

    def row(self, participant: int) -> list[int] | None:
        """The participant's row of the square (latin, balanced), else None."""
        if self.order not in ("latin", "balanced"):
            return None
        rows = square(self.order, len(self.cells()))
        return rows[((participant - 1) // len(self.groups())) % len(rows)]

    def block_order(self, participant: int, block: int) -> list[int]:
        """The cells' order in one block (block 0: practice)."""
        n = len(self.cells())
        row = self.row(participant)
        if row is not None:
            return list(row)
        if self.order == "random":
            return random_order(n, self.seed, participant, block)
        return list(range(n))


@dataclass(frozen=True, slots=True)
class TrialPlan:
    """One trial of a participant's session: where it stands and its condition."""

    index: int                       # 1, 2, ... over the whole session
    block: int                       # 0: practice; then 1..blocks; then a staircase each
    block_trial: int                 # 1, 2, ... within its block
    condition: dict[str, str] = field(default_factory=dict)
    practice: bool = False
    cell: int | None = None          # the within cell's number (0-based), if any
    staircase: str | None = None     # the staircase this trial belongs to

    def key(self) -> str:
        return ",".join(f"{k}={v}" for k, v in self.condition.items())


def check_participant(participant: int) -> None:
    if not isinstance(participant, int) or participant < 1:
        raise ValueError(f"participant numbers start at 1, got {participant!r}")


def plan(design: Design, participant: int) -> list[TrialPlan]:
    """The participant's practice and factorial trials, in order (staircase trials are
    made as the answers come: :func:`staircase_trial`)."""
    check_participant(participant)
    trials: list[TrialPlan] = []
    if not design.factors:
        return trials
    cells, group = design.cells(), design.group(participant)

    def add(block: int, n: int, cell: int, practice: bool) -> None:
        trials.append(TrialPlan(len(trials) + 1, block, n, {**group, **cells[cell]},
                                practice, cell))

    practice_order = design.block_order(participant, 0)
    for i in range(design.practice):
        add(0, i + 1, practice_order[i % len(practice_order)], True)
    for block in range(1, design.blocks + 1):
        order = design.block_order(participant, block)
        n = 0
        for _ in range(design.repeats):
            for cell in order:
                n += 1
                add(block, n, cell, False)
    return trials


def staircase_trial(design: Design, participant: int, index: int, stair: int,
                    block_trial: int, intensity: float) -> TrialPlan:
    """A staircase's trial at ``intensity`` (trial ``index`` of the session)."""
    spec = design.staircases[stair]
    condition = {**(design.group(participant) if design.factors else {}),
                 spec.id: f"{intensity:.6g}"}
    return TrialPlan(index, design.blocks + 1 + stair, block_trial, condition, False, None,
                     spec.id)


def columns(design: Design) -> list[str]:
    """The condition columns of trials.csv: every factor, then every staircase."""
    return [f.id for f in design.factors] + [s.id for s in design.staircases]
