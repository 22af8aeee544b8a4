"""How the process allocates memory: freed pages kept for the next arrays.

The kernels make many short-lived arrays of a few hundred kilobytes (a row of running sums,
the terms of a batch of plans). glibc serves each array above its threshold with fresh pages
from the system and returns them on free, so that every such array pays its page faults again:
a fifth of the new robustness's until. `keep_freed_memory` raises the thresholds, as the
`MALLOC_MMAP_THRESHOLD_` and `MALLOC_TRIM_THRESHOLD_` variables would: arrays up to
`MMAP_THRESHOLD` come from the heap, and up to `TRIM_THRESHOLD` of freed heap stays with the
process for reuse (its peak memory grows by a few percent). Elsewhere than glibc it does
nothing.
"""

from __future__ import annotations

import ctypes
import os

MMAP_THRESHOLD = 32 << 20  # bytes; glibc's own largest dynamic threshold
TRIM_THRESHOLD = 256 << 20  # bytes

# mallopt's parameters (malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3


def keep_freed_memory() -> bool:
    """Set this process's thresholds, and the variables that give processes it starts the same
    (a user's own setting of them is left as it is). True where glibc took them."""
    settings = {"MALLOC_MMAP_THRESHOLD_": MMAP_THRESHOLD, "MALLOC_TRIM_THRESHOLD_": TRIM_THRESHOLD}
    if any(name in os.environ for name in settings):
        return False
    mallopt = _mallopt()
    if mallopt is None:
        return False
    taken = bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))
    if taken:
        os.environ.update({name: str(value) for name, value in settings.items()})
    return taken


def _mallopt():
    """glibc's `mallopt`, from the symbols the process has loaded, or None."""
    try:
        function = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):
        return None
    function.argtypes, function.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    return function
