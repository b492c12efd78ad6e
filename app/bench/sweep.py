"""``colosseum bench sweep``: runs per minute of a sweep on 2 Dask workers, beside the same
runs one after the other in a plain loop in this process.

Each run is a headless ``run_once`` (what ``colosseum sweep`` runs) of 150 balls dropped
on the ground for 5 simulated seconds (quick: 2), its seed placing them. ``runs/min`` counts
from the submission of the first run to the last result, the LocalCluster already
started; ``with startup`` counts the cluster's start too (what one sweep pays once).
``cpu s/run`` is each run's CPU time in its process (the worker's, its Dask threads
included), beside the loop's (``loop cpu s/run``): where the machine has other work, or
fewer cores (``cpus``) than workers, runs/min measure the machine's load and the CPU
times what a run costs on a worker.
"""

from __future__ import annotations

import logging
import tempfile
import time
from pathlib import Path
from typing import Any

from app.bench import cpus

SCENE = """World { TimeStep 1/60 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
""" + "".join(
    f'Object {{ ID "ball{i}" Position [randInterval(-2, 2) randInterval(-2, 2) {1 + i * 0.3}] '
    'Size [0.3] PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" } } }\n'
    for i in range(150)) + 'Measure { ID "last" Object "ball149" Value "z" }\n'


def timed_run(scene: str, seed: int, frames: int) -> tuple[dict[str, Any], float]:
    """``run_once`` of ``scene`` and the CPU seconds its process spent on it."""
    from app.sweep import run_once

    cpu = time.process_time()
    result = run_once(scene, {}, seed, frames, None)
    return result, time.process_time() - cpu


def run_bench(quick: bool = False) -> list[dict[str, Any]]:
    from distributed import Client, LocalCluster

    runs = 4 if quick else 16
    frames = 120 if quick else 300
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-sweep-") as tmp:
        folder = Path(tmp)
        (folder / "main.scene").write_text(SCENE, encoding="utf-8")
        scene = str(folder / "main.scene")
        timed_run(scene, 0, frames)  # imports and caches warm, as in a worker
        t0 = time.perf_counter()
        alone = [timed_run(scene, seed, frames) for seed in range(runs)]
        loop = time.perf_counter() - t0
        t0 = time.perf_counter()
        logging.getLogger("distributed").setLevel(logging.WARNING)  # the table, not Dask's log
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=logging.WARNING) as cluster, \
                Client(cluster) as client:
            started = time.perf_counter()
            client.gather(client.map(timed_run, [scene] * 2, [0, 1], [frames] * 2,
                                     pure=False))  # each worker warm
            warm = time.perf_counter()
            swept = client.gather(client.map(timed_run, [scene] * runs, list(range(runs)),
                                             [frames] * runs, pure=False))
            done = time.perf_counter()
    same = all(a["measures"] == b["measures"] for (a, _), (b, _) in zip(alone, swept,
                                                                        strict=True))
    return [{"runs": runs, "workers": 2, "cpus": cpus(),
             "frames": frames, "runs/min": runs / (done - warm) * 60,
             "loop runs/min": runs / loop * 60, "with startup runs/min": runs / (done - t0) * 60,
             "cpu s/run": sum(c for _, c in swept) / runs,
             "loop cpu s/run": sum(c for _, c in alone) / runs,
             "cluster start s": started - t0, "same results": same}]
