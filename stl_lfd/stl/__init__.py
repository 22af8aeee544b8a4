"""STL specifications: parsing (`parse`, `load_spec`) and robustness (`compile_spec`), and the parts of
a conjunction (`split_spec`)."""

from stl_lfd.choices import SEMANTICS
from stl_lfd.stl.components import SpecParts, split_spec
from stl_lfd.stl.parser import load_spec, parse, resolve
from stl_lfd.stl.printer import format_formula, format_spec
from stl_lfd.stl.robustness import CostWarning, HorizonWarning, Robustness, compile_spec, horizon
from stl_lfd.stl.semantics import Semantics
from stl_lfd.stl.spec import Spec

__all__ = [
    "SEMANTICS",
    "CostWarning",
    "HorizonWarning",
    "Robustness",
    "Semantics",
    "compile_spec",
    "format_formula",
    "format_spec",
    "horizon",
    "load_spec",
    "parse",
    "resolve",
    "split_spec",
    "Spec",
    "SpecParts",
]
