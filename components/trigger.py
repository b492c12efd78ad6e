"""Sensor volumes."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(slots=True)
class Trigger:
    """A sensor: the entity's Physical shapes (a body nothing collides with) detect the
    bodies whose collision category meets ``mask``. ``inside`` holds the entities in it
    now (kept by the trigger system), so entering and leaving are told once each."""

    mask: int = 0xFFFFFFFF
    inside: set[int] = field(default_factory=set)
