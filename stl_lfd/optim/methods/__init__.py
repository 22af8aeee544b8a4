"""Search methods: one class per method behind one protocol (`base.SearchMethod`), found by name.

    method = method_class("plan")(problem, optimizer)    # once per run
    method.propose(request)                               # -> [(x, phase), ...] for a batch

| name     | class                                    | what it does                                   |
|----------|------------------------------------------|------------------------------------------------|
| `stl`    | `stl.CompositeSearch`                    | composite BO on the spec's parts               |
| `plan`   | `plan.PlanSearch`                        | the same with each part's plan as prior        |
| `pi`     | `analytic.ProbabilityOfImprovement`      | the paper's probability of improvement         |
| `logei`  | `analytic.LogExpectedImprovementSearch`  | log expected improvement                       |
| `random` | `random.RandomSearch`                    | uniform random points (the baseline)           |

A new method is a `SearchMethod` subclass and one line in `REGISTRY` (`optim/method_registry.py`,
or `register(name, cls)` from outside the package); its tuning, settable from a task file under
its name, a frozen dataclass in `tuning.py` and one line in `SETTINGS`. Classes are imported on first use: naming
the methods, as the command line and the settings' checks do, loads no torch (nor this
package, which the settings would otherwise import back).
"""

from stl_lfd.lazy import lazy_exports
from stl_lfd.optim.method_registry import REGISTRY, SETTINGS, method_class, method_names, register, settings_class

_HOMES = {
    "Problem": "stl_lfd.optim.methods.base",
    "Request": "stl_lfd.optim.methods.base",
    "SearchMethod": "stl_lfd.optim.methods.base",
    "ProbabilityOfImprovement": "stl_lfd.optim.methods.analytic",
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
__all__ += ["REGISTRY", "SETTINGS", "method_class", "method_names", "register", "settings_class"]
