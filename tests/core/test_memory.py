"""A frame loop keeps the memory it frees: arrays of a few hundred kilobytes made and
dropped every frame are served from the heap again, not faulted in afresh (in a fresh
process, since the setting is the process's)."""

from __future__ import annotations

import subprocess
import sys

import pytest

FRAMES = """
import resource, sys
import numpy as np
from engine.memory import keep_freed_memory
if sys.argv[1] == "keep" and not keep_freed_memory():
    print("skip")
    raise SystemExit
def frame():
    a = np.ones(100_000)  # 800 kB, over glibc's first mmap threshold
    return float((a * 2.0).sum())
for _ in range(10):
    frame()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(100):
    frame()
print((resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 100)
"""


def faults_per_frame(mode: str) -> float:
    out = subprocess.run([sys.executable, "-c", FRAMES, mode], capture_output=True, text=True,
                         timeout=60, check=True).stdout.strip()
    if out == "skip":
        pytest.skip("the C library is not glibc: nothing to set")
    return float(out)


def test_a_frame_reuses_the_memory_the_last_frame_freed():
    assert faults_per_frame("default") > 100  # 2 x 800 kB of fresh pages a frame
    assert faults_per_frame("keep") < 1
