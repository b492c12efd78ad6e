"""A virtual hand's configuration."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class Hand:
    """A physically simulated virtual hand driven toward a tracked pose with bounded
    force (N) and torque (N·m); ``deviation_distance`` (m) is where the real and the
    virtual hand are taken apart (paper section 5.4)."""

    tracker: str = ""
    max_force: float = 300.0
    max_torque: float = 30.0
    deviation_distance: float = 0.3
