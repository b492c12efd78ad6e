"""A participant's session on disk: ``sessions/<experiment>/<participant>/``.

- ``session.json``: the design, the seed, the participant, the engine's version, a hash
  of the content folder, and every run of the session (started, resumed at which trial);
  replaced whole (written beside, fsynced, renamed) so it is never half written;
- ``trials.csv``: one row per finished trial, written whole, flushed and fsynced at the
  trial's end, so a run killed at any moment leaves the rows of the trials it finished
  intact; a resumed session keeps them byte for byte and starts at the first trial
  without a row (a torn last line, which a kill between two writes could leave, is cut);
- ``tracking/trial-NNN.csv``: the tracked objects' poses during each trial;
- ``input/trial-NNN.input``: each trial's input recording (``--record`` format), which
  ``colosseum experiment replay`` plays back.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from engine.experiments.design import Design, TrialPlan, columns

FIRST = ["participant", "block", "trial", "block_trial", "practice"]
LAST = ["start_s", "end_s", "wall_start", "lsl_start", "lsl_end", "outcome", "responses",
        "measures"]
SKIPPED_DIRS = {"__pycache__", ".git", "sessions"}


class SessionError(Exception):
    """A session that cannot be started or resumed (told as it is)."""


def engine_version() -> str:
    """The installed package's version (importlib.metadata loaded here, not at start-up)."""
    from importlib import metadata

    try:
        return metadata.version("colosseum")
    except metadata.PackageNotFoundError:
        return "unknown"


def content_hash(folder: Path) -> str:
    """sha256 over the content folder's files (names and bytes, sorted; caches left out)."""
    digest = hashlib.sha256()
    folder = Path(folder)
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder)
        if any(part in SKIPPED_DIRS or part.startswith(".") for part in rel.parts):
            continue
        if path.is_file() and not path.name.endswith((".pyc", ".bak")):
            digest.update(str(rel.as_posix()).encode() + b"\0")
            digest.update(path.read_bytes())
            digest.update(b"\0")
    return digest.hexdigest()


def design_json(design: Design) -> dict[str, Any]:
    data = asdict(design)
    data.pop("where", None)
    return data


def header(design: Design) -> list[str]:
    return [*FIRST, *columns(design), *LAST]


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with tmp.open("w", encoding="utf-8") as f:
        json.dump(data, f, indent=2, default=str)
        f.write("\n")
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def read_rows(path: Path) -> list[dict[str, str]]:
    """The finished trials' rows of a trials.csv."""
    with path.open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


class SessionFiles:
    """Opens (or resumes) a participant's session folder and writes its rows."""

    def __init__(self, root: Path, design: Design, participant: int, content: Path,
                 resume: bool = False, seed: int = 0) -> None:
        self.design, self.participant = design, participant
        self.folder = Path(root) / design.id / str(participant)
        self.trials_path = self.folder / "trials.csv"
        self.meta_path = self.folder / "session.json"
        self.header = header(design)
        self.rows: list[dict[str, str]] = []
        digest = content_hash(content)
        run = {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "resumed_at": None}
        if self.trials_path.exists() and not resume:
            raise SessionError(f"{self.folder}: participant {participant} has a session "
                               "already; --resume continues it (or choose another "
                               "participant number)")
        if resume and not self.meta_path.exists() and self.trials_path.exists():
            raise SessionError(f"{self.folder}: trials.csv without session.json; it cannot be "
                               "resumed safely (move the folder away to start again)")
        if resume and self.meta_path.exists():
            meta = json.loads(self.meta_path.read_text(encoding="utf-8"))
            if meta.get("design") != json.loads(json.dumps(design_json(design))):
                raise SessionError(f"{self.folder}: the Experiment block changed since this "
                                   "session began; it cannot be resumed with another design")
            if meta.get("content_hash") != digest:
                meta.setdefault("warnings", []).append(
                    f"{run['started']}: resumed with a changed content folder")
            self.rows = self._recover()
            run["resumed_at"] = len(self.rows) + 1
            meta.setdefault("runs", []).append(run)
            meta["content_hash_now"] = digest
            self.changed_content = meta.get("content_hash") != digest
        else:
            self.folder.mkdir(parents=True, exist_ok=True)
            meta = {"format": "colosseum-experiment-session", "version": 1,
                    "experiment": design.id, "participant": participant,
                    "seed": design.seed, "run_seed": seed,
                    "engine_version": engine_version(), "content": str(content),
                    "content_hash": digest, "design": design_json(design),
                    "group": design.group(participant) if design.factors else {},
                    "square_row": design.row(participant), "runs": [run]}
            self.changed_content = False
        (self.folder / "tracking").mkdir(exist_ok=True)
        (self.folder / "input").mkdir(exist_ok=True)
        self.meta = meta
        write_json_atomic(self.meta_path, meta)  # first: a trials.csv always has its design
        if not self.trials_path.exists():
            self._write_header()

    def _write_header(self) -> None:
        with self.trials_path.open("w", newline="", encoding="utf-8") as f:
            f.write(self._line(self.header))
            f.flush()
            os.fsync(f.fileno())

    @staticmethod
    def _line(values: list[Any]) -> str:
        out = io.StringIO()
        csv.writer(out, lineterminator="\n").writerow(values)
        return out.getvalue()

    def _recover(self) -> list[dict[str, str]]:
        """The rows written whole; a torn last line (a kill mid-write) is cut off."""
        if not self.trials_path.exists():  # killed before its header was written
            self._write_header()
        data = self.trials_path.read_bytes()
        keep = data[:data.rfind(b"\n") + 1]
        if keep != data:
            with self.trials_path.open("r+b") as f:
                f.truncate(len(keep))
                f.flush()
                os.fsync(f.fileno())
        if not keep:  # killed while the header was written
            self._write_header()
            return []
        rows = read_rows(self.trials_path)
        first = next(csv.reader([keep.split(b"\n", 1)[0].decode("utf-8")]))
        if first != self.header:
            raise SessionError(f"{self.trials_path}: its columns are not this design's")
        return rows

    def trial_file(self, kind: str, trial: int) -> Path:
        suffix = {"tracking": ".csv", "input": ".input"}[kind]
        return self.folder / kind / f"trial-{trial:03d}{suffix}"

    def write_row(self, plan: TrialPlan, start: float, end: float, wall: float,
                  lsl_start: float | None, lsl_end: float | None, outcome: str,
                  responses: dict[str, Any], measures: dict[str, float]) -> dict[str, str]:
        """Append the trial's row, flushed and fsynced before it returns."""
        values: dict[str, Any] = {
            "participant": self.participant, "block": plan.block, "trial": plan.index,
            "block_trial": plan.block_trial, "practice": int(plan.practice),
            **{c: plan.condition.get(c, "") for c in columns(self.design)},
            "start_s": f"{start:.6f}", "end_s": f"{end:.6f}", "wall_start": f"{wall:.6f}",
            "lsl_start": "" if lsl_start is None else f"{lsl_start:.6f}",
            "lsl_end": "" if lsl_end is None else f"{lsl_end:.6f}",
            "outcome": outcome, "responses": json.dumps(responses, sort_keys=True),
            "measures": json.dumps(measures, sort_keys=True)}
        line = self._line([values[c] for c in self.header])
        with self.trials_path.open("a", newline="", encoding="utf-8") as f:
            f.write(line)
            f.flush()
            os.fsync(f.fileno())
        row = {c: str(values[c]) for c in self.header}
        self.rows.append(row)
        return row

    def finish(self, summary: dict[str, Any]) -> None:
        self.meta.update(summary)
        write_json_atomic(self.meta_path, self.meta)
