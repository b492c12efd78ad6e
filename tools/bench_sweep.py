"""``colosseum bench sweep``: runs per minute of a sweep on 2 Dask workers, beside the same
runs one after the other in a plain loop in this process.

Each run is a headless ``run_once`` (what ``colosseum sweep`` runs) of 150 balls dropped
on the ground for 5 simulated seconds (quick: 2), its seed placing them. ``runs/min`` counts
from the submission of the first run to the last result, the LocalCluster already
started; ``with startup`` counts the cluster's start too (what one sweep pays once).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

SCENE = """World { TimeStep 1/60 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
""" + "".join(
    f'Object {{ ID "ball{i}" Position [randInterval(-2, 2) randInterval(-2, 2) {1 + i * 0.3}] '
    'Size [0.3] PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" } } }\n'
    for i in range(150)) + 'Measure { ID "last" Object "ball149" Value "z" }\n'


def run_bench(quick: bool = False) -> list[dict[str, Any]]:
    from distributed import Client, LocalCluster

    from engine.sweep import run_once

    runs = 4 if quick else 16
    frames = 120 if quick else 300
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-sweep-") as tmp:
        folder = Path(tmp)
        (folder / "main.scene").write_text(SCENE, encoding="utf-8")
        scene = str(folder / "main.scene")
        run_once(scene, {}, 0, frames, None)  # imports and caches warm, as in a worker
        t0 = time.perf_counter()
        alone = [run_once(scene, {}, seed, frames, None) for seed in range(runs)]
        loop = time.perf_counter() - t0
        t0 = time.perf_counter()
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            started = time.perf_counter()
            client.gather(client.map(run_once, [scene] * 2, [{}] * 2, [0, 1], [frames] * 2,
                                     [None] * 2, pure=False))  # each worker warm
            warm = time.perf_counter()
            swept = client.gather(client.map(run_once, [scene] * runs, [{}] * runs,
                                             list(range(runs)), [frames] * runs,
                                             [None] * runs, pure=False))
            done = time.perf_counter()
    same = all(a["measures"] == b["measures"] for a, b in zip(alone, swept, strict=True))
    return [{"runs": runs, "workers": 2, "frames": frames,
             "runs/min": runs / (done - warm) * 60, "loop runs/min": runs / loop * 60,
             "with startup runs/min": runs / (done - t0) * 60,
             "cluster start s": started - t0, "same results": same}]
