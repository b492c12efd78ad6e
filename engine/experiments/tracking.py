"""The per-trial tracking log: the poses of the tracked objects (and the head) at a chosen
rate, ``tracking/trial-NNN.csv`` with the columns :data:`COLUMNS`.

A frame's sample is one gather of the tracked rows of the pose table into a numpy block;
blocks are written as raw float64 to ``trial-NNN.bin`` every :data:`FLUSH_ROWS` rows and
turned into the CSV when the trial ends, so the frame never formats text (2,000 objects at
90 Hz would take longer than the frame). A trial killed before its end leaves its .bin,
which a resumed session removes with the trial it runs again.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

COLUMNS = ("t", "frame", "object", "x", "y", "z", "qw", "qx", "qy", "qz")
FLUSH_ROWS = 1 << 16
_WIDTH = 10  # t, frame, object index, x y z, qw qx qy qz


class TrackLog:
    """Samples of ``names``' poses for one trial, written to ``path`` (a .csv) at its end."""

    def __init__(self, path: Path, names: list[str], rate: float) -> None:
        self.path = Path(path)
        self.raw = self.path.with_suffix(".bin")
        self.names = list(names)
        self.period = 0.0 if rate <= 0 else 1.0 / rate
        self._next = -1.0
        self._chunks: list[np.ndarray] = []
        self._pending = 0
        self._file = self.raw.open("wb")
        self._index = np.arange(len(self.names), dtype=np.float64)
        self.samples = 0

    def due(self, t: float) -> bool:
        return t + 1e-9 >= self._next

    def sample(self, t: float, frame: int, poses: np.ndarray) -> None:
        """One sample: ``poses`` is (n, 7), x y z qw qx qy qz of each name in order."""
        self._next = t + self.period if self._next < 0 else max(self._next + self.period, t)
        block = np.empty((len(self.names), _WIDTH))
        block[:, 0] = t
        block[:, 1] = frame
        block[:, 2] = self._index
        block[:, 3:] = poses
        self._chunks.append(block)
        self._pending += len(block)
        self.samples += 1
        if self._pending >= FLUSH_ROWS:
            self.flush()

    def flush(self) -> None:
        if self._chunks:
            self._file.write(np.concatenate(self._chunks).tobytes())
            self._chunks, self._pending = [], 0

    def close(self) -> Path:
        """Write the CSV (flushed and fsynced) and remove the raw samples."""
        self.flush()
        self._file.close()
        data = np.fromfile(self.raw, dtype=np.float64).reshape(-1, _WIDTH)
        names = self.names
        with self.path.open("w", encoding="utf-8", newline="") as f:
            f.write(",".join(COLUMNS) + "\n")
            f.writelines(
                f"{r[0]:.6f},{int(r[1])},{names[int(r[2])]},{r[3]:.6f},{r[4]:.6f},"
                f"{r[5]:.6f},{r[6]:.6f},{r[7]:.6f},{r[8]:.6f},{r[9]:.6f}\n"
                for r in data.tolist())
            f.flush()
            os.fsync(f.fileno())
        self.raw.unlink()
        return self.path

    def abandon(self) -> None:
        """Stop without a CSV (the trial did not finish)."""
        self._chunks = []
        self._file.close()


def read_tracking(path: Path) -> dict[str, np.ndarray]:
    """A tracking CSV's rows by object: (n, 9) arrays of t, frame, x y z, qw qx qy qz."""
    out: dict[str, list[list[float]]] = {}
    lines = Path(path).read_text(encoding="utf-8").splitlines()[1:]
    for line in lines:
        t, frame, name, *pose = line.split(",")
        out.setdefault(name, []).append([float(t), float(frame), *map(float, pose)])
    return {name: np.asarray(rows) for name, rows in out.items()}
