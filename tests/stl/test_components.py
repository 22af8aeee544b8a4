"""Specs split at their top-level conjunction: the parts compose to the spec's robustness."""

import numpy as np
import pytest

from stl_lfd.stl import compile_spec, load_spec, parse, split_spec
from tests.conftest import ROOT


def random_signals(seed: int, length: int = 2201) -> tuple[dict[str, np.ndarray], np.ndarray]:
    rng = np.random.default_rng(seed)
    times = np.arange(length) / 100.0
    walk = np.cumsum(rng.normal(0, 0.004, size=(3, length)), axis=1)
    centre = np.array([[0.45], [0.0], [0.40]])
    return dict(zip("xyz", centre + walk)), times


def test_parts_are_the_top_level_conjuncts_as_written():
    parts = split_spec(load_spec(ROOT / "specs" / "phi1.stl"), "new")
    assert parts.names == ("F L1", "G[12, 17] L2", "F L3", "F[8, 12] L4")
    assert split_spec(load_spec(ROOT / "specs" / "phi3_strict.stl")).names == ("F[0, 20] OBJECT", "G (HOLDER -> force < 2)")


def test_a_spec_that_is_not_a_conjunction_is_one_part():
    parts = split_spec(parse("F (x > 1 | y < 0)"), "new")
    assert parts.names == ("F (x > 1 | y < 0)",)
    signals, times = random_signals(0, 50)
    assert parts.compose(parts(signals, times)) == compile_spec(parse("F (x > 1 | y < 0)"), "new")(signals, times)


def test_defined_names_are_followed_to_the_conjunction_and_repeats_get_their_own_key():
    parts = split_spec(parse("A := x > 0 & F y > 1\nspec := A"))
    assert parts.names == ("x > 0", "F y > 1")
    assert split_spec(parse("x > 0 & x > 0")).names == ("x > 0", "x > 0 #2")


@pytest.mark.parametrize("spec", ["phi1", "phi2", "phi3_strict", "example"])
@pytest.mark.parametrize("semantics,nu", [("classic", 1.0), ("new", 1.0), ("new", 5.0)])
def test_composing_the_parts_gives_the_spec_robustness_exactly(spec, semantics, nu):
    parsed = load_spec(ROOT / "specs" / f"{spec}.stl")
    whole = compile_spec(parsed, semantics, nu)
    parts = split_spec(parsed, semantics, nu)
    for seed in range(5):
        signals, times = random_signals(seed)
        signals.update(force=np.abs(signals["x"] - 0.45) * 100, s=signals["x"] - 0.05)
        assert parts.compose(parts(signals, times)) == whole(signals, times)


def test_a_batch_gives_one_row_of_parts_per_trace():
    parts = split_spec(load_spec(ROOT / "specs" / "phi1.stl"), "new")
    traces = [random_signals(seed) for seed in range(3)]
    batch = {name: np.stack([signals[name] for signals, _ in traces]) for name in "xyz"}
    values = parts(batch, traces[0][1])
    assert values.shape == (3, 4)
    for row, (signals, times) in zip(values, traces):
        np.testing.assert_array_equal(row, parts(signals, times))


def test_the_semantics_are_named_once_and_new_is_every_default():
    import inspect
    from typing import get_args

    from stl_lfd.choices import DEFAULT_SEMANTICS, SEMANTICS
    from stl_lfd.optim.default_task import DEFAULTS
    from stl_lfd.stl import Spec, compile_spec
    from stl_lfd.stl.evaluate import evaluate_file
    from stl_lfd.stl.kernels import KERNELS
    from stl_lfd.stl.semantics import SemanticsName

    assert set(get_args(SemanticsName)) == set(SEMANTICS) == set(KERNELS) and DEFAULT_SEMANTICS == "new"
    defaults = [inspect.signature(function).parameters["semantics"].default for function in (compile_spec, split_spec, evaluate_file, Spec.robustness)]
    assert defaults == [DEFAULT_SEMANTICS] * 4 and DEFAULTS["semantics"] == DEFAULT_SEMANTICS
