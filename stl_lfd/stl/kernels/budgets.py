"""The kernels' tuning constants, each with why it has its value (most were measured on
the benchmark's traces, see `benchmarks/bench_stl.py`). Kernels read them as `NAME`,
so that a test can lower one to reach a rarely taken path.
"""

from __future__ import annotations

import math

import numpy as np

# --- memory ---

# Largest number of array elements a windowed evaluation materialises at once.
CHUNK_ELEMENTS = 1 << 22
# Sizes up to which `_blocks` pads freely (a block's calls cost more than its padding).
PADDED_SIZE = 64

# --- conjunction ---

# Operands of fewer elements than this, more than four of them, are stacked (measured).
STACKED_BELOW = 128
# Elements of each operand that `new_conjunction_of` takes at once: its operands and
# temporaries stay in cache (measured: 3 operands of 128 x 2,200, 12.5 ms whole, 4.9 ms so).
CACHED_OPERAND_ELEMENTS = 1 << 13

# --- until ---

# Elements of one block of owners x samples: small enough to stay in cache.
BLOCK_ELEMENTS = 1 << 16

# --- terms ---

# Up to this nu, exp(-nu x_k) is exp(-nu v_k / |m|) times a constant of the owner (one multiply
# a term instead of three); above it the constant would leave the floating-point range.
FACTORED_NU_MAX = 20.0

# --- interpolation ---

# Numbers of points R an owner may take (the fewest that are exact enough), and its row with it.
POINT_COUNTS = (12, 16, 20, 24, 32, 40, 48)
INTERPOLATION_ERROR = 1e-14
LOG_FACTORIALS = np.array([math.lgamma(count + 1) for count in POINT_COUNTS])
# Largest log f(t_r) an owner's node values may reach: the interpolation's rounding grows with
# them (f is at most 1 on the owner's own samples, larger below its scale).
NODE_VALUE_LOG_MAX = 2.0
# Cost of one node at one sample or one owner, in terms summed one by one (measured).
INTERPOLATION_COST = 4
# Running sums are taken within blocks of this many samples, as one product with a lower
# triangular matrix of ones (several times faster than cumsum, measured), then across blocks.
RUNNING_BLOCK = 16
LOWER_ONES = np.tril(np.ones((RUNNING_BLOCK, RUNNING_BLOCK)))
# Elements of the running sums of one chunk of rows: small enough to stay in cache with their
# owners' terms (measured: larger chunks, memory-bound, took twice as long).
CACHED_ELEMENTS = 1 << 17

# --- windows ---

# Windows at least this wide take the interpolation where it is exact (see interpolation.py): outputs are
# taken in groups of `width`, whose windows span 2 x width - 1 samples, a group's owners (the
# windows' minima) sharing the running sums of the basis over that span.
INTERPOLATED_WIDTH_MIN = 64
# Cost of one node at one sample or one owner, in window operands (measured; a window's new
# conjunction costs more an operand than a tail sum a term).
WINDOW_INTERPOLATION_COST = 1
