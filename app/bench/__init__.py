"""``colosseum bench WHAT``: benchmarks printed as tables, each beside a reference.

Every benchmark measures our path and a reference in the same run and reports
the ratio, so the numbers mean something on any machine.
"""

from __future__ import annotations

import importlib
import json
import os
import platform
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from systems import create_engine

#: name -> "module:function"; each function takes (quick, backend) and returns table rows.
BENCHMARKS: dict[str, str] = {
    "scheduler": "app.bench:bench_scheduler",
    "physics": "app.bench.physics:run_bench",
    "scene": "app.bench:bench_scene",
    "scripting": "app.bench.scripting:run_bench",
    "sound": "app.bench.sound:run_bench",
    "render": "app.bench.render:run_bench",
    "stereo": "app.bench.render:run_stereo_bench",
    "input": "app.bench.input:run_bench",
    "contacts": "app.bench:bench_contacts",
    "avatars": "app.bench.avatars:run_bench",
    "hands": "app.bench.hand_rows:run_bench",
    "import": "app.bench.model_import:run_bench",
    "net": "app.bench.net:run_bench",
    "sweep": "app.bench.sweep:run_bench",
    "accuracy": "app.bench.accuracy:run_bench",
    "stroke": "app.bench.stroke:run_bench",
    "experiment": "app.bench.experiment:run_bench",
    "startup": "app.bench.startup:run_bench",
    "pareto": "app.bench.pareto:run_bench",
}


@dataclass(frozen=True, slots=True)
class Figure:
    """One measured figure beside its reference, from the same run."""

    label: str
    ours: float
    reference: float
    unit: str
    reference_is: str

    @property
    def ratio(self) -> float:
        return self.ours / self.reference if self.reference else float("inf")


def cpus() -> int:
    """The cores this process may run on (``nproc``): a benchmark of several processes
    says it beside its figures."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
        os.cpu_count() or 1


def _by_row(label: Callable[[dict[str, Any]], str], ours: str, reference: str, unit: str,
            reference_is: str) -> Callable[[list[dict[str, Any]]], list[Figure]]:
    """Figures from rows that each hold our number and the reference's."""
    return lambda rows: [Figure(label(r), float(r[ours]), float(r[reference]), unit,
                                reference_is) for r in rows if ours in r and reference in r]


def _scene_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    total = next(r for r in rows if r["stage"] == "total")
    ref = next(r for r in rows if r["stage"].startswith("json.loads"))
    return [Figure(f"load {total['objects']} objects", total["cpu s"], ref["cpu s"], "s",
                   "json.loads of the same data")]


def _render_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    ours = next(r for r in rows if r["case"] == "instanced")
    ref = next(r for r in rows if r["case"] == "one draw per box")
    return [Figure(f"{ours['boxes']} boxes, {ours['size']}", ours["ms_per_frame"],
                   ref["ms_per_frame"], "ms/frame", "one draw call per box")]


def _physics_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    if rows and "C+fb ms" in rows[0]:  # ODE beside plain C
        return _by_row(lambda r: f"N={r['N']} sleeping {r['sleeping']}", "ours+sync ms",
                       "C+fb ms", "ms/step", "the same world in plain C (libode)")(rows)
    return _by_row(lambda r: f"N={r['n']}", "ours_ms", "raw_ms", "ms/step",
                   "bare pymunk stepping")(rows)


def _import_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    ref = next(r for r in rows if "reference" in r["stage"])
    return [Figure(f"{r['nodes']} nodes: {r['stage']}", r["cpu s"], ref["cpu s"], "cpu s",
                   "json.loads of the glTF's JSON") for r in rows if "goal s" in r]


def _accuracy_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    """At the default step: our error beside MuJoCo's on the same case, or beside the
    goal where MuJoCo is not installed (or has no such case). An error of exactly 0 (a
    motor holding its speed to the bit) has no ratio: the table shows it."""
    out = []
    for r in rows:
        if not r["default step"] or r["error"] == 0 or r.get("mujoco error", 1) == 0:
            continue
        label, unit = f"{r['case']} ({r['backend']})", r["error is"]
        if "mujoco error" in r:
            out.append(Figure(label, abs(r["error"]), abs(r["mujoco error"]), unit,
                              "MuJoCo's error on the same case at the same step"))
        elif "goal" in r:
            out.append(Figure(label, abs(r["error"]), r["goal"], unit, "the goal"))
    return out


def _input_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    ours = next(r for r in rows if r["path"].startswith("osc -> InputState"))
    ref = next(r for r in rows if "reference" in r["path"])
    return [Figure("CPU per OSC event, to InputState", ours["cpu us/event"],
                   ref["cpu us/event"], "us/event",
                   "python-osc's own server on the same stream")]


def _net_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    out = []
    for r in rows:
        n = r["nodes"]
        if r.get("case") == "avatars":
            out.append(Figure(f"{r['avatars']} walking avatars ({r['joints']} joints): bytes/s "
                              "per node", r["bytes/s per node"], r["float32 bytes/s"], "B/s",
                              "their joints and roots as plain float32 arrays"))
            continue
        out += [Figure(f"{n} node(s): latency p99", r["latency p99 ms"], r["bare zmq p99 ms"],
                       "ms", "a bare pyzmq PUB/SUB of the same bytes to as many processes"),
                Figure(f"{n} node(s): bytes/s per node", r["bytes/s per node"],
                       r["float32 bytes/s"], "B/s", "the bodies as plain float32 arrays"),
                Figure(f"{n} node(s): server frame", r["server ms/frame"], r["alone ms/frame"],
                       "ms/frame", "the same server with no node"),
                Figure(f"{n} node(s): server frame CPU", r["server cpu ms/frame"],
                       r["alone cpu ms/frame"], "ms/frame", "the same server with no node")]
    return out


def _stroke_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    serial, threaded, everything, scaled = rows
    return [Figure("threaded frames/s", threaded["fps"], serial["fps"], "frames/s",
                   "serial mode, the same run"),
            Figure("serial frames/s", serial["fps"], everything["fps"], "frames/s",
                   "culling, levels of detail and the shadow cache off"),
            Figure("serial frames/s at --render-scale 0.75", scaled["fps"], serial["fps"],
                   "frames/s", "serial mode at full resolution, the same run")]


#: benchmark -> how its rows become figures (ours beside the reference).
FIGURES: dict[str, Callable[[list[dict[str, Any]]], list[Figure]]] = {
    "scheduler": _by_row(lambda r: f"{r['mode']}, {r['systems']} systems", "ms/frame",
                         "bare loop ms", "ms/frame", "a bare loop calling the same functions"),
    "physics": _physics_figures,
    "scene": _scene_figures,
    "scripting": lambda rows: [
        *_by_row(lambda r: r["benchmark"], "us_per_call", "bare_lupa_us", "us/call",
                 "a bare lupa call")(rows),
        *_by_row(lambda r: r["benchmark"], "ms_per_box", "ms_100_bodies", "ms/box",
                 "the same among 100 bodies")(rows)],
    "sound": _by_row(lambda r: r["case"], "ours_ms", "raw_al_ms", "ms/frame",
                     "raw OpenAL calls for the same sources"),
    "render": _render_figures,
    "stereo": lambda rows: [Figure(f"{r['boxes']} boxes, {r['case']}, {r['size']}",
                                   r["engine_cpu_ms"], rows[0]["engine_cpu_ms"],
                                   "engine CPU ms/frame",
                                   "a mono frame at one eye's size, the same run")
                            for r in rows[1:]],
    "input": _input_figures,
    "contacts": _by_row(lambda r: f"{r['pairs']} pairs {r['state']}", "ms/frame",
                        "unique ms", "ms/frame",
                        "pair keys and np.unique of the same contacts alone"),
    "hands": lambda rows: [Figure(f"{r['case']} ({r['backend']})", r["ms/step"],
                                  r["without hands ms/step"],
                                  "ms/step", "the same scene without the hands")
                           for r in rows if "ms/step" in r],
    "avatars": lambda rows: [Figure(f"{r['avatars']} avatars, {r['case']}", r["ms_per_frame"],
                                    r["reference_ms"], "ms/frame", r["reference"])
                             for r in rows if r["ms_per_frame"] > 0],
    "import": _import_figures,
    "net": _net_figures,
    "sweep": _by_row(lambda r: f"{r['runs']} runs on {r['workers']} Dask workers",
                     "runs/min", "loop runs/min", "runs/min", "the same runs in a plain loop"),
    "accuracy": _accuracy_figures,
    "stroke": _stroke_figures,
    "pareto": lambda rows: _pareto_figures(rows),
    "experiment": lambda rows: [Figure("tracking 2,000 objects every frame", r["frame ms"],
                                       r["without ms"], "ms/frame",
                                       "the same frames without a trial")
                                for r in rows if r["case"] == "summary"],
    "startup": lambda rows: [Figure(r["command"], r["ours cpu s"], r["reference cpu s"],
                                    "cpu s",
                                    f"a bare python importing {r['reference: bare imports of']}")
                             for r in rows],
}


def _resolve(name: str) -> Callable[..., Any]:
    """``module:function`` looked up when needed, as BENCHMARKS' entries are (a benchmark
    module imports this one for its rows and figures)."""
    module_name, func_name = name.split(":")
    return getattr(importlib.import_module(module_name), func_name)


def _pareto_figures(rows: list[dict[str, Any]]) -> list[Figure]:
    return _resolve("app.bench.pareto:figures")(rows)


def _pareto_plot() -> Callable[[dict[str, Any], Path], Path]:
    return _resolve("app.bench.pareto:plot")


#: benchmark -> its own plot, where the bars of ours beside the reference do not fit.
PLOTS: dict[str, Callable[[], Callable[[dict[str, Any], Path], Path]]] = {
    "pareto": _pareto_plot,
}


def print_table(rows: list[dict[str, Any]]) -> None:
    """One table per kind of row (:func:`kinds`), each under its kind's name: no table
    has a column that half its rows leave blank."""
    for i, (kind, group) in enumerate(kinds(rows)):
        if kind or i:
            print(f"\n{kind}" if kind else "")
        _print_one_table(group)


def kinds(rows: list[dict[str, Any]]) -> list[tuple[str, list[dict[str, Any]]]]:
    """Rows grouped by their ``kind`` where they name one; a row without one joins the
    first untitled group led by the same column whose columns it mostly shares (at least
    half of the two together), else starts its own. Groups and rows keep their order."""
    groups: list[tuple[str, list[dict[str, Any]], dict[str, None]]] = []
    for row in rows:
        kind = row.get("kind")
        row = {k: v for k, v in row.items() if k != "kind"}
        group = next((g for g in groups if _same_kind(g, kind, row)), None)
        if group is None:
            group = (str(kind or ""), [], {})
            groups.append(group)
        group[1].append(row)
        group[2].update(dict.fromkeys(row))
    return [(title, members) for title, members, _ in groups]


def _same_kind(group: tuple[str, list[dict[str, Any]], dict[str, None]], kind: Any,
               row: dict[str, Any]) -> bool:
    title, _, columns = group
    if kind is not None or title:
        return title == str(kind or "")
    shared = len(columns.keys() & row.keys())
    return (next(iter(columns)) == next(iter(row), None)
            and 2 * shared >= len(columns.keys() | row.keys()))


def _print_one_table(rows: list[dict[str, Any]]) -> None:
    if not rows:
        return
    columns = list(rows[0])
    for row in rows[1:]:
        columns += [c for c in row if c not in columns]
    cells = [[_fmt(row.get(c, "")) for c in columns] for row in rows]
    widths = [max(len(c), *(len(r[i]) for r in cells)) for i, c in enumerate(columns)]
    print("  ".join(c.rjust(w) for c, w in zip(columns, widths, strict=True)))
    print("  ".join("-" * w for w in widths))
    for r in cells:
        print("  ".join(v.rjust(w) for v, w in zip(r, widths, strict=True)))


def print_row(row: dict[str, Any]) -> None:
    """One row as it is measured (``key=value`` pairs), before the table at the end; its
    kind is the title of its table there."""
    print("  ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                    for k, v in row.items() if k != "kind"), flush=True)


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def measure(what: str, backend: str | None = None, quick: bool = False,
            content: Path | None = None) -> list[dict[str, Any]]:
    """Run one benchmark (a spinner with the elapsed time on a terminal); its rows.
    ``content`` is the content folder of a benchmark that runs one (stroke)."""
    from engine.progress import progress

    module_name, func_name = BENCHMARKS[what].split(":")
    func: Callable[..., list[dict[str, Any]]] = getattr(importlib.import_module(module_name),
                                                        func_name)
    kwargs: dict[str, Any] = {}
    if backend is not None:
        kwargs["backend"] = backend
    if quick:
        kwargs["quick"] = True
    if content is not None:
        kwargs["content"] = content
    with progress(f"bench {what}"):
        return func(**kwargs)


def report(what: str, rows: list[dict[str, Any]], backend: str | None = None,
           quick: bool = False) -> dict[str, Any]:
    """The run as plain data: the rows, our figures beside their references, when (UTC) and
    on what machine (a figure made from it can say both)."""
    return {"benchmark": what, "backend": backend, "quick": quick, "rows": rows,
            "figures": [{**asdict(f), "ratio": f.ratio} for f in FIGURES[what](rows)],
            "date": datetime.now(UTC).isoformat(timespec="seconds"),
            "machine": {"python": sys.version.split()[0], "platform": platform.platform(),
                        "cpus": os.cpu_count(), "processor": _processor()}}


def _processor() -> str:
    """The CPU's model name (Linux), else what platform knows."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.partition(":")[2].strip()
    except OSError:
        pass
    return platform.processor()


def plot(data: dict[str, Any], path: Path) -> Path:
    """Our figures beside their references as grouped bars, each pair's ratio above it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures = data["figures"]
    many = len(figures) > 12  # a long row of pairs: narrower bars, steeper labels
    fig, ax = plt.subplots(figsize=(min(max(6.0, 1.6 * len(figures) + 2), 24.0),
                                    6.5 if many else 4.5))
    xs = range(len(figures))
    ours = [f["ours"] for f in figures]
    refs = [f["reference"] for f in figures]
    ax.bar([x - 0.2 for x in xs], ours, 0.4, label="colosseum")
    ax.bar([x + 0.2 for x in xs], refs, 0.4,
           label=f"reference: {figures[0]['reference_is']}" if figures else "reference")
    for x, f in zip(xs, figures, strict=True):
        ax.annotate(f"x{f['ratio']:.2g}" if many else f"x{f['ratio']:.2f}",
                    (x, max(f["ours"], f["reference"])), ha="center", va="bottom",
                    fontsize=6 if many else None)
    ax.set_xticks(list(xs), [f["label"] for f in figures], rotation=60 if many else 15,
                  ha="right", fontsize=7 if many else None)
    ax.set_ylabel(", ".join(dict.fromkeys(f["unit"] for f in figures)))
    values = [v for v in ours + refs if v > 0]
    if values and max(values) > 100 * min(values):  # figures a hundredfold apart
        ax.set_yscale("symlog", linthresh=min(values))
    when = f", {data['date'][:10]}" if data.get("date") else ""  # JSON from before: no date
    ax.set_title(f"colosseum bench {data['benchmark']} ({data['machine']['platform']}{when})",
                 fontsize=9)
    ax.legend(fontsize=8, title=None if len({f["reference_is"] for f in figures}) < 2 else
              "references: " + "; ".join(sorted({f["reference_is"] for f in figures})),
              title_fontsize=7)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def run_benchmark(what: str, backend: str | None = None, quick: bool = False,
                  json_out: str | None = None, plot_out: Path | None = None,
                  content: Path | None = None) -> int:
    """Measure, then print the table (or the JSON: ``json_out`` "-" is stdout), and plot."""
    rows = measure(what, backend, quick, content)
    data = report(what, rows, backend, quick)
    if json_out == "-":
        print(json.dumps(data, indent=2))
    else:
        print(f"\ncolosseum bench {what}")
        tables = dict.fromkeys(r.get("table", "") for r in rows)
        for table in tables:  # rows that say their table: one table each
            if len(tables) > 1:
                print(f"\n{table}")
            print_table([r for r in rows if r.get("table", "") == table])
        for f in FIGURES[what](rows):
            print(f"{f.label}: {f.ours:.4g} {f.unit}, reference {f.reference:.4g} "
                  f"({f.reference_is}): ratio {f.ratio:.3g}")
        if json_out is not None:
            Path(json_out).write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    if plot_out is not None:
        draw = PLOTS[what]() if what in PLOTS else plot
        print(f"plot written to {draw(data, plot_out)}", file=sys.stderr)
    return 0


def bench_scheduler(quick: bool = False) -> list[dict[str, Any]]:
    """Engine overhead per frame: no bodies, ten trivial systems; reference: a bare loop."""
    from engine import EngineConfig, Phase, system

    frames = 2_000 if quick else 20_000
    phases = list(Phase)
    counter = [0]

    def trivial(engine: Any, dt: float) -> None:
        counter[0] += 1

    functions = [trivial] * 10
    t0 = time.perf_counter()
    for _ in range(frames):
        for fn in functions:
            fn(None, 0.016)
    bare_ms = (time.perf_counter() - t0) / frames * 1e3

    rows = []
    for mode in ("serial", "threaded"):
        with create_engine(EngineConfig(backend="ballistic", mode=mode, fast=True)) as eng:
            for i in range(10):
                eng.add_system(system(phases[i % len(phases)])(trivial))
            eng.run(frames=100)
            t0 = time.perf_counter()
            eng.run(frames=frames)
            ms = (time.perf_counter() - t0) / frames * 1e3
        rows.append({"mode": mode, "systems": 10, "frames": frames, "ms/frame": ms,
                     "bare loop ms": bare_ms, "overhead ms": ms - bare_ms,
                     "target ms": 0.2, "ok": "yes" if ms < 0.2 else "NO"})
    return rows


def bench_scene(quick: bool = False, repeats: int = 3) -> list[dict[str, Any]]:
    """Parse, validate, build and instantiate a generated file of 10,000 objects; reference:
    json.loads (a C parser) of the same objects as JSON (a list of dicts with the same keys
    and values), timed in the same run, to show what reading the data costs by itself.
    A second reference is the scene's own reference parser (the token path, without the
    compiled fast path) reading the same text, beside the fast path reading it.

    Both are run ``repeats`` times and the fastest run is shown, as timeit does (this
    machine's speed swings from minute to minute); the total's median is shown beside it.
    """
    import json
    import statistics

    import numpy as np

    from engine.scene import bench_scene as run
    from engine.scene import generate_scene, parse_text
    from engine.scene.parser import token_path_only

    n = 1_000 if quick else 10_000
    runs = [run(n) for _ in range(1 if quick else repeats)]
    r = min(runs, key=lambda x: x["cpu_s"])
    median = statistics.median(x["cpu_s"] for x in runs)
    db = parse_text(generate_scene(n), rng=np.random.default_rng(0))
    as_json = json.dumps([_plain_dict(b) for b in db.blocks("Object")])
    json_s = json_cpu_s = float("inf")
    for _ in range(len(runs)):
        c0, t0 = time.process_time(), time.perf_counter()
        json.loads(as_json)
        json_s = min(json_s, time.perf_counter() - t0)
        json_cpu_s = min(json_cpu_s, time.process_time() - c0)
    text = generate_scene(n)
    fast_cpu_s = token_cpu_s = float("inf")
    for _ in range(len(runs)):
        fast_cpu_s = min(fast_cpu_s, _cpu_seconds(lambda: parse_text(text)))
        with token_path_only():
            token_cpu_s = min(token_cpu_s, _cpu_seconds(lambda: parse_text(text)))
    target = 1.0 if n == 10_000 else 0.1
    mb = r["file_bytes"] / 1e6
    stages = "loading the scene file, stage by stage (fastest run)"
    return [{"kind": stages, "objects": n, "file MB": mb, "stage": stage,
             "wall s": r[f"{key}_s"], "cpu s": r[f"{key}_cpu_s"]}
            for stage, key in (("parse (read+lex+parse)", "parse"), ("validate", "validate"),
                               ("build specs", "build_specs"), ("instantiate", "instantiate"))
            ] + [{"kind": stages, "objects": n, "file MB": mb, "stage": "total",
                  "wall s": r["total_s"], "cpu s": r["cpu_s"], "target s": target,
                  "ok": "yes" if r["cpu_s"] < target else "NO",
                  f"cpu s, median of {len(runs)}": median},
                 {"kind": "reference: the same objects as JSON", "objects": n,
                  "JSON MB": len(as_json) / 1e6, "stage": "json.loads (reference)",
                  "wall s": json_s, "cpu s": json_cpu_s,
                  "x total": r["cpu_s"] / json_cpu_s if json_cpu_s else float("inf")},
                 {"kind": "the parser alone: compiled fast path beside the token path",
                  "objects": n, "file MB": mb, "stage": "parse text, fast path",
                  "cpu s": fast_cpu_s},
                 {"kind": "the parser alone: compiled fast path beside the token path",
                  "objects": n, "file MB": mb, "stage": "parse text, token path (reference)",
                  "cpu s": token_cpu_s, "x fast path": token_cpu_s / fast_cpu_s}]


def _cpu_seconds(work: Callable[[], object]) -> float:
    """CPU seconds ``work`` takes (freeing what it returned is not counted)."""
    c0 = time.process_time()
    result = work()
    elapsed = time.process_time() - c0
    del result
    return elapsed


def _plain_dict(block: Any) -> dict[str, Any]:
    """A scene block as plain JSON-able data: STRUCTUREs as dicts, vectors as lists."""
    return {e.key: _plain_dict(e.value.data) if e.value.kind == "STRUCTURE" else e.value.py()
            for e in block}


def _fastest_ms(fn: Callable[[], None], frames: int, rounds: int = 3) -> float:
    """The fastest of ``rounds`` rounds of ``frames`` calls, in ms per call."""
    best = float("inf")
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(frames):
            fn()
        best = min(best, (time.perf_counter() - t0) / frames * 1e3)
    return best


def _contacts_case(pairs: int, frames: int, asleep: bool) -> dict[str, Any]:
    """One size of bench_contacts: our tracker and the reference, alternating rounds. Pairs
    ``asleep`` touched once and are reported no more (their bodies asleep where they were:
    the tracker checks each frame that none moved)."""
    import numpy as np

    from engine.app import EngineConfig
    from engine.events import Contacts
    from engine.physics.backend import CONTACT_DTYPE, BodyState
    from engine.physics.driver import Snapshot
    from systems.contacts import ContactEventsSystem, pair_keys

    rng = np.random.default_rng(pairs)
    batch = np.zeros(2 * pairs, CONTACT_DTYPE)  # two contacts per pair
    with create_engine(EngineConfig(backend="ballistic", fast=True)) as engine:
        keys = np.array(engine.world.create_entities([[]] * (2 * pairs)))  # bodies of pairs
        ids = rng.permutation(keys[:pairs])
        batch["a"] = np.repeat(ids, 2)
        batch["b"] = np.repeat(np.where(rng.random(pairs) < 0.5, -1, keys[pairs:]), 2)
        batch["impulse"] = 0.1
        tracker = ContactEventsSystem()
        rest = np.zeros((len(keys), 3))
        engine.physics.snapshot = Snapshot(1, 0.0, BodyState.from_arrays(
            keys, rng.random((len(keys), 3)), np.tile([1.0, 0, 0, 0], (len(keys), 1)), rest,
            rest).freeze())

        def frame() -> None:
            if not asleep:
                tracker._collect(Contacts(batch))
            tracker.run(engine, 0.01)

        tracker._collect(Contacts(batch))
        tracker.run(engine, 0.01)  # every pair begins: what follows is the steady state
        ours = _fastest_ms(frame, frames)
        assert len(tracker.touching) == pairs  # asleep: still touching
        ref = _fastest_ms(lambda: np.unique(pair_keys(batch["a"], batch["b"]),
                                            return_inverse=True), frames)
    return {"pairs": pairs, "state": "asleep" if asleep else "touching",
            "contacts": len(batch), "ms/frame": ours, "unique ms": ref, "ratio": ours / ref}


def bench_contacts(quick: bool = False) -> list[dict[str, Any]]:
    """Contact begin/end tracking (systems.contacts) with every pair touching frame after
    frame, and with every pair asleep (touched once, then checked for motion); reference:
    the least any tracker does, one pair key per contact and np.unique, timed in the same
    run."""
    return [_contacts_case(pairs, 50 if quick else 200, asleep)
            for pairs in ((200, 2000) if quick else (200, 2000, 20000))
            for asleep in (False, True)]
