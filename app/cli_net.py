"""``colosseum serve``, ``join`` and ``keygen``: one simulation, several machines.

``serve`` is ``run`` headless with the server plugin (systems/net.py) added;
``join`` builds a node: no physics, no scripts, the scene built from the server's
full state in the node's own copy of the content folder, which must hash the same.
Every problem (no server, a refused key, other content, a port in use) is one
message and exit code 1 (2 for usage errors), never a traceback.
"""

from __future__ import annotations

import argparse
import getpass
import logging
import os
import sys
from pathlib import Path
from typing import Any

from app.runner import execute_run, fail, outputs_problem, prepare_run
from engine.realtime import TIME_STEP

log = logging.getLogger("colosseum.net")


def serve(args: argparse.Namespace) -> int:
    made = serving_engine(args)
    if isinstance(made, int):
        return made
    engine, server, scene = made
    try:
        log.info("serving %s on %s (nodes join with: colosseum join %s --user NAME)",
                 scene.content.folder, args.bind, args.bind)
        return execute_run(engine, args, scene)
    finally:
        server.close()


def serving_engine(args: argparse.Namespace) -> Any:
    """(engine, bound server, scene) for ``serve``'s flags — the scene not yet in the
    engine — or an exit code, the problem told."""
    from engine.physics import BackendUnavailable
    from services.net.keys import KeyProblem, server_keys
    from services.net.protocol import content_fingerprint, endpoints, is_loopback
    from services.net.server import NetError, NetServer
    from systems import create_engine
    from systems.net import ServerPlugin

    args.headless = True
    try:
        endpoints(args.bind)
    except ValueError as exc:
        return fail(str(exc))
    prepared = prepare_run(args)
    if isinstance(prepared, int):
        return prepared
    scene, config = prepared
    try:
        keys = None if args.key is None else server_keys(args.key)
    except KeyProblem as exc:
        return fail(str(exc), 1)
    if not is_loopback(args.bind) and keys is None:
        log.warning("serving on %s without --key: anyone who reaches it can join and send "
                    "input; use --key DIR (colosseum keygen) off a trusted network", args.bind)
    server = NetServer(args.bind, content_fingerprint(scene.content.folder), keys,
                       timeout=args.timeout, barrier_wait=args.barrier_wait)
    server.content_dir = str(scene.content.folder)
    try:
        server.bind()
    except NetError as exc:
        return fail(str(exc), 1)
    try:
        engine = create_engine(config)
    except BackendUnavailable as exc:
        server.close()
        return fail(str(exc), 1)
    engine.add_plugin(ServerPlugin(server, args.leave_after))
    return engine, server, scene


def join(args: argparse.Namespace) -> int:
    from services.net.client import NetClient
    from services.net.keys import KeyProblem, client_keys
    from services.net.protocol import content_fingerprint, endpoints
    from services.net.server import NetError

    try:
        endpoints(args.address)
    except ValueError as exc:
        return fail(str(exc))
    if args.swap_barrier and not args.display:
        return fail("--swap-barrier is for --display nodes (the walls of a cluster)")
    problem = outputs_problem(args)
    if problem is not None:
        return fail(problem)
    user = args.user or f"{getpass.getuser()}-{os.getpid()}"
    try:
        keys = None if args.key is None else client_keys(args.key, user)
    except KeyProblem as exc:
        return fail(str(exc), 1)
    folder = None
    if args.path is not None:  # a content folder or a .scene file, as serve takes
        from engine.content import ContentError, resolve

        try:
            folder = resolve(args.path).folder
        except ContentError as exc:
            return fail(str(exc))
    client = NetClient(args.address, user, "" if folder is None else
                       content_fingerprint(folder), args.display, keys, timeout=args.timeout)
    try:
        try:
            welcome = client.join()
        except NetError as exc:
            if folder is not None or not exc.reply.get("content_dir"):
                return fail(str(exc), 1)
            folder = Path(exc.reply["content_dir"])  # the server's folder, if it is here too
            if not folder.is_dir():
                return fail(f"the server runs {folder}, which is not here; give this node's "
                            "copy of the content folder: colosseum join ADDRESS PATH", 1)
            client.content = content_fingerprint(folder)
            welcome = client.join()
        return _run_node(args, client, welcome, folder.resolve())
    except NetError as exc:
        return fail(str(exc), 1)
    finally:
        client.close()


def _run_node(args: argparse.Namespace, client: Any, welcome: dict[str, Any],
              folder: Path) -> int:
    made = node_engine(args, client, welcome, folder)
    if isinstance(made, int):
        return made
    engine, node, scene = made
    log.info("joined %s as %s at its frame %s", client.address, client.user, welcome["frame"])

    def stamp(eng: Any) -> None:  # the state a node shows is at the server's time
        eng.time = node.system.shown_time

    return execute_run(engine, args, scene, custom_systems=False, before_save=stamp)


def node_engine(args: argparse.Namespace, client: Any, welcome: dict[str, Any],
                folder: Path) -> Any:
    """(engine, node plugin, scene) of a node that joined (``welcome``) — the scene not
    yet in the engine — or the exit code of a state this folder cannot build (told)."""
    from app.scene_loading import LoadedScene
    from engine.app import Engine, EngineConfig
    from engine.content import Content
    from engine.scene import SceneError
    from systems import RegistryPlugin, load_plugin, wants_render
    from systems.anomalies import AnomaliesPlugin
    from systems.net import NodePlugin, node_scene

    try:
        spec = node_scene(welcome, folder)
    except SceneError as exc:
        print(exc.render(), file=sys.stderr)
        return 1
    headless = args.headless or not (os.environ.get("DISPLAY")
                                     or os.environ.get("WAYLAND_DISPLAY"))
    config = EngineConfig(
        content_dir=folder, headless=headless, sound=args.sound,
        dt=float(welcome.get("dt") or TIME_STEP), world=spec.world, backend="none",
        options={"screenshot": args.screenshot, "record_frames": args.record_frames,
                 "record_every": args.record_every, "hud": args.hud, "size": args.size,
                 "input": args.input, "display": args.display, "stereo": args.stereo,
                 "render_scale": args.render_scale})
    node = NodePlugin(client, welcome, display=args.display is not None,
                      barrier=args.swap_barrier)
    # anomalies before render (the renderer draws the resource it finds); switched by the
    # server only (this node's keys go there)
    plugins: list[Any] = [RegistryPlugin(), load_plugin("input"), load_plugin("sound"),
                          AnomaliesPlugin(switches=False)]
    if wants_render(config):
        plugins.append(load_plugin("render"))
    engine = Engine(config, plugins=[*plugins, node])
    return engine, node, LoadedScene(spec, Content(folder, folder / "main.scene"))


def keygen(args: argparse.Namespace) -> int:
    from services.net.keys import KeyProblem, make_keys

    try:
        made = make_keys(args.folder, args.user)
    except (KeyProblem, OSError) as exc:
        return fail(str(exc), 1)
    for path in made:
        print(path)
    print(f"keys in {args.folder}: serve --key {args.folder}; give each user "
          f"{args.folder}/server.key and their users/NAME.key_secret", file=sys.stderr)
    return 0
