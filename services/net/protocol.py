"""What server and nodes say to each other over ZeroMQ, and how a message is checked.

Two sockets per server, both on the address ``--bind`` names:

* **state** (PUB on PORT, nodes SUB): every physics frame ``[b"S", header, poses]`` —
  ``header`` a JSON object (:func:`state_header`: the server's epoch, frame, simulated
  time, wall time sent, and the frame's events), ``poses`` a blob of
  :mod:`services.net.codec`; and ``[b"B", {"frame": F, "rounds": {user: round}}]``, the
  swap barrier's release of the displays that were ready (each at its own round): F is
  the newest frame every one of them holds or, where a display joined after another's
  newest, the oldest one the newcomer holds, which the others then wait for.
* **control** (ROUTER on PORT+1, nodes DEALER): one JSON object per message, ``type``
  one of :data:`REQUESTS` (node to server) or ``welcome``, ``refused``, ``state``
  (server to node).

Every message a server receives is checked before it is used: not JSON, not an
object, an unknown ``type``, a missing field or one larger than :data:`MAX_MESSAGE`
bytes is a :class:`MessageError`, counted and dropped by the caller.

>>> decode_request([b'{"type": "beat"}'])["type"]
'beat'
>>> decode_request([b'{"type": "launch"}'])
Traceback (most recent call last):
...
services.net.protocol.MessageError: unknown request type 'launch' (known: bye, hello, ...)
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

#: Version of this protocol; a node of another version is refused at hello (2: change
#: residuals zigzagged, keyframes stored; see services/net/codec.py).
VERSION = 2
#: Bytes a node may send in one message (a frame's input is far smaller).
MAX_MESSAGE = 64 * 1024
#: ZeroMQ's own cap per message on the server's sockets: larger ones cut the peer off.
HARD_LIMIT = 1024 * 1024
STATE, BARRIER = b"S", b"B"
#: Seconds a swap barrier waits for every display before it lets the ready ones go
#: (``serve --barrier-wait``).
BARRIER_WAIT = 0.1

#: Requests a node sends, and the fields each must carry.
REQUESTS: dict[str, tuple[str, ...]] = {
    "bye": (), "hello": ("v", "user", "content"), "input": ("events",), "key": (),
    "ready": ("frame", "oldest", "round"), "state": (), "beat": (),
}


class MessageError(ValueError):
    """A message that is not one of the protocol's; the text says what is wrong."""


def encode(message: dict[str, Any]) -> bytes:
    return json.dumps(message, separators=(",", ":")).encode()


def decode_request(frames: list[bytes]) -> dict[str, Any]:
    """A node's request from its message frames (the ROUTER's identity already taken off)."""
    if len(frames) != 1:
        raise MessageError(f"a request is one frame, got {len(frames)}")
    raw = frames[0]
    if len(raw) > MAX_MESSAGE:
        raise MessageError(f"request of {len(raw)} bytes is over the {MAX_MESSAGE} limit")
    message = decode_json(raw)
    kind = message.get("type")
    if kind not in REQUESTS:
        raise MessageError(f"unknown request type {kind!r} (known: {', '.join(REQUESTS)})")
    missing = [f for f in REQUESTS[kind] if f not in message]
    if missing:
        raise MessageError(f"{kind} request lacks {', '.join(missing)}")
    return message


def decode_json(raw: bytes) -> dict[str, Any]:
    """A JSON object (a request, a reply, a frame's header)."""
    try:
        message = json.loads(raw)
    except (ValueError, UnicodeDecodeError) as exc:
        raise MessageError(f"not JSON ({exc})") from None
    if not isinstance(message, dict):
        raise MessageError("not a JSON object")
    return message


def state_header(epoch: str, frame: int, time: float, sent: float,
                 events: dict[str, Any]) -> bytes:
    header: dict[str, Any] = {"epoch": epoch, "frame": frame, "time": time, "sent": sent}
    if events:
        header["events"] = events
    return encode(header)


def endpoints(address: str) -> tuple[str, str]:
    """The state and control endpoints of ``tcp://HOST:PORT`` (PORT and PORT+1).

    >>> endpoints("tcp://127.0.0.1:5555")
    ('tcp://127.0.0.1:5555', 'tcp://127.0.0.1:5556')
    """
    parts = urlsplit(address)
    if parts.scheme != "tcp" or not parts.hostname or parts.port is None:
        raise ValueError(f"{address!r} is not an address tcp://HOST:PORT")
    host = f"[{parts.hostname}]" if ":" in parts.hostname else parts.hostname
    return f"tcp://{host}:{parts.port}", f"tcp://{host}:{parts.port + 1}"


def is_loopback(address: str) -> bool:
    host = urlsplit(address).hostname or ""
    return host in ("localhost", "::1") or host.startswith("127.")


#: Entries of a content folder that are not content: caches, editor and VCS files.
_NOT_CONTENT = ("__pycache__",)
_NOT_CONTENT_SUFFIXES = (".pyc", ".bak")


def content_fingerprint(folder: Path) -> str:
    """A hash of a content folder: every file's path and bytes, hidden files, caches and
    ``.bak`` files left out. Two nodes with the same hash run the same content."""
    import hashlib  # OpenSSL loads for serve and join only, not at every command's start

    digest = hashlib.sha256()
    root = Path(folder).resolve()
    for base, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in _NOT_CONTENT)
        for name in sorted(files):
            if name.startswith(".") or name.endswith(_NOT_CONTENT_SUFFIXES):
                continue
            path = Path(base) / name
            digest.update(path.relative_to(root).as_posix().encode() + b"\0")
            digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.hexdigest()
