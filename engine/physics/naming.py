"""Backends' messages name scene objects, not entity numbers.

A backend knows bodies and joints by key (the entity id) and logs "body 7: ..."; an
author knows them by scene ID. :class:`SceneNames` is a logging filter the physics plugin
puts on the backends' loggers: it rewrites ``body N`` / ``joint N`` in their records to
``object 'crate'`` / ``joint 'hinge'`` for the keys its engine has names for, so no
backend needs to know the scene.

>>> import logging, sys
>>> logger = logging.getLogger("colosseum.physics.doctest")
>>> logger.addHandler(logging.StreamHandler(sys.stdout)); logger.propagate = False
>>> names = SceneNames({7: "crate"})
>>> names.install([logger])
>>> logger.warning("body %s: %s", 7, "mass is zero"); logger.warning("body 8: far away")
object 'crate': mass is zero
body 8: far away
>>> names.uninstall()
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable, Mapping

_KEY = re.compile(r"\b(body|joint) (-?\d+)\b")


def named(text: str, names: Mapping[int, str]) -> str:
    """``text`` with ``body N`` / ``joint N`` as ``object 'ID'`` / ``joint 'ID'`` for the
    keys ``names`` (entity -> scene ID) knows.

    >>> named("body 7: velocity beyond 1e5", {7: "crate"})
    "object 'crate': velocity beyond 1e5"
    """
    def scene_id(match: re.Match[str]) -> str:
        name = names.get(int(match[2]))
        if name is None:
            return match[0]
        return f"{'joint' if match[1] == 'joint' else 'object'} {name!r}"

    return _KEY.sub(scene_id, text)


class SceneNames(logging.Filter):
    """Rewrites backend records' ``body N`` and ``joint N`` to the scene IDs in ``names``
    (entity -> ID, the physics plugin's live table); keys it has no name for stay."""

    def __init__(self, names: Mapping[int, str]) -> None:
        super().__init__()
        self.names = names
        self._loggers: list[logging.Logger] = []

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        renamed = named(text, self.names)
        if renamed != text:
            record.msg, record.args = renamed, ()
        return True

    def install(self, loggers: Iterable[logging.Logger]) -> None:
        for logger in loggers:
            logger.addFilter(self)
            self._loggers.append(logger)

    def uninstall(self) -> None:
        for logger in self._loggers:
            logger.removeFilter(self)
        self._loggers.clear()


def backend_loggers() -> list[logging.Logger]:
    """The loggers of the physics backends imported so far (``colosseum.physics.*``)."""
    return [logging.getLogger(name) for name in sorted(logging.root.manager.loggerDict)
            if name.startswith("colosseum.physics.")]
