from pathlib import Path

from hypothesis import settings

ROOT = Path(__file__).resolve().parent.parent

# Deterministic property tests: the same examples on every run and machine.
settings.register_profile("default", derandomize=True, deadline=None, max_examples=150)
settings.load_profile("default")
