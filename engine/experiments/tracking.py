"""The per-trial tracking log: the poses of the tracked objects (and the head) at a chosen
rate, ``tracking/trial-NNN.csv`` with the columns :data:`COLUMNS`.

A frame's sample is one gather of the tracked rows of the pose table into a preallocated
float32 buffer; full buffers are written raw to ``trial-NNN.bin`` (the times and frames
to ``trial-NNN.times.bin``) every :data:`FLUSH_ROWS` rows and turned into the CSV when the
trial ends, so the frame never formats text (2,000 objects at 90 Hz would take longer than
the frame). Positions and orientations are kept as float32 (7 significant digits: 10 µm
at 100 m). A trial killed before its end leaves its raw files, which a resumed session
removes with the trial it runs again.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

COLUMNS = ("t", "frame", "object", "x", "y", "z", "qw", "qx", "qy", "qz")
#: Pose rows buffered before a write to the raw file.
FLUSH_ROWS = 1 << 16


class TrackLog:
    """Samples of ``names``' poses for one trial, written to ``path`` (a .csv) at its end.

    While the trial runs, each sample's poses go into a preallocated float32 buffer (a
    copy of 28 bytes per object) and its time and frame into another; full buffers are
    written raw (``.bin`` and ``.times.bin``) without a copy."""

    def __init__(self, path: Path, names: list[str], rate: float) -> None:
        self.path = Path(path)
        self.raw = self.path.with_suffix(".bin")
        self.raw_times = self.path.with_suffix(".times.bin")
        self.names = list(names)
        self.period = 0.0 if rate <= 0 else 1.0 / rate
        self._next = -1.0
        n = max(1, len(self.names))
        self._poses = np.empty((max(1, FLUSH_ROWS // n), n, 7), np.float32)
        self._times = np.empty((len(self._poses), 2), np.float64)
        self._k = 0
        self._file = self.raw.open("wb")
        self._times_file = self.raw_times.open("wb")
        self.samples = 0

    def due(self, t: float) -> bool:
        return t + 1e-9 >= self._next

    def sample(self, t: float, frame: int, poses: np.ndarray) -> None:
        """One sample: ``poses`` is (n, 7), x y z qw qx qy qz of each name in order."""
        self._next = t + self.period if self._next < 0 else max(self._next + self.period, t)
        k = self._k
        self._poses[k] = poses
        self._times[k] = (t, frame)
        self._k = k + 1
        self.samples += 1
        if self._k == len(self._poses):
            self.flush()

    def flush(self) -> None:
        k, self._k = self._k, 0
        if k:
            self._file.write(memoryview(self._poses[:k]).cast("B"))
            self._times_file.write(memoryview(self._times[:k]).cast("B"))

    def close(self) -> Path:
        """Write the CSV (flushed and fsynced) and remove the raw samples."""
        self.flush()
        self._file.close()
        self._times_file.close()
        n = len(self.names)
        poses = np.fromfile(self.raw, dtype=np.float32).reshape(-1, max(1, n), 7)
        times = np.fromfile(self.raw_times, dtype=np.float64).reshape(-1, 2)
        names = self.names
        with self.path.open("w", encoding="utf-8", newline="") as f:
            f.write(",".join(COLUMNS) + "\n")
            for (t, frame), block in zip(times.tolist(), poses.tolist(), strict=True):
                head = f"{t:.6f},{int(frame)},"
                f.writelines(
                    f"{head}{names[i]},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f},{p[3]:.6f},"
                    f"{p[4]:.6f},{p[5]:.6f},{p[6]:.6f}\n" for i, p in enumerate(block[:n]))
            f.flush()
            os.fsync(f.fileno())
        self.raw.unlink()
        self.raw_times.unlink()
        return self.path

    def abandon(self) -> None:
        """Stop without a CSV (the trial did not finish)."""
        self._k = 0
        self._file.close()
        self._times_file.close()


#: The columns of a trial's wheel log (``trial-NNN.wheels.csv``).
WHEEL_COLUMNS = ("t", "frame", "wheel", "count", "turns", "rad_s")


class WheelLog:
    """The wheel counters' counts and rates at the tracking samples of one trial, written
    to ``path`` as they come (a few wheels: text is cheap), flushed and fsynced at its
    end; a trial run again starts the file afresh."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._file = self.path.open("w", encoding="utf-8", newline="")
        self._file.write(",".join(WHEEL_COLUMNS) + "\n")
        self.samples = 0

    def sample(self, t: float, frame: int, wheels: dict) -> None:
        """One sample of every wheel: name -> its state (count, turns, angular velocity)."""
        for name, wheel in sorted(wheels.items()):
            self._file.write(f"{t:.6f},{int(frame)},{name},{int(wheel.count)},"
                             f"{float(wheel.turns):.6f},{float(wheel.angular_velocity):.6f}\n")
        self.samples += 1

    def close(self) -> Path:
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()
        return self.path

    def abandon(self) -> None:
        self._file.close()


def read_tracking(path: Path) -> dict[str, np.ndarray]:
    """A tracking CSV's rows by object: (n, 9) arrays of t, frame, x y z, qw qx qy qz."""
    out: dict[str, list[list[float]]] = {}
    lines = Path(path).read_text(encoding="utf-8").splitlines()[1:]
    for line in lines:
        t, frame, name, *pose = line.split(",")
        out.setdefault(name, []).append([float(t), float(frame), *map(float, pose)])
    return {name: np.asarray(rows) for name, rows in out.items()}
