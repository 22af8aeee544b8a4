"""How the process allocates memory: freed pages kept for the next arrays.

The kernels make many short-lived arrays of a few hundred kilobytes (a row of running sums,
the terms of a batch of plans). glibc serves each array above its threshold with fresh pages
from the system and returns them on free, so that every such array pays its page faults again:
a fifth of the new robustness's until. `keep_freed_memory` raises the thresholds, as the
`MALLOC_MMAP_THRESHOLD_` and `MALLOC_TRIM_THRESHOLD_` variables would: arrays up to
`MMAP_THRESHOLD` come from the heap, which returns freed memory at its top to the system only
beyond `TRIM_THRESHOLD`. So the process keeps what its largest arrays freed, until it ends
(freed memory below a live allocation is kept whatever the threshold); its peak memory grew
by a few percent in a run measured. Elsewhere than glibc it does nothing.
"""

from __future__ import annotations

import ctypes
import os
from typing import Callable

MMAP_THRESHOLD = 32 << 20  # bytes; glibc's own largest dynamic threshold
TRIM_THRESHOLD = 256 << 20  # bytes

# mallopt's parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3


def keep_freed_memory() -> bool:
    """Set this process's thresholds, and the variables that give processes it starts the same.
    A user's own setting of either threshold (by these variables or `GLIBC_TUNABLES`) is left
    as it is, and so is the other. True where glibc took them."""
    settings = {"MALLOC_MMAP_THRESHOLD_": MMAP_THRESHOLD, "MALLOC_TRIM_THRESHOLD_": TRIM_THRESHOLD}
    tunables = os.environ.get("GLIBC_TUNABLES", "")
    if any(name in os.environ for name in settings) or "mmap_threshold" in tunables or "trim_threshold" in tunables:
        return False
    mallopt = _mallopt()
    if mallopt is None:
        return False
    taken = bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))
    if taken:
        os.environ.update({name: str(value) for name, value in settings.items()})
    return taken


def _mallopt() -> Callable[[int, int], int] | None:
    """glibc's `mallopt`, from the symbols the process has loaded, or None."""
    try:
        function = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):
        return None
    function.argtypes, function.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    return function
