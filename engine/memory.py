"""How the process keeps memory: the C allocator a frame's freed memory for the next frame,
and the cyclic GC away from a load's many objects (:func:`paused_gc`).

A frame builds and drops numpy arrays of a few hundred kilobytes (the animation mixer's
blends, instance data, contact batches). glibc serves allocations over its mmap
threshold (128 kB to start) with fresh pages and returns them when freed, and gives the
top of its heap back to the system past its trim threshold: each frame then faults the
same memory in again. For 100 animated avatars that was 590 page faults and 1.1 ms of
system time a frame, 40 % of the animation's cost. Kept in the heap instead (up to
TRIM_THRESHOLD bytes of it free at its top), the next frame reuses it.
"""

from __future__ import annotations

import ctypes
import gc
import logging
from collections.abc import Iterator
from contextlib import contextmanager

log = logging.getLogger("colosseum")

#: Allocations below this many bytes come from the heap, not fresh mmap'd pages.
MMAP_THRESHOLD = 4 << 20
#: Bytes free at the top of the heap before glibc gives them back to the system.
TRIM_THRESHOLD = 16 << 20
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # glibc's mallopt parameters


def keep_freed_memory() -> bool:
    """Set glibc's thresholds for a frame loop; False where the C library is not glibc
    (nothing to do there). ``mallopt`` is looked up among the symbols the process has
    loaded (the C library among them): ``ctypes.util.find_library`` would run
    ``ldconfig`` and import ``subprocess`` at every command's start."""
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):
        return False
    ok = bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(
        mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))
    if not ok:
        log.debug("the C library refused its allocation thresholds; left as they were")
    return ok


@contextmanager
def paused_gc() -> Iterator[None]:
    """Pause the cyclic GC while building many small objects that all stay alive.

    Without this, collections re-scan the growing tree again and again. A big
    load (a scene file, its specs, its entities) is then frozen (``gc.freeze``):
    it lives as long as the scene, so scanning it in later collections would only
    cost time (about a third of a second per collection for 10,000 objects).
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if gc.get_count()[0] > _FREEZE_AFTER:
            gc.freeze()
        if was_enabled:
            gc.enable()


#: New GC-tracked objects above which a load is frozen instead of scanned later.
_FREEZE_AFTER = 100_000
