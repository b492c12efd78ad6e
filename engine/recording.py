"""``--record``/``--replay`` moved to :mod:`engine.input` (kept here while engine/cli.py
imports them from this module)."""

from engine.input import InputRecorder, InputReplayer, ReplayError

__all__ = ["InputRecorder", "InputReplayer", "ReplayError"]
