"""A key pressed on a node reaches the server's scripts (``onKey``). The node runs in this
process (keys come from its window, which a headless test has not got: they are pushed
where the window's keyboard pushes them), the server too; both over real sockets."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from app.cli import build_parser
from app.cli_net import node_engine
from engine.events import CustomEvent
from services.input.desktop import WindowDevice
from services.net.client import NetClient
from services.net.protocol import content_fingerprint
from tests.net.net_helpers import free_port, local_server

SCENE = """World { Gravity [0 0 0] TimeStep 1/60 }
Object { ID "box" Position [0 0 1] Dynamic 0 VisualAttributes { Geometry { Primitive "box" } } }
Script "keys.lua"
"""
SCRIPT = """function onKey(key, pressed)
  emit("keySeen", {key = key, pressed = pressed})
end
"""


def test_a_key_pressed_on_a_node_reaches_the_servers_scripts(tmp_path: Path) -> None:
    content = tmp_path / "keys"
    content.mkdir()
    (content / "main.scene").write_text(SCENE)
    (content / "keys.lua").write_text(SCRIPT)
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    seen: list[object] = []
    with local_server(port, content=content) as server:
        server.engine.events.subscribe(
            CustomEvent, lambda e: seen.append(e.data) if e.name == "keySeen" else None)
        client = NetClient(address, "alice", content_fingerprint(content))
        try:
            with ThreadPoolExecutor(1) as pool:  # the hello waits for the server's answer
                welcome = pool.submit(client.join)
                server.step_until(lambda e: welcome.done(), 10, "alice's welcome")
            args = build_parser().parse_args(["join", address, str(content), "--user",
                                              "alice", "--headless"])
            made = node_engine(args, client, welcome.result(), content.resolve())
            assert not isinstance(made, int)
            node, _, scene = made
            scene.instantiate(node)
            node.start()
            keyboard = node.resource(WindowDevice)
            pressed = released = False
            end = time.monotonic() + 10
            while len(seen) < 2 and time.monotonic() < end:
                node.step()
                server.engine.step()
                if node.frame == 3 and not pressed:
                    keyboard.key("Space", True)
                    pressed = True
                elif seen and not released:
                    keyboard.key("Space", False)
                    released = True
            node.close()
        finally:
            client.close()
    assert seen == [{"key": "space", "pressed": True}, {"key": "space", "pressed": False}]
