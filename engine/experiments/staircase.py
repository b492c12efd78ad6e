"""Adaptive procedures: a transformed up/down staircase and a QUEST-style Bayesian one.

The intensity is the stimulus' strength (a contrast loss, a blur): a correct answer (the
participant saw it) makes the next trial harder, one step down; a wrong one easier. An
``up``-up/``down``-down staircase goes down after ``down`` correct answers in a row and up
after ``up`` wrong ones in a row, so it converges to the intensity seen with probability
p where p^down = 0.5 for up = 1 (Levitt, 1971): 1-up/1-down 50 %, 1-up/2-down 70.7 %,
1-up/3-down 79.4 %. A reversal is a change of direction; each one takes the next of the
step sizes (the last one stays), and the threshold is the mean of the last ``average``
reversals' intensities (of all trials' when there were too few reversals).

QUEST (Watson & Pelli, 1983) keeps a posterior over the threshold on a grid, with a
logistic psychometric function of the given slope, guess and lapse rates, and places each
trial at the posterior mean; its estimate is the posterior mean.

Both are pure functions of the answers so far: a resumed session rebuilds a staircase by
feeding it the answers its trials.csv holds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

METHODS = ("updown", "quest")


@dataclass(frozen=True, slots=True)
class StaircaseSpec:
    """An ``Experiment { Staircase { ... } }`` block."""

    id: str
    start: float = 0.5
    steps: tuple[float, ...] = (0.1,)
    up: int = 1
    down: int = 3
    trials: int = 40
    reversals: int = 0
    minimum: float = 0.0
    maximum: float = 1.0
    average: int = 6
    method: str = "updown"
    response: str = "seen"
    slope: float = 10.0
    guess: float = 0.0
    lapse: float = 0.01
    variable: str | None = None
    anomaly: str | None = None
    param: str | None = None


@dataclass(slots=True)
class Staircase:
    """One staircase's state: ``intensity`` is the next trial's, :meth:`answer` moves it."""

    spec: StaircaseSpec
    intensity: float = 0.0
    history: list[tuple[float, bool]] = field(default_factory=list)
    reversal_intensities: list[float] = field(default_factory=list)
    _run: int = 0            # > 0: correct answers in a row; < 0: wrong ones
    _direction: int = 0      # the last move: -1 down, +1 up, 0 none yet
    _grid: np.ndarray | None = None
    _log_post: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.intensity = self._clamp(self.spec.start)
        if self.spec.method == "quest":
            s = self.spec
            self._grid = np.linspace(s.minimum, s.maximum, 401)
            spread = (s.maximum - s.minimum) / 4.0 or 1.0  # a wide prior about Start
            self._log_post = -0.5 * ((self._grid - s.start) / spread) ** 2

    def _clamp(self, x: float) -> float:
        return round(min(max(float(x), self.spec.minimum), self.spec.maximum), 12)

    @property
    def step(self) -> float:
        """The step size now: one per reversal so far, the last one kept."""
        steps = self.spec.steps
        return steps[min(len(self.reversal_intensities), len(steps) - 1)]

    @property
    def done(self) -> bool:
        s = self.spec
        return len(self.history) >= s.trials or (
            s.reversals > 0 and len(self.reversal_intensities) >= s.reversals)

    def probability(self, intensity: float, threshold: float) -> float:
        """QUEST's psychometric function: the chance of a correct answer."""
        s = self.spec
        core = 1.0 / (1.0 + math.exp(-s.slope * (intensity - threshold)))
        return s.guess + (1.0 - s.guess - s.lapse) * core

    def answer(self, correct: bool) -> None:
        """The answer to the trial at :attr:`intensity`; the next intensity follows."""
        x = self.intensity
        self.history.append((x, bool(correct)))
        if self.spec.method == "quest":
            self._quest(x, bool(correct))
            return
        s = self.spec
        if correct:
            self._run = self._run + 1 if self._run > 0 else 1
        else:
            self._run = self._run - 1 if self._run < 0 else -1
        move = 0
        if self._run >= s.down:
            move, self._run = -1, 0
        elif -self._run >= s.up:
            move, self._run = 1, 0
        if move == 0:
            return
        if self._direction and move != self._direction:
            self.reversal_intensities.append(x)
        self._direction = move
        self.intensity = self._clamp(x + move * self.step)

    def _quest(self, x: float, correct: bool) -> None:
        assert self._grid is not None and self._log_post is not None
        s = self.spec
        core = 1.0 / (1.0 + np.exp(-s.slope * (x - self._grid)))
        p = s.guess + (1.0 - s.guess - s.lapse) * core
        self._log_post = self._log_post + np.log(p if correct else 1.0 - p)
        self.intensity = self._clamp(self.estimate)

    @property
    def estimate(self) -> float:
        """The threshold as estimated now."""
        if self.spec.method == "quest":
            assert self._grid is not None and self._log_post is not None
            w = np.exp(self._log_post - self._log_post.max())
            return float((w * self._grid).sum() / w.sum())
        rev = self.reversal_intensities
        if len(rev) >= 2:
            last = rev[-min(self.spec.average, len(rev)):]
            return float(sum(last) / len(last))
        xs = [x for x, _ in self.history] or [self.intensity]
        return float(sum(xs) / len(xs))


def replayed(spec: StaircaseSpec, answers: list[bool]) -> Staircase:
    """The staircase after ``answers`` (a resumed session's)."""
    stair = Staircase(spec)
    for correct in answers:
        stair.answer(correct)
    return stair


def simulated_observer(threshold: float, slope: float, seed: int,
                       guess: float = 0.0, lapse: float = 0.0):  # type: ignore[no-untyped-def]
    """A simulated participant: answers correctly with a logistic probability of the
    intensity about ``threshold`` (fixed ``seed``)."""
    rng = np.random.default_rng(seed)

    def respond(intensity: float) -> bool:
        core = 1.0 / (1.0 + math.exp(-slope * (intensity - threshold)))
        return bool(rng.random() < guess + (1.0 - guess - lapse) * core)

    return respond
