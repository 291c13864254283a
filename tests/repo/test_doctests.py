"""Every ``>>>`` example in the package runs and prints what its docstring says.

The modules are found by their source text, so an example added anywhere under
``pipeline/spindlebench`` is run without being listed here; only those modules are imported.
"""

from __future__ import annotations

import doctest
import importlib

import pytest
from conftest import REPO

PACKAGE = REPO / "pipeline" / "spindlebench"


def modules_with_examples() -> list[str]:
    """Dotted names of the package's modules whose source holds a ``>>>`` prompt."""
    names = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if ">>> " in path.read_text(encoding="utf-8"):
            parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
            names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


MODULES = modules_with_examples()


def test_the_examples_the_issue_named_are_found():
    """registry, fingerprint, controller and mapping had examples that never ran (issue 19)."""
    for name in ("selection.registry", "studies.fingerprint.statistics",
                 "studies.compensation.controller", "calibration.mapping"):
        assert f"spindlebench.{name}" in MODULES, MODULES


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    failed, attempted = doctest.testmod(
        module, optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS, verbose=False)
    assert attempted > 0, f"{name}: '>>> ' in its source but no example doctest can run"
    assert failed == 0, f"{name}: {failed} of {attempted} examples failed (printed above)"
