"""Benchmarks of stlopt (`make bench`). They run as `stlopt` does, keeping freed memory for
reuse (`stl_lfd.allocator`)."""

from stl_lfd import keep_freed_memory

keep_freed_memory()
