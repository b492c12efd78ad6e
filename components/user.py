"""Whom an object stands for, on a server several users join."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class UserOwned:
    """The user (``colosseum join --user NAME``) an object stands for — their avatar,
    wheelchair or hands: a server takes it out of the world a while after that user's node
    leaves, unless the user comes back first."""

    user: str
