"""STL specifications: parsing (`parse`, `load_spec`) and robustness (`compile_spec`), and the parts of
a conjunction (`split_spec`); a signal file's robustness (`evaluate_file`), a spec's regions
as boxes (`region_boxes`), and the semantics' plain definitions (`definitions`)."""

from stl_lfd.choices import SEMANTICS
from stl_lfd.stl.components import SpecParts, split_spec
from stl_lfd.stl.evaluate import evaluate_file
from stl_lfd.stl.parser import load_spec, parse, resolve
from stl_lfd.stl.printer import format_formula, format_spec
from stl_lfd.stl.regions import region_boxes
from stl_lfd.stl.robustness import CostWarning, HorizonWarning, Robustness, compile_spec, horizon
from stl_lfd.stl.semantics import Semantics
from stl_lfd.stl.spec import Spec
from stl_lfd.stl.transformer import MAX_DEPTH

__all__ = [
    "MAX_DEPTH",
    "SEMANTICS",
    "CostWarning",
    "HorizonWarning",
    "Robustness",
    "Semantics",
    "compile_spec",
    "definitions",  # the module: the semantics' plain definitions, sample by sample
    "evaluate_file",
    "format_formula",
    "format_spec",
    "horizon",
    "load_spec",
    "parse",
    "region_boxes",
    "resolve",
    "split_spec",
    "Spec",
    "SpecParts",
]
