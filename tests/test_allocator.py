"""Freed memory kept for reuse (`stl_lfd.allocator`), checked in fresh processes."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="the thresholds are glibc's")

# Minor page faults per round of four 1 MB arrays alive together (every page written), over 50
# rounds: what a kernel's temporaries do.
FAULTS = """
import json, resource, sys
import numpy as np
from stl_lfd.allocator import keep_freed_memory
kept = keep_freed_memory() if sys.argv[1] == "keep" else None
def round():
    arrays = [np.ones(1 << 17) for _ in range(4)]
round()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(50):
    round()
faults = (resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before) / 50
print(json.dumps({"kept": kept, "faults": faults, "variable": __import__("os").environ.get("MALLOC_MMAP_THRESHOLD_")}))
"""


def run(mode: str, **variables: str) -> dict:
    environment = {name: value for name, value in os.environ.items() if not name.startswith("MALLOC_")} | variables
    result = subprocess.run([sys.executable, "-c", FAULTS, mode], capture_output=True, text=True, env=environment, check=True)
    return json.loads(result.stdout)


def test_an_array_allocated_again_reuses_the_freed_pages():
    fresh, kept = run("fresh"), run("keep")
    assert fresh["faults"] > 500  # 4 x 256 pages of 4 KB, mostly faulted in anew each round
    assert kept["kept"] is True and kept["faults"] < 5
    assert kept["variable"] == str(32 << 20)  # processes it starts do the same


def test_a_users_own_setting_is_left_as_it_is():
    result = run("keep", MALLOC_MMAP_THRESHOLD_="65536")
    assert result["kept"] is False and result["variable"] == "65536"


def test_a_users_glibc_tunables_are_left_as_they_are():
    result = run("keep", GLIBC_TUNABLES="glibc.malloc.mmap_threshold=65536")
    assert result["kept"] is False and result["variable"] is None
