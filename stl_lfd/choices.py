"""The names users choose among, defined once: the packages validate against these tuples and
the command line builds its choices from them. A leaf module (no imports), so that `stlopt
--help` loads nothing heavy. (The optimiser's methods are named by their registry,
`stl_lfd.optim.methods`, which a new method joins.)"""

SEMANTICS = ("classic", "new")  # space robustness; the robustness of Varnai & Dimarogonas
BACKENDS = ("pybullet", "kinematic", "command")  # a simulated Panda; the reference itself; an external program
RECORDED_SIGNALS = ("x", "y", "z", "gripper", "force", "qx", "qy", "qz", "qw", "tilt")  # what every rollout records
