"""CURVE keys: ZeroMQ's encryption and client authentication, laid out in one folder.

``colosseum keygen DIR --user alice`` makes (once; existing keys are kept)::

    DIR/server.key  DIR/server.key_secret          the server's pair
    DIR/users/alice.key  DIR/users/alice.key_secret  one pair per user

``serve --key DIR`` uses the server's secret key and accepts only the users whose public
key is in ``DIR/users``, each only under its own name (the key file's); ``join --key DIR
--user alice`` needs ``server.key`` (public) and ``users/alice.key_secret``. Hand each user
only those two files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import zmq
import zmq.auth


class KeyProblem(Exception):
    """Keys that cannot be used; the message names the file."""


@dataclass(frozen=True, slots=True)
class ServerKeys:
    public: bytes
    secret: bytes
    users: Path
    #: Each user's public key (Z85, the User-Id CURVE gives their messages) -> their name
    #: (the key file's): a node may join only as the user its key is.
    names: dict[str, str]


@dataclass(frozen=True, slots=True)
class ClientKeys:
    public: bytes
    secret: bytes
    server: bytes


def make_keys(folder: Path, users: list[str]) -> list[Path]:
    """Create the server's pair and each user's (those missing); returns the files made."""
    if not zmq.has("curve"):
        raise KeyProblem("this libzmq was built without CURVE; keys cannot be made")
    made: list[Path] = []
    (folder / "users").mkdir(parents=True, exist_ok=True)
    for where, name in [(folder, "server"), *((folder / "users", u) for u in users)]:
        if not (where / f"{name}.key_secret").exists():
            public, secret = zmq.auth.create_certificates(str(where), name)
            made += [Path(public), Path(secret)]
    return made


def _load(path: Path, secret: bool) -> tuple[bytes, bytes | None]:
    if not path.is_file():
        raise KeyProblem(f"{path}: no such key file (make keys with `colosseum keygen DIR "
                        "--user NAME`)")
    try:
        public, private = zmq.auth.load_certificate(str(path))
    except (ValueError, OSError) as exc:
        raise KeyProblem(f"{path}: not a ZeroMQ key file ({exc})") from None
    if secret and private is None:
        raise KeyProblem(f"{path}: holds no secret key")
    return public, private


def server_keys(folder: Path) -> ServerKeys:
    public, secret = _load(folder / "server.key_secret", True)
    users = folder / "users"
    if not users.is_dir() or not any(users.glob("*.key")):
        raise KeyProblem(f"{users}: no user keys; no node could join (make them with "
                        "`colosseum keygen DIR --user NAME`)")
    assert secret is not None
    names = {_load(key, False)[0].decode(): key.stem for key in sorted(users.glob("*.key"))}
    return ServerKeys(public, secret, users, names)


def client_keys(folder: Path, user: str) -> ClientKeys:
    server, _ = _load(folder / "server.key", False)
    public, secret = _load(folder / "users" / f"{user}.key_secret", True)
    assert secret is not None
    return ClientKeys(public, secret, server)
