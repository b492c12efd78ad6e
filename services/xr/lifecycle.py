"""An OpenXR session's life, as a state machine over the runtime's state changes.

The runtime moves a session IDLE → READY → SYNCHRONIZED → VISIBLE → FOCUSED and back,
through STOPPING to IDLE, and ends it with EXITING (the user or the engine asked to
quit) or LOSS_PENDING (the runtime or the headset went away). What the engine must do
at each change is decided here, with no runtime: READY begins the session, STOPPING
ends it, EXITING and LOSS_PENDING end the run. Input acts only while FOCUSED; the
world is drawn while the session runs and the runtime asks for frames; a headset
taken off (VISIBLE or FOCUSED back to SYNCHRONIZED) pauses the simulation or keeps it
going, as the scene says (``Display { WhenHidden "pause" }``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum, IntEnum


class SessionState(IntEnum):
    """``XrSessionState``, with the specification's values."""

    UNKNOWN = 0
    IDLE = 1
    READY = 2
    SYNCHRONIZED = 3
    VISIBLE = 4
    FOCUSED = 5
    STOPPING = 6
    LOSS_PENDING = 7
    EXITING = 8


#: How far along the way to the headset a state is (STOPPING and the ends are not).
PROGRESS = (SessionState.IDLE, SessionState.READY, SessionState.SYNCHRONIZED,
            SessionState.VISIBLE, SessionState.FOCUSED)
RUNNING = (SessionState.SYNCHRONIZED, SessionState.VISIBLE, SessionState.FOCUSED)
SHOWN = (SessionState.VISIBLE, SessionState.FOCUSED)


class Action(Enum):
    """What the engine does at a state change."""

    BEGIN = "begin"  # xrBeginSession: frames are asked for from now on
    END = "end"  # xrEndSession: the runtime stopped asking
    QUIT = "quit"  # end the run: the session is over (exiting, or lost)


WHEN_HIDDEN = ("pause", "run")


@dataclass(slots=True)
class Lifecycle:
    """The session's standing, fed the runtime's state changes one by one."""

    #: ``pause``: a headset taken off stops the simulation until it is back on; ``run``:
    #: the world goes on.
    when_hidden: str = "run"
    state: SessionState = SessionState.UNKNOWN
    furthest: SessionState = SessionState.UNKNOWN
    #: Between xrBeginSession and xrEndSession: frames must be waited for and ended.
    running: bool = False
    #: Why the run ended ("exiting", "lost"); None while it goes on.
    ended: str | None = None
    history: list[SessionState] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.when_hidden not in WHEN_HIDDEN:
            raise ValueError(f"WhenHidden must be one of {', '.join(WHEN_HIDDEN)}, "
                             f"not {self.when_hidden!r}")

    @property
    def focused(self) -> bool:
        """Input from the headset's controllers acts only now."""
        return self.state == SessionState.FOCUSED

    @property
    def shown(self) -> bool:
        return self.state in SHOWN

    @property
    def paused(self) -> bool:
        """The simulation waits: a running session not shown, when the scene says so."""
        return self.when_hidden == "pause" and self.running and not self.shown \
            and SessionState.VISIBLE in self.history

    def change(self, state: SessionState | int) -> list[Action]:
        """The runtime says the session is now ``state``; what to do, in order."""
        state = SessionState(state)
        self.state = state
        self.history.append(state)
        if state in PROGRESS and PROGRESS.index(state) > (
                PROGRESS.index(self.furthest) if self.furthest in PROGRESS else -1):
            self.furthest = state
        if state == SessionState.READY and not self.running:
            self.running = True
            return [Action.BEGIN]
        if state == SessionState.STOPPING and self.running:
            self.running = False
            return [Action.END]
        if state in (SessionState.EXITING, SessionState.LOSS_PENDING):
            actions = [Action.END] if self.running else []
            self.running = False
            self.ended = "exiting" if state == SessionState.EXITING else "lost"
            return [*actions, Action.QUIT]
        return []

    def instance_lost(self) -> list[Action]:
        """The runtime itself is going (``XrEventDataInstanceLossPending``)."""
        actions = [Action.END] if self.running else []
        self.running = False
        self.ended = "lost"
        return [*actions, Action.QUIT]


def replay(states: list[SessionState | int], when_hidden: str = "run"
           ) -> tuple[Lifecycle, list[Action]]:
    """Feed a recorded sequence of state changes; the lifecycle and every action taken.

    >>> life, actions = replay([1, 2, 3, 4, 5, 6, 1, 8])
    >>> [a.value for a in actions], life.furthest.name, life.ended
    (['begin', 'end', 'quit'], 'FOCUSED', 'exiting')
    """
    life = Lifecycle(when_hidden=when_hidden)
    actions: list[Action] = []
    for state in states:
        actions.extend(life.change(state))
    return life, actions
