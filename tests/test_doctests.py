"""Every docstring example in the package runs and prints what it says.

The examples are documentation (numpydoc ``Examples``); this keeps them true. Each
module of ``src/nirglucose`` is one case, run with the standard library's doctest.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import nirglucose

MODULES = sorted(
    m.name
    for m in pkgutil.walk_packages(nirglucose.__path__, prefix="nirglucose.")
    if not m.name.endswith(".__main__")  # importing it runs the command line
)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testmod(module, optionflags=flags, verbose=False, report=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples fail in {name}"
