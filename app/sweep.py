"""``colosseum sweep``: the same simulation many times, over parameters and seeds, on Dask.

Every combination of the ``--param KEY=v1,v2`` values and every seed of ``--seeds`` is
one headless run (serial, unpaced, no sound): :func:`run_once`, the same code path as
``colosseum run --param KEY=v --seed S --fast``, so a run of a sweep gives the numbers
that run gives alone. The runs are Dask tasks: on a LocalCluster of ``--workers``
processes here, or on the cluster whose scheduler ``--scheduler`` names (any machine that
sees the content folder at the same path: dask-jobqueue's SLURMCluster, for one; see
docs/howto/sweeps.md). A run that raises, or whose worker dies, is tried once more and then
reported in the table with its error; the other runs are kept.

The results are ``DIR/results.csv`` (one row per run: parameters, seed, statistics,
measures) and ``DIR/results.png`` (each measure against the first parameter, the mean
over seeds with its spread).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import logging
import math
import re
import sys
import time
from pathlib import Path
from typing import Any

from app.runner import USAGE_ERROR, fail

log = logging.getLogger("colosseum.sweep")

#: Statistics each row keeps (from ``--stats``).
STAT_COLUMNS = ("frames", "sim_seconds", "wall_seconds", "real_time_factor", "physics_ms_mean",
                "bodies", "contacts")


class SweepError(ValueError):
    """A sweep that cannot start; the message says what to change."""


def parse_seeds(text: str) -> list[int]:
    """``0..99`` (both ends), ``3`` or ``1,5,9``.

    >>> parse_seeds("0..3"), parse_seeds("7"), parse_seeds("1,5")
    ([0, 1, 2, 3], [7], [1, 5])
    """
    match = re.fullmatch(r"\s*(-?\d+)\s*\.\.\s*(-?\d+)\s*", text)
    try:
        if match:
            low, high = int(match.group(1)), int(match.group(2))
            if high < low:
                raise SweepError(f"--seeds {text}: the range runs backwards")
            return list(range(low, high + 1))
        return [int(part) for part in text.split(",")]
    except ValueError:
        raise SweepError(f"--seeds {text!r}: use A..B, N or N,M,...") from None


def parse_params(options: list[str]) -> dict[str, list[str]]:
    """``KEY=v1,v2`` options as KEY -> its values.

    >>> parse_params(["mass=1,2", "g=9.81"])
    {'mass': ['1', '2'], 'g': ['9.81']}
    """
    params: dict[str, list[str]] = {}
    for option in options:
        key, sep, values = option.partition("=")
        listed = [v.strip() for v in values.split(",") if v.strip()]
        if not sep or not key.strip() or not listed:
            raise SweepError(f"--param {option!r}: use KEY=v1,v2,...")
        params[key.strip()] = listed
    return params


def combinations(params: dict[str, list[str]], seeds: list[int]) -> list[tuple[dict[str, str],
                                                                               int]]:
    keys = list(params)
    return [(dict(zip(keys, values, strict=True)), seed)
            for values in itertools.product(*(params[k] for k in keys)) for seed in seeds]


def run_once(path: str, params: dict[str, str], seed: int, frames: int | None,
             seconds: float | None, backend: str | None = None,
             dt: float | None = None) -> dict[str, Any]:
    """One headless run, as ``colosseum run PATH --param K=V --seed S --fast`` makes it;
    returns its statistics and measures. Raises on a scene that does not load."""
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import load_systems, resolve
    from engine.stats import collect
    from systems import create_engine

    scene = load_content_scene(resolve(path), seed=seed, params=params)
    config = EngineConfig(content_dir=scene.content.folder, seed=seed, fast=True,
                          headless=True, sound="null")
    scene.configure(config, backend=backend, dt=dt)
    engine = create_engine(config)
    try:
        load_systems(engine, scene.content.folder)
        scene.instantiate(engine)
        engine.run(frames=frames, seconds=seconds)
        stats = collect(engine)
    finally:
        engine.close()
    return {**{k: stats[k] for k in STAT_COLUMNS}, "measures": stats.get("measures", {})}


def sweep(args: argparse.Namespace) -> int:
    from engine.content import ContentError, resolve
    from engine.scene.params import ParamError, with_params

    try:
        content = resolve(args.path)
        params = parse_params(args.param)
        seeds = parse_seeds(args.seeds)
        for key, values in params.items():  # each value checked before any run starts
            for value in values:
                with_params(content.scene, {key: value})
    except (ContentError, SweepError, ParamError) as exc:
        return fail(str(exc), USAGE_ERROR)
    except Exception as exc:  # the scene itself does not parse: told as a run tells it
        return fail(f"{content.scene}: {exc}", 1)
    if args.frames is None and args.seconds is None:
        return fail("a sweep needs --frames N or --seconds S (each run must end)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    runs = combinations(params, seeds)
    try:
        rows = _distribute(str(content.scene), runs, args)
    except SweepError as exc:
        return fail(str(exc), 1)
    table = out / "results.csv"
    failed = write_table(table, params, rows)
    plot = out / "results.png"
    if write_plot(plot, params, rows):
        log.info("plot written to %s", plot)
    log.info("%d run(s), %d failed; results in %s", len(rows), failed, table)
    return 1 if failed else 0


def _distribute(scene: str, runs: list[tuple[dict[str, str], int]],
                args: argparse.Namespace) -> list[dict[str, Any]]:
    """Every run on Dask; rows in the order of ``runs``, a failure as its error."""
    calls = [(scene, params, seed, args.frames, args.seconds, args.backend, args.dt)
             for params, seed in runs]
    rows: list[dict[str, Any]] = []
    for (params, seed), result in zip(runs, map_on_dask(run_once, calls, args, "runs"),
                                      strict=True):
        if isinstance(result, BaseException):  # reported in the table, the rest kept
            rows.append({"params": params, "seed": seed, "measures": {},
                         "error": _error_text(result)})
            log.error("run %s seed %d failed: %s", params, seed, rows[-1]["error"])
        else:
            rows.append({"params": params, "seed": seed, **result, "error": ""})
    return rows


def map_on_dask(fn: Any, calls: list[tuple[Any, ...]], args: argparse.Namespace,
                what: str = "runs") -> list[Any]:
    """``fn(*call)`` for every call as Dask tasks (``args.scheduler``'s cluster, else a
    LocalCluster of ``args.workers`` processes); results in the order of ``calls``, a call
    that raised (twice: it is retried once) as its exception."""
    import dask
    from distributed import Client, LocalCluster, as_completed

    from engine.progress import on_terminal, progress

    # one run per worker thread at a time (none queued on it), so a worker that dies takes
    # down only the run it was running, which is retried once
    # a dying worker is this table's row, not Dask's tracebacks on the author's terminal
    # (distributed sets some of its loggers' levels itself: "Couldn't gather ... keys,
    # rescheduling" came from distributed.client)
    for name in ["distributed", *logging.root.manager.loggerDict]:
        if name.startswith("distributed"):
            logging.getLogger(name).setLevel(logging.CRITICAL)
    with dask.config.set({"distributed.scheduler.allowed-failures": 1,
                          "distributed.scheduler.worker-saturation": 1.0,
                          "distributed.worker.daemon": False,
                          "distributed.logging.distributed": "error"}):
        if args.scheduler:
            try:
                client = Client(args.scheduler, timeout="10s")
            except (OSError, ValueError, TypeError) as exc:  # unreachable, not an address
                raise SweepError(f"--scheduler {args.scheduler}: no Dask scheduler answers "
                                 f"there ({str(exc).splitlines()[0]}); start one (`dask "
                                 "scheduler`) or leave --scheduler out to sweep on this "
                                 "machine") from None
            cluster = None
        else:
            cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1,
                                   processes=True, dashboard_address=None,
                                   silence_logs=logging.CRITICAL)
            client = Client(cluster)
        try:
            futures = {client.submit(fn, *call, retries=1, pure=False): i
                       for i, call in enumerate(calls)}
            results: list[Any] = [None] * len(calls)
            done = 0
            started = time.monotonic()
            with progress("sweep", len(calls)) as report:
                for future in as_completed(futures):
                    i = futures[future]
                    try:
                        results[i] = future.result()
                    except Exception as exc:  # the caller reports it, the rest kept
                        results[i] = exc
                    done += 1
                    report(done, f"{done}/{len(calls)} {what}")
                    if not on_terminal() and (done == len(calls) or done % 10 == 0):
                        rate = done / max(time.monotonic() - started, 1e-9) * 60
                        print(f"sweep: {done}/{len(calls)} {what} done ({rate:.1f} per "
                              "minute)", file=sys.stderr)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    return results


def _error_text(exc: BaseException) -> str:
    name = type(exc).__name__
    if name == "KilledWorker":
        return "its worker died twice (a crash in the simulation, or out of memory)"
    return f"{name}: {exc}".splitlines()[0][:300]


def write_table(path: Path, params: dict[str, list[str]], rows: list[dict[str, Any]]) -> int:
    """The CSV table; returns how many runs failed."""
    measures = sorted({name for row in rows for name in row.get("measures", {})})
    header = [*params, "seed", *STAT_COLUMNS, *measures, "error"]
    with path.open("w", newline="", encoding="utf-8") as out:
        writer = csv.writer(out)
        writer.writerow(header)
        for row in rows:
            writer.writerow([*(row["params"][k] for k in params), row["seed"],
                             *(_cell(row.get(k)) for k in STAT_COLUMNS),
                             *(_cell(row["measures"].get(m)) for m in measures), row["error"]])
    return sum(1 for row in rows if row["error"])


def _cell(value: Any) -> str:
    return "" if value is None else repr(value) if isinstance(value, float) else str(value)


def _axis(values: list[str]) -> list[float] | list[str]:
    """Numbers where every value is one (an axis to scale), else the values as labels."""
    try:
        return [float(v) for v in values]
    except ValueError:
        return values


def write_plot(path: Path, params: dict[str, list[str]], rows: list[dict[str, Any]]) -> bool:
    """Each measure against the first parameter: mean over seeds, bars one standard
    deviation. False when there is nothing to plot (no measure, or no parameter)."""
    measures = sorted({name for row in rows for name in row.get("measures", {})})
    if not measures or not params:
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    key = next(iter(params))
    fig, axes = plt.subplots(1, len(measures), figsize=(4.5 * len(measures), 3.5),
                             squeeze=False)
    for ax, name in zip(axes[0], measures, strict=True):
        xs, means, spreads = [], [], []
        for value in params[key]:
            got = [r["measures"][name] for r in rows if r["params"][key] == value
                   and name in r["measures"]]
            if got:
                mean = sum(got) / len(got)
                xs.append(value)
                means.append(mean)
                spreads.append(math.sqrt(sum((g - mean) ** 2 for g in got) / len(got)))
        ax.errorbar(_axis(xs), means, yerr=spreads, marker="o", capsize=4)
        ax.set_xlabel(key)
        ax.set_ylabel(name)
    fig.suptitle(f"{len(rows)} runs")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return True
