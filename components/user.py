"""Whom an object stands for, on a server several users join."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from components.blocks import BuildContext, Key, KeyDeclaration, declare_key


@dataclass(slots=True)
class UserOwned:
    """The user (``colosseum join --user NAME``) an object stands for — their avatar,
    wheelchair or hands: a server takes it out of the world a while after that user's node
    leaves, unless the user comes back first."""

    user: str


def build_user(user: str | None, ctx: BuildContext) -> list[Any]:
    """An object's ``User``: the user it stands for, on the network."""
    return [] if user is None else [UserOwned(user)]


USER_KEY = declare_key(KeyDeclaration(
    Key("User", "string", None, "the user (colosseum join --user NAME) it stands for — an "
        "avatar, a wheelchair, hands: a server takes it out of the world --leave-after s "
        "after that user's node leaves, unless the user comes back"), build_user))

