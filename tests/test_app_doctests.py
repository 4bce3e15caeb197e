"""The app's docstring examples run, as the core's do (pytest collects those from ur10core/ itself)."""

import doctest
import importlib
import pkgutil

import pytest
import ur10teach

MODULES = sorted(name for _, name, _ in pkgutil.walk_packages(ur10teach.__path__, "ur10teach.")
                 if not name.endswith("__main__"))


@pytest.mark.parametrize("name", MODULES)
def test_the_examples_in_the_docstrings_hold(name):
    module = importlib.import_module(name)
    failed, _ = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert failed == 0, f"{failed} docstring examples of {name} fail (run python -m doctest -v on it)"
