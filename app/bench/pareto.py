"""``colosseum bench pareto``: what each engine's accuracy costs, setting by setting.

For each engine and each solver setting (QuickStep/chipmunk/MuJoCo/Bullet iterations
5, 10, 20, 40 at the steps 0.02, 0.01 and 0.005 s) two things are measured in the same
run: the CPU cost of a step of the boxes scene (``app/bench/physics.py``: N boxes of
1 m and 1 kg in columns of ten, μ 0.5, sleeping off, ``SIM_SECONDS`` of simulated time
from the drop) and the error of every case of ``colosseum bench accuracy`` that has a
goal (pendulum periods, the Bounce 0.8 rebound, the friction slide, the 10-crate stack),
as a share of its goal. A row's ``worst/goal`` is the largest of those shares: at most 1
means every goal holds at that setting.

The engines: ours on ODE; ours on pymunk (the planar boxes scene, the planar cases);
MuJoCo (its defaults, with ``opt.iterations`` set) and PyBullet (its defaults, with
``numSolverIterations`` set; the stack is its only accuracy case) where installed (both
optional: ``pip install .[anchors]``); and, for the cost only, libode stepped by a plain C
program twice: plain QuickStep with no engine policy (``app/bench/bench_ode.c`` POLICY=0)
and with the engine's step (``engine/physics/ode3d/stepper.h``).

Cost is per simulated second as well as per step, since a setting with a finer step
takes more steps: the frontier (``--plot``) is drawn over CPU ms per simulated second.

Then, measured interleaved ``repeats`` times: ours at the default settings against MuJoCo
at its defaults on the boxes scene at 60 Hz (sleeping off on both; then both with their
sleeping on, where the installed MuJoCo can sleep: 4.0 and later); the price of the
policy, ours against plain libode at the same iterations and step, with each policy turned
off in turn; and a settled scene asleep against the same scene awake. Each ratio is the
median of the repeats' own ratios, with their spread (min–max).

Run: ``colosseum bench pareto [--quick] [--json F] [--plot F.png]``.
"""

from __future__ import annotations

import math
import statistics
import subprocess
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from app.bench import accuracy as bench_accuracy
from app.bench import print_row
from app.bench.physics import box_positions, compile_reference
from engine.physics.backend import WorldSettings
from engine.physics.sleep import SLEEP_ANGULAR, SLEEP_LINEAR, SLEEP_TIME, SMOOTHING, STEADY_SHARE

ITERATIONS = (5, 10, 20, 40)
STEPS = (0.02, 0.01, 0.005)
#: Simulated seconds of the boxes scene timed per setting (the drop and the settling).
SIM_SECONDS = 2.0
HEADLINE_STEP = 1.0 / 60.0
GROUND_KEY = 10**6


# -- the boxes scene on each engine --------------------------------------------------------
def _ours(name: str, n: int, settings: WorldSettings) -> Any:
    """The boxes scene through our backend ``name`` (pymunk: the X–Z plane)."""
    from components import MaterialProps, Physical, Shape
    from engine.physics import create_backend

    backend = create_backend(name)
    backend.configure(settings)
    material = MaterialProps(friction=0.5)
    backend.add_body(GROUND_KEY, Physical(kind="static", mass=None, material=material,
                                          shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))]),
                     np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]))
    box = Physical(mass=1.0, shapes=[Shape("box", (1.0, 1.0, 1.0))], material=material)
    identity = np.array([1.0, 0.0, 0.0, 0.0])
    positions = box_positions(n)
    if name == "pymunk":
        positions = np.column_stack([1.2 * (np.arange(n) // 10), np.zeros(n), positions[:, 2]])
    for key, pos in enumerate(positions):
        backend.add_body(key, box, pos, identity)
    return backend


def time_ours(name: str, n: int, dt: float, steps: int, read_contacts: bool = False,
              **settings: Any) -> dict[str, float]:
    """CPU ms per step of our backend, the step and the readback of every body's state
    (what the dynamics system does each step), and with ``read_contacts`` the step's
    contacts with their impulses (what the engine's driver reads for contact events; ODE
    works their whole forces out only when they are read); ``settings`` over max_contacts
    4, sleeping off."""
    world = WorldSettings(**{"max_contacts": 4, "auto_sleep": False, **settings})
    backend = _ours(name, n, world)
    table = np.zeros((backend.body_count(), 13))
    t0 = time.thread_time()
    for _ in range(steps):
        backend.step(dt)
        backend.read_state_into(table)
        if read_contacts:
            backend.contacts()
    ms = (time.thread_time() - t0) / steps * 1e3
    asleep = backend.sleeping_count() if hasattr(backend, "sleeping_count") else 0
    backend.close()
    return {"ms": ms, "asleep": asleep}


def time_libode(exe: Path, n: int, dt: float, steps: int, iterations: int, policy: bool,
                forces: bool = False, **override: Any) -> dict[str, float]:
    """CPU ms per step of the plain C program: plain QuickStep, or the engine's step
    (``policy``) with the default world's settings (``override`` changes some); with
    ``forces`` it also reads every contact's whole force, as the engine's contact reports
    do."""
    w = WorldSettings(iterations=iterations, **override)
    sleep = int(policy and w.auto_sleep)
    out = subprocess.run([str(exe), str(n), str(steps), str(sleep), str(int(policy and forces)),
                          repr(SLEEP_TIME), repr(SLEEP_LINEAR), repr(SLEEP_ANGULAR),
                          repr(STEADY_SHARE), repr(SMOOTHING), str(w.iterations), repr(w.erp),
                          repr(w.cfm), repr(w.warm_start), repr(w.contact_softness),
                          str(w.exact_rows), str(int(policy)), repr(dt)],
                         check=True, capture_output=True, text=True).stdout
    fields = dict(item.split("=") for item in out.split())
    return {"ms": float(fields["ms_per_step"]), "asleep": float(fields["asleep"])}


def mujoco_sleeps() -> bool:
    """Whether the installed MuJoCo can put bodies to sleep (4.0 and later)."""
    import mujoco

    return hasattr(mujoco.mjtEnableBit, "mjENBL_SLEEP")


def mujoco_boxes(n: int, dt: float, iterations: int | None = None,
                 sleep: bool = False) -> tuple[Any, Any]:
    """The boxes scene in MuJoCo at its defaults (the step, μ 0.5 set; its sleeping
    enabled in the model, as its docs ask, when ``sleep``)."""
    import mujoco

    friction = 'friction="0.5 0.005 0.0001"'
    bodies = "".join(f'<body pos="{x} {y} {z}"><freejoint/><geom type="box" size=".5 .5 .5" '
                     f'mass="1" {friction}/></body>' for x, y, z in box_positions(n))
    flag = '<flag sleep="enable"/>' if sleep else ""
    model = mujoco.MjModel.from_xml_string(
        f'<mujoco><option timestep="{dt}">{flag}</option><worldbody>'
        f'<geom type="plane" size="0 0 1" {friction}/>{bodies}</worldbody></mujoco>')
    if iterations is not None:
        model.opt.iterations = iterations
    return model, mujoco.MjData(model)


def mujoco_asleep(data: Any) -> int:
    """How many of MuJoCo's bodies are asleep (its world body is always awake)."""
    return int(data.model.nbody - data.nbody_awake)


def time_mujoco(n: int, dt: float, steps: int, iterations: int | None = None,
                sleep: bool = False) -> dict[str, float]:
    import mujoco

    model, data = mujoco_boxes(n, dt, iterations, sleep)
    step = mujoco.mj_step
    t0 = time.thread_time()
    for _ in range(steps):
        step(model, data)
    asleep = float(mujoco_asleep(data)) if sleep else 0.0
    return {"ms": (time.thread_time() - t0) / steps * 1e3, "asleep": asleep}


@contextmanager
def _bullet(dt: float, iterations: int) -> Iterator[Any]:
    """A headless PyBullet client with a ground plane, closed afterwards."""
    import pybullet

    client = pybullet.connect(pybullet.DIRECT)
    try:
        pybullet.setGravity(0, 0, -9.81, physicsClientId=client)
        pybullet.setPhysicsEngineParameter(fixedTimeStep=dt, numSolverIterations=iterations,
                                           physicsClientId=client)
        plane = pybullet.createCollisionShape(pybullet.GEOM_PLANE, physicsClientId=client)
        ground = pybullet.createMultiBody(0, plane, physicsClientId=client)
        pybullet.changeDynamics(ground, -1, lateralFriction=0.5, physicsClientId=client)
        yield client
    finally:
        pybullet.disconnect(client)


def _bullet_boxes(client: int, positions: np.ndarray, half: float, mass: float) -> list[int]:
    import pybullet

    shape = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[half] * 3,
                                          physicsClientId=client)
    bodies = []
    for pos in positions:
        body = pybullet.createMultiBody(mass, shape, basePosition=[float(v) for v in pos],
                                        physicsClientId=client)
        pybullet.changeDynamics(body, -1, lateralFriction=0.5, physicsClientId=client)
        bodies.append(body)
    return bodies


def time_pybullet(n: int, dt: float, steps: int, iterations: int) -> dict[str, float]:
    import pybullet

    with _bullet(dt, iterations) as client:
        _bullet_boxes(client, box_positions(n), 0.5, 1.0)
        t0 = time.thread_time()
        for _ in range(steps):
            pybullet.stepSimulation(physicsClientId=client)
        return {"ms": (time.thread_time() - t0) / steps * 1e3, "asleep": 0.0}


def pybullet_stack(dt: float, iterations: int) -> float:
    """The 10-crate stack of ``bench accuracy`` in PyBullet: the top's drift (mm) in 20 s."""
    import pybullet

    size, count = bench_accuracy.STACK_BOX, bench_accuracy.STACK
    with _bullet(dt, iterations) as client:
        start = np.column_stack([np.zeros(count), np.zeros(count),
                                 size * (np.arange(count) + 0.5)])
        top = _bullet_boxes(client, start, size / 2, 1000.0 * size**3)[-1]
        for _ in range(round(bench_accuracy.STACK_TIME / dt)):
            pybullet.stepSimulation(physicsClientId=client)
        pos = pybullet.getBasePositionAndOrientation(top, physicsClientId=client)[0]
    return 1e3 * math.hypot(pos[0] - start[-1, 0], pos[1] - start[-1, 1])


def installed(module: str) -> bool:
    try:
        __import__(module)
    except ImportError:
        return False
    return True


# -- accuracy per setting --------------------------------------------------------------
def goal_cases() -> list[bench_accuracy.Case]:
    return [c for c in bench_accuracy.cases() if c.goal is not None]


def accuracy(engine: str, iterations: int, dt: float) -> dict[str, float]:
    """Each goal case's |error| as a share of its goal, and the worst; the stack's drift."""
    shares: dict[str, float] = {}
    drift = math.inf  # no stack case ran
    if engine == "pybullet":
        drift = pybullet_stack(dt, iterations)
        shares["stack"] = drift / 10.0
    for case in goal_cases() if engine != "pybullet" else ():
        if engine == "pymunk" and not case.planar:
            continue
        if engine == "mujoco":
            with bench_accuracy.solver(None, {"iterations": iterations}):
                got = bench_accuracy._mujoco_outcome(case.mujoco, dt)
        else:
            with bench_accuracy.solver({"iterations": iterations}):
                got = case.ours(engine, dt)
        error = abs(case.error_of(got.value))
        if case.group == "stack":
            drift = error if math.isfinite(error) else 1e9
        share = error / float(case.goal or 1.0)
        shares[case.group] = max(shares.get(case.group, 0.0), share if math.isfinite(share)
                                 else 1e9)  # a run that blew up: plain data, off the chart
    return {"worst/goal": max(shares.values()), "stack drift mm": drift,
            **{f"{k}/goal": v for k, v in shares.items()}}


# -- the grid ---------------------------------------------------------------------------
def _cost(engine: str, exe: Path, n: int, iterations: int, dt: float,
          steps: int) -> dict[str, float]:
    if engine in ("ode", "pymunk"):
        return time_ours(engine, n, dt, steps, iterations=iterations)
    if engine.startswith("libode"):
        return time_libode(exe, n, dt, steps, iterations, engine == "libode+stepper.h",
                           auto_sleep=False)
    if engine == "mujoco":
        return time_mujoco(n, dt, steps, iterations)
    return time_pybullet(n, dt, steps, iterations)


def engines() -> list[str]:
    """Ours, the plain-C references, and the peers that are installed."""
    out = ["ode", "pymunk", "libode plain", "libode+stepper.h"]
    return out + [m for m in ("mujoco", "pybullet") if installed(m)]


def grid(exe: Path, ns: tuple[int, ...], iterations: tuple[int, ...], steps: tuple[float, ...],
         seconds: float) -> list[dict[str, Any]]:
    """One row per engine, iterations and step: cost on the boxes scene, goal shares."""
    rows = []
    for dt in steps:
        for it in iterations:
            for engine in engines():
                row: dict[str, Any] = {"table": "frontier", "engine": engine,
                                       "iterations": it, "dt s": dt}
                for n in ns:
                    ms = _cost(engine, exe, n, it, dt, max(1, round(seconds / dt)))["ms"]
                    row[f"ms/step {n}"] = ms
                    row[f"ms/sim s {n}"] = ms / dt
                if not engine.startswith("libode"):
                    row.update(accuracy(engine, it, dt))
                print_row(row)
                rows.append(row)
    return rows


def frontier(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """The Pareto-optimal (cost, error) points, cheapest first: none both cheaper and at
    least as accurate."""
    best, out = math.inf, []
    for cost, error in sorted(points):
        if error < best:
            out.append((cost, error))
            best = error
    return out


# -- the headline figures, interleaved and repeated -----------------------------------------
def _spread(ratios: list[float]) -> dict[str, float]:
    return {"ratio": statistics.median(ratios), "min": min(ratios), "max": max(ratios),
            "runs": float(len(ratios))}


def versus_mujoco(ns: tuple[int, ...], seconds: float, repeats: int) -> list[dict[str, Any]]:
    """Ours at the default settings against MuJoCo at its defaults, 60 Hz, interleaved:
    both awake, and (where MuJoCo can sleep) both with their sleeping on."""
    pairs = [("ours", "mujoco")] + ([("ours sleeping", "mujoco sleeping")]
                                   if mujoco_sleeps() else [])
    rows = []
    for n in ns:
        steps = round(seconds / HEADLINE_STEP)
        times: dict[str, list[float]] = {who: [] for pair in pairs for who in pair}
        for _ in range(repeats):
            for ours, theirs in pairs:
                sleep = ours == "ours sleeping"
                times[theirs].append(time_mujoco(n, HEADLINE_STEP, steps, sleep=sleep)["ms"])
                times[ours].append(time_ours("ode", n, HEADLINE_STEP, steps,
                                             auto_sleep=sleep)["ms"])
        for ours, theirs in pairs:
            row = {"table": "defaults vs MuJoCo", "N": n, "ours": ours,
                   "ours ms/step": statistics.median(times[ours]), "mujoco": theirs,
                   "mujoco ms/step": statistics.median(times[theirs]),
                   **_spread([m / o for m, o in zip(times[theirs], times[ours], strict=True)])}
            row["faster by"] = row.pop("ratio")
            print_row(row)
            rows.append(row)
    return rows


#: Each policy turned off in turn (world settings), to price it against the defaults.
POLICIES: dict[str, dict[str, Any]] = {
    "policies on, sleeping off": {},
    "resting warm start off": {"warm_start": 0.0},
    "exact islands off": {"exact_rows": 0},
    "sleeping on (defaults: the scene falls asleep)": {"auto_sleep": True},
}


def price_of_policy(exe: Path, ns: tuple[int, ...], seconds: float, repeats: int,
                    iterations: int = 20) -> list[dict[str, Any]]:
    """Ours and the stepper.h program against plain QuickStep, same iterations and step."""
    rows = []
    for n in ns:
        steps = round(seconds / HEADLINE_STEP)
        plain: list[float] = []
        runs: dict[str, list[float]] = {k: [] for k in (*POLICIES, "libode+stepper.h",
                                                        "ours step only (no readback)",
                                                        "ours + contact reports",
                                                        "libode+stepper.h + every force")}
        for _ in range(repeats):
            plain.append(time_libode(exe, n, HEADLINE_STEP, steps, iterations, False)["ms"])
            runs["libode+stepper.h"].append(time_libode(
                exe, n, HEADLINE_STEP, steps, iterations, True, auto_sleep=False)["ms"])
            for name, settings in POLICIES.items():
                runs[name].append(time_ours("ode", n, HEADLINE_STEP, steps,
                                            iterations=iterations, **settings)["ms"])
            runs["ours step only (no readback)"].append(_step_only(n, steps, iterations))
            runs["ours + contact reports"].append(time_ours(
                "ode", n, HEADLINE_STEP, steps, read_contacts=True, iterations=iterations)["ms"])
            runs["libode+stepper.h + every force"].append(time_libode(
                exe, n, HEADLINE_STEP, steps, iterations, True, forces=True,
                auto_sleep=False)["ms"])
        for name, times in runs.items():
            row = {"table": "price of the policy", "N": n, "variant": name,
                   "ms/step": statistics.median(times), "plain ms/step": statistics.median(plain),
                   **_spread([t / p for t, p in zip(times, plain, strict=True)])}
            row["x plain"] = row.pop("ratio")
            print_row(row)
            rows.append(row)
    return rows


def _step_only(n: int, steps: int, iterations: int) -> float:
    """Ours without reading the bodies back: the readback's price is the difference."""
    backend = _ours("ode", n, WorldSettings(max_contacts=4, auto_sleep=False,
                                            iterations=iterations))
    t0 = time.thread_time()
    for _ in range(steps):
        backend.step(HEADLINE_STEP)
    ms = (time.thread_time() - t0) / steps * 1e3
    backend.close()
    return ms


def _sleeper(engine: str, n: int, sleep: bool) -> tuple[Any, Any, Any]:
    """The boxes scene on ``engine`` (ours on ODE, or MuJoCo) at its defaults, sleeping or
    not: its step at 60 Hz, how many boxes are asleep, and its closing."""
    if engine == "mujoco":
        import mujoco

        model, data = mujoco_boxes(n, HEADLINE_STEP, sleep=sleep)
        return (lambda: mujoco.mj_step(model, data), lambda: mujoco_asleep(data),
                lambda: None)
    backend = _ours("ode", n, WorldSettings(max_contacts=4, auto_sleep=sleep))
    return (lambda: backend.step(HEADLINE_STEP), backend.sleeping_count, backend.close)


def asleep_vs_awake(n: int, repeats: int, settle: float = 12.0,
                    engine: str = "ours") -> list[dict[str, Any]]:
    """A settled scene at the default settings once every body is asleep, against the same
    settled scene with sleeping off; and when it fell asleep (``engine``: ours on ODE, or
    MuJoCo with its own sleeping)."""
    ratios, fell, slept_ms, awake_ms = [], [], [], []
    for _ in range(repeats):
        sleeping, awake = _sleeper(engine, n, True), _sleeper(engine, n, False)
        when = math.nan
        for i in range(round(settle / HEADLINE_STEP)):
            sleeping[0]()
            awake[0]()
            if math.isnan(when) and sleeping[1]() == n:
                when = (i + 1) * HEADLINE_STEP
        times = []
        for step, _, close in (sleeping, awake):
            t0 = time.thread_time()
            for _ in range(60):
                step()
            times.append((time.thread_time() - t0) / 60 * 1e3)
            close()
        slept_ms.append(times[0])
        awake_ms.append(times[1])
        ratios.append(times[0] / times[1])
        fell.append(when)
    asleep_at = statistics.median(fell) if all(math.isfinite(t) for t in fell) else None
    row = {"table": "asleep vs awake", "engine": engine, "N": n, "all asleep at s": asleep_at,
           "asleep ms/step": statistics.median(slept_ms),
           "awake ms/step": statistics.median(awake_ms), **_spread(ratios)}
    row["x awake"] = row.pop("ratio")
    print_row(row)
    return [row]


def run_bench(quick: bool = False, repeats: int | None = None,
              ns: tuple[int, ...] | None = None) -> list[dict[str, Any]]:
    """The frontier grid, then the headline ratios; every row, each saying its table."""
    ns = ns or ((200,) if quick else (500, 2000))
    repeats = repeats or (2 if quick else 5)
    seconds = 0.5 if quick else SIM_SECONDS
    iterations = (5, 20) if quick else ITERATIONS
    steps = (0.02, 0.01) if quick else STEPS
    for module in ("mujoco", "pybullet"):
        if not installed(module):
            print(f"{module} is not installed: no {module} rows (pip install .[anchors])")
    with tempfile.TemporaryDirectory(prefix="colosseum-pareto-") as tmp:
        exe = compile_reference(Path(tmp))
        rows = grid(exe, ns, iterations, steps, seconds)
        if installed("mujoco"):
            rows += versus_mujoco(ns, 4.0 if not quick else 1.0, repeats)
        rows += price_of_policy(exe, ns, 4.0 if not quick else 1.0, repeats)
    rows += asleep_vs_awake(ns[0], max(1, repeats // 2))
    if installed("mujoco") and mujoco_sleeps():
        rows += asleep_vs_awake(ns[0], max(1, repeats // 2), engine="mujoco")
    return rows


def figures(rows: list[dict[str, Any]]) -> list[Any]:
    """Ours at defaults against MuJoCo at defaults (MuJoCo's ms over ours: above 1, ours
    is faster); the engine's step against plain QuickStep; asleep against awake."""
    from app.bench import Figure

    out = []
    for r in rows:
        if r["table"] == "defaults vs MuJoCo":
            mujoco = ("MuJoCo with its sleeping on" if r.get("mujoco") == "mujoco sleeping"
                      else "MuJoCo at its defaults")
            out.append(Figure(f"N={r['N']}, {r['ours']}", r["ours ms/step"], r["mujoco ms/step"],
                              "ms/step", f"{mujoco}, the same scene and step"))
        elif r["table"] == "price of the policy" and r["variant"] == "policies on, sleeping off":
            out.append(Figure(f"N={r['N']}, policy on", r["ms/step"], r["plain ms/step"],
                              "ms/step", "plain libode QuickStep, same iterations and step"))
        elif r["table"] == "asleep vs awake":
            who = "MuJoCo, " if r.get("engine") == "mujoco" else ""
            out.append(Figure(f"{who}N={r['N']} settled, asleep", r["asleep ms/step"],
                              r["awake ms/step"], "ms/step", "the same scene awake"))
    return out


def plot(data: dict[str, Any], path: Path) -> Path:
    """Worst error over goal, and the stack's drift, against CPU ms per simulated second
    on the boxes scene: a point per setting, each engine's frontier as a line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in data["rows"] if r["table"] == "frontier" and "worst/goal" in r]
    n = next((k.split()[-1] for k in (rows[0] if rows else {}) if k.startswith("ms/sim s")), "")
    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for ax, key, label in ((axes[0], "worst/goal", "worst |error| / goal (1: at the goal)"),
                           (axes[1], "stack drift mm", "10-crate stack: top's drift in 20 s (mm)")):
        for i, engine in enumerate(dict.fromkeys(r["engine"] for r in rows)):
            mine = [r for r in rows if r["engine"] == engine and math.isfinite(r[key])]
            colour = f"C{i}"
            ax.scatter([r[f"ms/sim s {n}"] for r in mine], [max(r[key], 1e-3) for r in mine],
                       color=colour, s=18)
            for r in mine:
                ax.annotate(f"{r['iterations']}/{r['dt s']:g}", (r[f"ms/sim s {n}"],
                            max(r[key], 1e-3)), fontsize=6, color=colour)
            front = frontier([(r[f"ms/sim s {n}"], max(r[key], 1e-3)) for r in mine])
            ax.step([c for c, _ in front], [e for _, e in front], where="post", color=colour,
                    label=engine)
        ax.axhline(1.0 if key == "worst/goal" else 10.0, color="grey", lw=0.8, ls="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"CPU ms per simulated second, {n} boxes")
        ax.set_ylabel(label)
        ax.legend(fontsize=8, title="iterations/step s", title_fontsize=7)
    when = f", {data['date'][:10]}" if data.get("date") else ""
    fig.suptitle(f"colosseum bench pareto ({data['machine']['platform']}{when})", fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    import argparse

    from app.bench import print_table

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--repeats", type=int, default=None)
    parser.add_argument("--n", type=int, nargs="+", default=None, help="boxes (500 2000)")
    args = parser.parse_args(argv)
    rows = run_bench(args.quick, args.repeats, tuple(args.n) if args.n else None)
    for table in dict.fromkeys(r["table"] for r in rows):
        print(f"\n{table}")
        print_table([r for r in rows if r["table"] == table])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
