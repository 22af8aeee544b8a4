"""The names users choose among, defined once: the packages validate against these tuples and
the command line builds its choices from them. A leaf module (no imports), so that `stlopt
--help` loads nothing heavy. (The optimiser's methods and the execution backends are named by
their registries, `stl_lfd.optim.methods` and `stl_lfd.sim.registry`, which a new one joins.)"""

SEMANTICS = ("classic", "new")  # space robustness; the robustness of Varnai & Dimarogonas
DEFAULT_SEMANTICS = "new"  # the paper's, at every entry point (command line, task files, Python)
# The wrist force-torque sensor: external force (N) and torque (Nm) in the robot base frame.
WRENCH_SIGNALS = ("fx", "fy", "fz", "tx", "ty", "tz")
# What every rollout records (then each object frame's NAME_x, NAME_y, NAME_z and NAME_tilt, and
# the outcome signals of `Scene.recorded_signals`).
RECORDED_SIGNALS = ("x", "y", "z", "gripper", "force", "qx", "qy", "qz", "qw", "tilt") + WRENCH_SIGNALS
