"""``colosseum experiment report sessions/<experiment>``: what the sessions say.

Reads every participant's trials.csv (practice trials left out of the summaries), and
writes into ``--out`` (default ``<folder>/report``):

- ``summary.csv``: per condition (each factor's level) the number of trials, the task
  time's mean, standard deviation, minimum and maximum (s), each outcome's count, and the
  mean of every numeric measure and response;
- ``thresholds.csv``: each participant's staircase estimates (session.json);
- ``times.png``: task times per condition (a box per condition, the trials as points);
- ``trajectories.png``: the tracked objects' paths from above (x, y), a colour per
  condition, one panel per object, over the floor plan (the content's static boxes:
  walls, counters, tables);
- ``heatmap.png``: where each tracked object went (a 2D histogram of its samples);
- ``gaze.png``: where the head looked (TrackCamera): the floor point its line of sight
  meets, or, looking above the horizon, the point :data:`GAZE_REACH` m ahead of it.

The table is printed too. Exit codes: 0 written, 1 nothing to report.
"""

from __future__ import annotations

import csv
import json
import math
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

from engine.experiments.tracking import read_tracking

#: Panels of trajectories and heat maps at most (the first tracked objects).
MAX_PANELS = 4
#: How far ahead (m) a look that never meets the floor is counted, on the floor plan.
GAZE_REACH = 3.0


def floor_plan(content: Path) -> list[Any]:
    """The footprints (4 corners x, y each) of the static boxes of a content folder's
    scene that stand between the floor and head height (walls, counters, tables): drawn
    under the trajectories. Empty when the scene cannot be read (told in the log)."""
    import logging

    import numpy as np

    from components import Physical, Transform
    from engine.rotation import quat_to_matrix
    from engine.scene import SceneError, load_spec

    try:
        spec = load_spec(Path(content))
    except (SceneError, OSError) as exc:
        logging.getLogger("colosseum.experiment").warning(
            "report: no floor plan from %s: %s", content, str(exc).splitlines()[0])
        return []
    plan = []
    for entity in spec.entities:
        body = next((c for c in entity.components if isinstance(c, Physical)), None)
        pose = next((c for c in entity.components if isinstance(c, Transform)), None)
        if body is None or pose is None or body.kind != "static":
            continue
        turn = quat_to_matrix(np.asarray(pose.orientation, float))
        for shape in body.shapes:
            if shape.kind != "box":
                continue
            centre = np.asarray(pose.position, float) + turn @ np.asarray(shape.offset, float)
            axes = turn @ quat_to_matrix(np.asarray(shape.rotation, float))
            half = np.asarray(shape.size[:3], float) / 2
            if centre[2] + half[2] < 0.05 or centre[2] - half[2] > 2.0:
                continue
            corners = [centre + axes @ (half * np.array([sx, sy, 0.0]))
                       for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            plan.append(np.array(corners)[:, :2])
    return plan


def _draw_plan(ax: Any, plan: list[Any]) -> None:
    from matplotlib.patches import Polygon

    for corners in plan:
        ax.add_patch(Polygon(corners, closed=True, facecolor="0.85", edgecolor="0.55",
                             linewidth=0.5, zorder=0))


def gaze_points(samples: Any) -> Any:
    """Where a head looked, per tracking sample (rows of t, frame, x y z, qw qx qy qz; the
    camera looks along its local +y): on the floor plan (x, y), the point its line of
    sight meets the floor (z = 0), or the point GAZE_REACH m ahead when it looks level or
    up, or would meet the floor farther than that.

    >>> import numpy as np
    >>> down = [0, 0, 0, 0, 1.6, np.cos(-np.pi / 8), np.sin(-np.pi / 8), 0, 0]  # 45° down
    >>> [round(float(v), 6) for v in gaze_points(np.array([down]))[0]]
    [0.0, 1.6]
    """
    import numpy as np

    from engine.rotation import quat_to_matrix

    eye = samples[:, 2:5]
    forward = np.array([quat_to_matrix(q)[:, 1] for q in samples[:, 5:9]])
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = np.where(forward[:, 2] < -1e-9, -eye[:, 2] / forward[:, 2], np.inf)
    reach = np.minimum(reach, GAZE_REACH)
    return (eye + forward * reach[:, None])[:, :2]


def _sessions(folder: Path) -> list[Path]:
    return sorted((p for p in folder.iterdir() if (p / "trials.csv").is_file()),
                  key=lambda p: (not p.name.isdigit(), int(p.name) if p.name.isdigit()
                                 else 0, p.name)) if folder.is_dir() else []


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float) and math.isfinite(value):
        return float(value)
    return None


def _stats(xs: list[float]) -> dict[str, float]:
    n = len(xs)
    mean = sum(xs) / n
    sd = math.sqrt(sum((x - mean) ** 2 for x in xs) / (n - 1)) if n > 1 else 0.0
    return {"mean": mean, "sd": sd, "min": min(xs), "max": max(xs)}


def summarise(folder: Path) -> tuple[list[str], list[dict[str, Any]], list[dict[str, Any]]]:
    """The condition columns, one summary per condition, every trial (with its session)."""
    trials: list[dict[str, Any]] = []
    factors: list[str] = []
    for session in _sessions(folder):
        meta = json.loads((session / "session.json").read_text(encoding="utf-8"))
        design = meta.get("design", {})
        factors = [f["id"] for f in design.get("factors", [])] + \
                  [s["id"] for s in design.get("staircases", [])]
        with (session / "trials.csv").open(newline="", encoding="utf-8") as f:
            for row in csv.DictReader(f):
                trials.append({**row, "_session": session})
    groups: dict[tuple[str, ...], list[dict[str, Any]]] = defaultdict(list)
    for t in trials:
        if t["practice"] != "1":
            groups[tuple(t.get(k, "") for k in factors)].append(t)
    summaries = []
    for key, group in sorted(groups.items()):
        times = [float(t["end_s"]) - float(t["start_s"]) for t in group]
        row: dict[str, Any] = dict(zip(factors, key, strict=True))
        row["trials"] = len(group)
        row.update({f"time_{k}": round(v, 6) for k, v in _stats(times).items()})
        outcomes: dict[str, int] = defaultdict(int)
        values: dict[str, list[float]] = defaultdict(list)
        for t in group:
            outcomes[t["outcome"]] += 1
            for column in ("measures", "responses"):
                for name, value in json.loads(t[column] or "{}").items():
                    number = _number(value)
                    if number is not None:
                        values[f"{column[:-1]}_{name}"].append(number)
        row.update({f"outcome_{k}": v for k, v in sorted(outcomes.items())})
        row.update({f"{k}_mean": round(sum(v) / len(v), 6) for k, v in sorted(values.items())})
        summaries.append(row)
    return factors, summaries, trials


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, columns, restval="")
        writer.writeheader()
        writer.writerows(rows)


def _label(factors: list[str], trial: dict[str, Any]) -> str:
    return " ".join(f"{k}={trial[k]}" for k in factors if trial.get(k)) or "-"


def plots(out: Path, factors: list[str], trials: list[dict[str, Any]],
          plan: list[Any] | None = None) -> list[Path]:
    """The report's figures: task times per condition, each tracked path from above with
    where it went, and where the head looked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    made = []
    real = [t for t in trials if t["practice"] != "1"]
    labels = sorted({_label(factors, t) for t in real})
    if labels:
        made.append(_times_plot(out, factors, real, labels, plt))
    paths: dict[str, list[tuple[str, Any]]] = defaultdict(list)
    for t in real:
        track = Path(t["_session"]) / "tracking" / f"trial-{int(t['trial']):03d}.csv"
        if track.is_file():
            for name, samples in read_tracking(track).items():
                paths[name].append((_label(factors, t), samples))
    names = sorted(paths)[:MAX_PANELS]
    if names:
        made += _path_plots(out, names, paths, labels, plan or [], plt)
    if paths.get("head"):
        made.append(_gaze_plot(out, [s for _, s in paths["head"]], plt))
    return made


def _times_plot(out: Path, factors: list[str], real: list[dict[str, Any]],
                labels: list[str], plt: Any) -> Path:
    """``times.png``: the task times of each condition, a box and its points."""
    fig, ax = plt.subplots(figsize=(max(6, 1.2 * len(labels)), 4))
    data = [[float(t["end_s"]) - float(t["start_s"]) for t in real
             if _label(factors, t) == label] for label in labels]
    ax.boxplot(data)
    ax.set_xticks(range(1, len(labels) + 1), labels, rotation=30, ha="right")
    for i, ys in enumerate(data, start=1):
        ax.plot([i] * len(ys), ys, "o", alpha=0.4, color="tab:blue")
    ax.set_ylabel("task time (s)")
    ax.set_title("task times per condition")
    fig.tight_layout()
    fig.savefig(out / "times.png", dpi=100)
    plt.close(fig)
    return out / "times.png"


def _path_plots(out: Path, names: list[str], paths: dict[str, list[tuple[str, Any]]],
                labels: list[str], plan: list[Any], plt: Any) -> list[Path]:
    """``trajectories.png`` (each tracked thing's paths from above, coloured by condition)
    and ``heatmap.png`` (where it went), a panel per tracked thing."""
    import numpy as np

    colours = {label: plt.cm.tab10(i % 10) for i, label in enumerate(labels)}
    fig, axes = plt.subplots(1, len(names), figsize=(5 * len(names), 5), squeeze=False)
    heat, haxes = plt.subplots(1, len(names), figsize=(5 * len(names), 4.5), squeeze=False)
    for ax, hax, name in zip(axes[0], haxes[0], names, strict=True):
        _draw_plan(ax, plan)
        seen = set()
        for label, samples in paths[name]:
            colour = colours.get(label, "grey")
            ax.plot(samples[:, 2], samples[:, 3], color=colour, alpha=0.6,
                    label=None if label in seen else label)
            ax.plot(samples[:1, 2], samples[:1, 3], "o", color=colour, ms=3)  # start
            seen.add(label)
        ax.set_title(f"{name} from above")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize="small")
        xy = np.concatenate([s[:, 2:4] for _, s in paths[name]])
        counts = hax.hist2d(xy[:, 0], xy[:, 1], bins=40, cmap="magma")[3]
        heat.colorbar(counts, ax=hax, label="samples")
        hax.set_title(f"where {name} went")
        hax.set_xlabel("x (m)")
        hax.set_ylabel("y (m)")
    fig.tight_layout()
    fig.savefig(out / "trajectories.png", dpi=100)
    heat.tight_layout()
    heat.savefig(out / "heatmap.png", dpi=100)
    plt.close(fig)
    plt.close(heat)
    return [out / "trajectories.png", out / "heatmap.png"]


def _gaze_plot(out: Path, samples: list[Any], plt: Any) -> Path:
    """``gaze.png``: a 2D histogram of where the head looked (see :func:`gaze_points`)."""
    import numpy as np

    xy = np.concatenate([gaze_points(s) for s in samples])
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    counts = ax.hist2d(xy[:, 0], xy[:, 1], bins=40, cmap="viridis")[3]
    fig.colorbar(counts, ax=ax, label="samples")
    ax.set_title(f"where the head looked (the floor, or {GAZE_REACH:g} m ahead)")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal", adjustable="datalim")
    fig.tight_layout()
    fig.savefig(out / "gaze.png", dpi=100)
    plt.close(fig)
    return out / "gaze.png"


def report(folder: Path, out: Path | None = None) -> int:
    folder = Path(folder)
    if not _sessions(folder):
        print(f"colosseum: error: {folder}: no sessions (sessions/<experiment>/<participant>/"
              "trials.csv)", file=sys.stderr)
        return 1
    out = Path(out) if out is not None else folder / "report"
    out.mkdir(parents=True, exist_ok=True)
    factors, summaries, trials = summarise(folder)
    _write_csv(out / "summary.csv", summaries)
    thresholds = []
    for session in _sessions(folder):
        meta = json.loads((session / "session.json").read_text(encoding="utf-8"))
        for sid, value in (meta.get("thresholds") or {}).items():
            thresholds.append({"participant": session.name, "staircase": sid,
                               "threshold": value})
    if thresholds:
        _write_csv(out / "thresholds.csv", thresholds)
    contents = {json.loads((session / "session.json").read_text(encoding="utf-8")).get(
        "content") for session in _sessions(folder)}
    content = next(iter(contents)) if len(contents) == 1 else None
    plan = floor_plan(Path(content)) if content and Path(content).is_dir() else []
    made = plots(out, factors, trials, plan)
    participants = len(_sessions(folder))
    print(f"{folder}: {participants} participant(s), {len(trials)} trial(s)")
    for row in summaries:
        label = " ".join(f"{k}={row[k]}" for k in factors if row.get(k)) or "-"
        print(f"  {label:<32} n={row['trials']:<4} time {row['time_mean']:.3f} ± "
              f"{row['time_sd']:.3f} s")
    for row in thresholds:
        print(f"  participant {row['participant']}: staircase {row['staircase']} threshold "
              f"{row['threshold']:.4g}")
    print(f"written: {', '.join(str(p) for p in [out / 'summary.csv', *made])}")
    return 0
