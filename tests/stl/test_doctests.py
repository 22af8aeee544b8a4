"""The examples in the STL modules' docstrings run and print what they show."""

import doctest

import pytest

from stl_lfd.stl import components, robustness, spec


@pytest.mark.parametrize("module", [components, robustness, spec], ids=lambda module: module.__name__)
def test_docstring_examples(module):
    failures, tried = doctest.testmod(module)
    assert tried > 0 and failures == 0
