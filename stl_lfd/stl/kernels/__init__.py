"""The numerical kernels of the robustness semantics: n-ary conjunctions and sliding windows,
one module per operator, vectorised over any leading axes.

    semantics.py       the two semantics as strategies (ClassicKernels, NewKernels): what a
                       conjunction, a window and an until are in each; the compiler asks them
    conjunction.py     the classic minimum and the new robustness's conjunction and disjunction
                       (the new conjunction's formula is written once, here)
    windows.py         sliding minima and window conjunctions (G, F with a bounded interval)
    until.py           left U[a, b] right, classic and new
    sums.py, terms.py  the new conjunction's running and tail sums, term by term
    interpolation.py   the same sums by interpolation at Chebyshev points, where exact
    memory.py          chunking and padding; budgets.py: every tuning constant and its reason

All functions take and return float arrays; reductions run along the last axis. Infinite
operands stand for empty windows: +inf is the identity of a conjunction, -inf of a
disjunction. Every kernel is tested against the brute-force definitions of
`stl_lfd.stl.definitions`.
"""

from stl_lfd.stl.kernels.conjunction import classic_conjunction, new_conjunction, new_conjunction_of, new_disjunction
from stl_lfd.stl.kernels.semantics import KERNELS, ClassicKernels, NewKernels
from stl_lfd.stl.kernels.until import classic_until, new_until
from stl_lfd.stl.kernels.windows import new_windows, suffix_min, window_min

__all__ = [
    "KERNELS",
    "ClassicKernels",
    "NewKernels",
    "classic_conjunction",
    "classic_until",
    "new_conjunction",
    "new_conjunction_of",
    "new_disjunction",
    "new_until",
    "new_windows",
    "suffix_min",
    "window_min",
]
