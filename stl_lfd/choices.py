"""The names users choose among, defined once: the packages validate against these tuples and
the command line builds its choices from them. A leaf module (no imports), so that `stlopt
--help` loads nothing heavy."""

SEMANTICS = ("classic", "new")  # space robustness; the robustness of Varnai & Dimarogonas
BACKENDS = ("pybullet", "kinematic", "command")  # a simulated Panda; the reference itself; an external program
RECORDED_SIGNALS = ("x", "y", "z", "gripper", "force")  # what every rollout records
