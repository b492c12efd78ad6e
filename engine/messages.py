"""Messages that repeat are said once, then counted.

A script that sends the same bad value every frame, or a device that keeps sending
malformed packets, must not flood the log with identical lines: the first one is
logged, the repeats are counted and reported as one line ("... (repeated 299 times)")
at most every :attr:`MessageLog.interval` seconds and when the run ends. Messages that
differ only in their numbers (a frame, a falling body's height in the value refused)
are the same message: numbers standing alone (and runs of spaces) are left out when
they are compared; names with digits in them ("crate2") are not.

>>> import logging, sys
>>> logger = logging.getLogger("doctest.messages")
>>> logger.addHandler(logging.StreamHandler(sys.stdout)); logger.propagate = False
>>> messages = MessageLog(logger, clock=lambda: 0.0)
>>> for _ in range(3):
...     messages.warn("body 'crate' left the world")
body 'crate' left the world
>>> messages.flush()
body 'crate' left the world (repeated 2 more times)
"""

from __future__ import annotations

import logging
import re
import threading
import time
from collections.abc import Callable

#: Distinct messages remembered; past this, those without pending repeats are forgotten.
MAX_DISTINCT = 10_000
#: A number standing alone (not part of a name such as "crate2" or "c17").
_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?(?![\w])|"
                     r"(?<![\w.])[-+]?(?:nan|inf)\b")


def same_message(message: str) -> str:
    """What two messages are compared by: the text with its numbers left out.

    >>> same_message("frame 12: x = 1e+30 for 'crate2'")
    "frame #: x = # for 'crate2'"
    """
    return " ".join(_NUMBER.sub("#", message).split())


class MessageLog:
    """Logs each distinct message once, then counts its repeats."""

    def __init__(self, logger: logging.Logger, interval: float = 5.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.logger = logger
        self.interval = interval
        self.clock = clock
        #: message, numbers left out -> (level, repeats not reported yet, when last reported,
        #: the message as first told)
        self._seen: dict[str, tuple[int, int, float, str]] = {}
        self._lock = threading.Lock()

    def warn(self, message: str, where: str = "", key: str | None = None) -> None:
        self.say(logging.WARNING, message, where, key)

    def error(self, message: str, where: str = "", key: str | None = None) -> None:
        self.say(logging.ERROR, message, where, key)

    def say(self, level: int, message: str, where: str = "", key: str | None = None) -> None:
        """Log ``message`` (prefixed by ``where``, e.g. "frame 12: ", the first time only);
        repeats of the same ``message`` are counted, or of the same ``key`` where one is
        given (messages whose details a sender chooses: one line per sender, not one per
        variant it makes up)."""
        now = self.clock()
        key = same_message(message) if key is None else key
        with self._lock:
            seen = self._seen.get(key)
            if seen is None:
                if len(self._seen) >= MAX_DISTINCT:
                    self._seen = {m: v for m, v in self._seen.items() if v[1]}
                self._seen[key] = (level, 0, now, message)
                report = where + message
            else:
                _, repeats, last, first = seen
                repeats += 1
                if now - last < self.interval:
                    self._seen[key] = (level, repeats, last, first)
                    return
                self._seen[key] = (level, 0, now, first)
                report = f"{first} (repeated {repeats} more times)"
        self.logger.log(level, report)

    def flush(self) -> None:
        """Report the repeats not reported yet (at the end of a run)."""
        with self._lock:
            pending = [(key, level, n, first)
                       for key, (level, n, _, first) in self._seen.items() if n]
            for key, level, _, first in pending:
                self._seen[key] = (level, 0, self.clock(), first)
        for _, level, repeats, first in pending:
            self.logger.log(level, "%s (repeated %d more times)", first, repeats)
