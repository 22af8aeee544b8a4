"""The generator of the bundled pose demonstrations (`demos/make_turn.py`), for tests that need
variations of them (other seeds, counts, turns, a rigid motion)."""

from __future__ import annotations

import importlib.util

from tests.conftest import ROOT

_spec = importlib.util.spec_from_file_location("make_turn", ROOT / "demos" / "make_turn.py")
_module = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_module)

pose_demos = _module.pose_demos
write_pose_demos = _module.write_pose_demos
