"""Messages that repeat are said once, then counted.

A script that sends the same bad value every frame, or a device that keeps sending
malformed packets, must not flood the log with identical lines: the first one is
logged, the repeats are counted and reported as one line ("... (repeated 299 times)")
at most every :attr:`MessageLog.interval` seconds and when the run ends.

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
import threading
import time
from collections.abc import Callable

#: Distinct messages remembered; past this, those without pending repeats are forgotten.
MAX_DISTINCT = 10_000


class MessageLog:
    """Logs each distinct message once, then counts its repeats."""

    def __init__(self, logger: logging.Logger, interval: float = 5.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.logger = logger
        self.interval = interval
        self.clock = clock
        #: message -> (level, repeats not reported yet, when last reported)
        self._seen: dict[str, tuple[int, int, float]] = {}
        self._lock = threading.Lock()

    def warn(self, message: str, where: str = "") -> None:
        self.say(logging.WARNING, message, where)

    def error(self, message: str, where: str = "") -> None:
        self.say(logging.ERROR, message, where)

    def say(self, level: int, message: str, where: str = "") -> None:
        """Log ``message`` (prefixed by ``where``, e.g. "frame 12: ", the first time only);
        repeats of the same ``message`` are counted."""
        now = self.clock()
        with self._lock:
            seen = self._seen.get(message)
            if seen is None:
                if len(self._seen) >= MAX_DISTINCT:
                    self._seen = {m: v for m, v in self._seen.items() if v[1]}
                self._seen[message] = (level, 0, now)
                report = where + message
            else:
                _, repeats, last = seen
                repeats += 1
                if now - last < self.interval:
                    self._seen[message] = (level, repeats, last)
                    return
                self._seen[message] = (level, 0, now)
                report = f"{message} (repeated {repeats} more times)"
        self.logger.log(level, report)

    def flush(self) -> None:
        """Report the repeats not reported yet (at the end of a run)."""
        with self._lock:
            pending = [(m, level, n) for m, (level, n, _) in self._seen.items() if n]
            for message, level, _ in pending:
                self._seen[message] = (level, 0, self.clock())
        for message, level, repeats in pending:
            self.logger.log(level, "%s (repeated %d more times)", message, repeats)
