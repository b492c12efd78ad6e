"""``colosseum bench net``: a server's 2,000 moving bodies at 60 Hz to 1, 4 and 8 nodes.

The server is ``colosseum serve``'s engine in this process, paced at 60 frames a second
(ODE, 2,000 spheres drifting and spinning in zero gravity, so every body moves every
frame). Each node is its own process running a node's network path — join, receive,
decode (:class:`~services.net.codec.PoseDecoder`) and follow
(:class:`~services.net.follow.Follower`) — without an engine to draw: the bench measures
what the network costs, not drawing. Rows, per node count:

* ``server ms/frame``: the server's frame (physics, scripts, gathering and handing the
  frame to the sender thread; wall time, pacing sleep excluded), beside the same server
  with no node just before (``alone ms/frame``, gathering, encoding and sending all the
  same: :attr:`~systems.net.PublishSystem.publish_alone`): the goal is at most 5 % slower
  with 8 nodes. ``server cpu ms/frame`` and ``alone cpu ms/frame`` are the CPU time of
  the thread that runs the frame, which a core taken by a node process does not inflate:
  with more node processes than the machine has spare cores (``cpus``; each node process
  decodes every frame, ``node cpu ms/frame``), the wall times measure the machine
  oversubscribed, and the CPU times what the nodes cost the server itself;
* ``bytes/s per node``: what each node received, beside the bodies as plain float32
  arrays (a uint32 id and seven float32 per body per frame): the goal is 1 MB/s;
* ``publish ms`` is what the server's frame spends handing a frame over, ``send ms``
  what its sender thread spends encoding and sending it (beside the next frame; wall
  time, and ``send cpu ms`` its CPU time);
* ``latency p50/p99``: from the end of the server's frame to the node holding the decoded
  frame (both clocks are this machine's), beside a bare pyzmq PUB/SUB of the same number of
  bytes at the same rate to the same number of receiving processes: the goal is a p99 of
  2 ms.

A last row (``avatars``) serves 10 walkers (``content/avatars``' figure walking paths with
its feet on the ground by IK) to one node: the bytes each node receives for their
skeletons (every joint's matrix as a pose, :mod:`services.net.bones`) and roots, beside
those joints and roots as plain float32 arrays.
"""

from __future__ import annotations

import multiprocessing
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from app.bench import cpus

BODIES = 2000
RATE = 60.0
AVATARS = 10


def _scene(n: int) -> str:
    rng = np.random.default_rng(1)
    side = int(np.ceil(n ** (1 / 3)))
    parts = ["World { Gravity [0 0 0] TimeStep 1/60 AutoSleep 0 }\n"]
    for i in range(n):
        x, y, z = (i % side) * 2.0, (i // side % side) * 2.0, (i // side // side) * 2.0 + 5
        v = rng.normal(0, 0.3, 3)
        w = rng.normal(0, 60, 3)
        parts.append(f'Object {{ ID "b{i}" Position [{x} {y} {z}] Size [0.4] '
                     f"Velocity [{v[0]:.3f} {v[1]:.3f} {v[2]:.3f}] "
                     f"AngularVelocity [{w[0]:.1f} {w[1]:.1f} {w[2]:.1f}] "
                     'VisualAttributes { Geometry { Primitive "sphere" } } '
                     'PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" } } }\n')
    return "".join(parts)


def _avatar_scene(n: int) -> str:
    """``n`` walkers, each on its own square path, feet on the ground."""
    parts = ["World { Gravity [0 0 -9.81] TimeStep 1/60 }\n",
             'Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive '
             '"plane" } } }\n']
    for i in range(n):
        x = 3.0 * i
        parts.append(f'Avatar {{ ID "w{i}" Model "walker.glb" Position [{x} 0 0] '
                     f'Blend ["Walk" "Run"] Weights [{1 - i / n:.2f} {i / n:.2f}] '
                     f"Path [{x} 0 0  {x} 8 0  {x + 2} 8 0  {x + 2} 0 0] GroundFollow 1 "
                     'FootIK ["thigh.L" "shin.L" "foot.L"  "thigh.R" "shin.R" "foot.R"] }\n')
    return "".join(parts)


def _node(address: str, content: str, name: str, seconds: float, out: Any) -> None:
    """One node's network path for ``seconds``; puts (bytes, CPU seconds per frame,
    latencies) on ``out``."""
    from services.net import protocol
    from services.net.client import NetClient
    from services.net.codec import CodecError, PoseDecoder
    from services.net.follow import Follower

    client = NetClient(address, name, content, timeout=5.0)
    client.join()
    decoder, follower = PoseDecoder(), Follower(delay=1.5 / RATE)
    latencies: list[float] = []
    start_bytes, cpu = client.bytes, time.process_time()
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        client.beat()
        if not client.wait(0.05):
            continue
        for kind, header, blob in client.receive():
            if kind != protocol.STATE or blob is None:
                continue
            try:
                decoder.decode(blob)
            except CodecError:
                continue
            follower.push(header["frame"], header["time"], decoder.ids, decoder.poses,
                          time.monotonic())
            latencies.append(time.time() - header["sent"])
    out.put((client.bytes - start_bytes, (time.process_time() - cpu) / max(len(latencies), 1),
             latencies))
    client.close()


def _bare_receiver(address: str, seconds: float, out: Any) -> None:
    import zmq

    ctx = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(address)
    latencies: list[float] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if sub.poll(50):
            sent, _ = sub.recv_multipart()
            latencies.append(time.time() - float(sent))
    out.put(latencies[5:])  # the first ones wait for the connection
    sub.close(0)
    ctx.term()


def _bare_zmq(nodes: int, size: int, seconds: float) -> list[float]:
    """Latencies of a bare PUB/SUB sending ``size`` bytes at RATE to ``nodes`` processes."""
    import zmq

    address = f"tcp://127.0.0.1:{_port()}"
    ctx = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.bind(address)
    out: Any = multiprocessing.Queue()
    procs = [multiprocessing.Process(target=_bare_receiver, args=(address, seconds + 0.5, out))
             for _ in range(nodes)]
    for proc in procs:
        proc.start()
    payload = os.urandom(size)
    end = time.monotonic() + seconds
    tick = time.monotonic()
    while time.monotonic() < end:
        pub.send_multipart([repr(time.time()).encode(), payload])
        tick += 1 / RATE
        time.sleep(max(tick - time.monotonic(), 0.0))
    latencies = [x for _ in procs for x in out.get(timeout=30)]
    for proc in procs:
        proc.join(10)
    pub.close(0)
    ctx.term()
    return latencies


def _port() -> int:
    import socket

    for _ in range(100):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        try:
            with socket.socket() as s:
                s.bind(("127.0.0.1", port + 1))
            return port
        except OSError:
            continue
    raise RuntimeError("no two free ports next to each other")


def _window(engine: Any, seconds: float) -> tuple[float, float]:
    """Step the server for ``seconds``; its mean frame cost in wall time (pacing sleep
    excluded) and in the CPU time of the thread that steps it (ms)."""
    from engine.realtime import CostLog

    engine.frame_costs = CostLog()
    frames, cpu = engine.frame, time.thread_time()
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        engine.step()
    cpu_ms = (time.thread_time() - cpu) / max(engine.frame - frames, 1) * 1e3
    return engine.frame_costs.mean() * 1e3, cpu_ms


def run_bench(quick: bool = False) -> list[dict[str, Any]]:
    from engine.animation import Palettes

    counts = (1,) if quick else (1, 4, 8)
    seconds = 1.0 if quick else 4.0
    n = 500 if quick else BODIES
    rows = []
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-net-") as tmp:
        folder = Path(tmp)
        (folder / "main.scene").write_text(_scene(n), encoding="utf-8")
        engine, server, address = _serve(folder)
        try:
            _window(engine, 1.0)  # warm: bodies in, caches planned
            for nodes in counts:
                rows.append(_with_nodes(engine, server, address, nodes, seconds)
                            | {"bodies": n, "float32 bytes/s": n * 32 * RATE})
        finally:
            engine.close()
            server.close()
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-net-avatars-") as tmp:
        folder = Path(tmp)
        (folder / "main.scene").write_text(_avatar_scene(AVATARS), encoding="utf-8")
        shutil.copy(Path(__file__).resolve().parents[2] / "content" / "avatars" / "models" /
                    "walker.glb", folder / "walker.glb")
        engine, server, address = _serve(folder)
        try:
            _window(engine, 1.0)
            row = _with_nodes(engine, server, address, 1, seconds)
            joints = len(engine.resource(Palettes).matrices)
            row |= {"case": "avatars", "avatars": AVATARS, "joints": joints, "bodies": 0,
                    "float32 bytes/s": (joints + AVATARS) * 32 * RATE}
            rows.append(row)
        finally:
            engine.close()
            server.close()
    return rows


def _serve(folder: Path) -> tuple[Any, Any, str]:
    """``colosseum serve``'s engine on ``folder``, its scene in; (engine, server, address)."""
    from app.cli import build_parser
    from app.cli_net import serving_engine
    from engine.system import Phase
    from systems.net import PublishSystem

    address = f"tcp://127.0.0.1:{_port()}"
    args = build_parser().parse_args(["serve", str(folder), "--bind", address])
    made = serving_engine(args)
    if isinstance(made, int):
        raise RuntimeError(f"the bench server did not start (exit code {made})")
    engine, server, scene = made
    scene.instantiate(engine)
    next(s for s in engine.systems[Phase.RENDER] if isinstance(s, PublishSystem)
         ).publish_alone = True  # the baseline gathers, encodes and sends as with nodes
    return engine, server, address


def _with_nodes(engine: Any, server: Any, address: str, nodes: int,
                seconds: float) -> dict[str, Any]:
    """One row: the server alone for ``seconds``, then with ``nodes`` node processes
    following it for ``seconds``."""
    from engine.realtime import CostLog

    alone, alone_cpu = _window(engine, seconds)
    out: Any = multiprocessing.Queue()
    procs = [multiprocessing.Process(target=_node, args=(
        address, server.content, f"node{i}", seconds + 1.5, out)) for i in range(nodes)]
    for proc in procs:
        proc.start()
    deadline = time.monotonic() + 30
    while len(server.peers) < nodes and time.monotonic() < deadline:
        engine.step()
    _window(engine, 0.5)  # every node past its first keyframe
    sent_before = server.bytes_sent
    server.send_costs, server.send_cpu = CostLog(), CostLog()
    with_nodes, with_nodes_cpu = _window(engine, seconds)
    send_ms, send_cpu_ms = server.send_costs.mean() * 1e3, server.send_cpu.mean() * 1e3
    frame_bytes = (server.bytes_sent - sent_before) / max(seconds * RATE, 1)
    results = [out.get(timeout=60) for _ in procs]
    for proc in procs:
        proc.join(10)
    while server.peers:  # they said bye
        engine.step()
    latencies = np.array([x for _, _, lat in results for x in lat[10:]]) * 1e3
    received = sum(b for b, _, _ in results) / len(results) / (seconds + 1.5)
    bare = np.array(_bare_zmq(nodes, int(frame_bytes), seconds)) * 1e3
    return {
        "nodes": nodes, "cpus": cpus(),
        "server ms/frame": with_nodes, "alone ms/frame": alone,
        "slowdown %": (with_nodes / alone - 1) * 100,
        "server cpu ms/frame": with_nodes_cpu, "alone cpu ms/frame": alone_cpu,
        "cpu slowdown %": (with_nodes_cpu / alone_cpu - 1) * 100,
        "node cpu ms/frame": float(np.mean([cpu for _, cpu, _ in results])) * 1e3,
        "publish ms": engine.stat_sources["net"]()["publish_ms_mean"],
        "send ms": send_ms, "send cpu ms": send_cpu_ms,
        "bytes/s per node": received,
        "latency p50 ms": float(np.percentile(latencies, 50)),
        "latency p99 ms": float(np.percentile(latencies, 99)),
        "bare zmq p50 ms": float(np.percentile(bare, 50)),
        "bare zmq p99 ms": float(np.percentile(bare, 99)),
    }
