"""docs/contracts.md holds: its homes exist, names are spelled only in their home, the
package's ``>>>`` examples run, and its recipes work as written (each demonstrated here).

The string checks read the source with ``ast`` (docstrings and f-string pieces left out), so
a comment or a docstring may name a column; code that spells one must import it.
"""

from __future__ import annotations

import ast
import doctest
import importlib
import re
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import REPO

PACKAGE = REPO / "pipeline" / "spindlebench"
CONTRACTS = REPO / "docs" / "contracts.md"

# --------------------------------------------------------------------------- the homes


def _backticked(text: str) -> list[str]:
    """The backticked names of ``text``, without those it says a thing *was* called."""
    return [m.group(1) for m in re.finditer(r"`([^`\s]+)`", text)
            if not text[:m.start()].endswith("was ")]


def _module_attribute(token: str) -> tuple[Path, list[str]] | None:
    """``selection/registry.make_selector`` -> (the file, ['make_selector'])."""
    match = re.fullmatch(r"([a-z_]+(?:/[a-z_]+)+)((?:\.[A-Za-z_][A-Za-z0-9_]*)+)", token)
    if not match or match.group(2) == ".py":
        return None
    return PACKAGE / f"{match.group(1)}.py", match.group(2).lstrip(".").split(".")


def test_every_home_the_contracts_name_exists():
    """Every ``path/module.py`` and every ``spindlebench.x.NAME`` docs/contracts.md names is
    a file of the package (or the repository) and an importable object."""
    text = CONTRACTS.read_text(encoding="utf-8")
    missing = []
    for token in _backticked(text):
        token = token.rstrip(".,;:")
        if re.search(r"\.(py|md|c|h|toml|csv|json|png|mo|fmu|txt)$", token) and "/" in token \
                and "*" not in token and "NAME" not in token and "<" not in token:
            if not any((base / token).is_file()
                       for base in (PACKAGE, PACKAGE.parent, REPO, REPO / "tests")):
                missing.append(token)
        elif (found := _module_attribute(token)) is not None:
            path, names = found
            if not path.is_file():
                missing.append(token)
                continue
            module = importlib.import_module(
                ".".join(("spindlebench", *path.relative_to(PACKAGE).with_suffix("").parts)))
            if not hasattr(module, names[0]):
                missing.append(token)
        elif re.fullmatch(r"spindlebench(\.[A-Za-z_][A-Za-z0-9_]*)+", token):
            parts = token.split(".")
            for cut in range(len(parts), 0, -1):
                try:
                    obj = importlib.import_module(".".join(parts[:cut]))
                except ImportError:
                    continue
                try:
                    for name in parts[cut:]:
                        obj = getattr(obj, name)
                except AttributeError:
                    missing.append(token)
                break
            else:
                missing.append(token)
    assert not missing, f"docs/contracts.md names homes that do not exist: {missing}"


def test_the_home_check_could_fail(tmp_path):
    assert not (PACKAGE / "core" / "no_such_home.py").is_file()
    with pytest.raises(ImportError):
        importlib.import_module("spindlebench.core.no_such_home")


# --------------------------------------------------------------------------- one spelling


def _literals(path: Path) -> list[tuple[int, str]]:
    """The string constants of ``path``'s code (no docstrings, no f-string pieces)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) \
                and node.body and isinstance(node.body[0], ast.Expr) \
                and isinstance(node.body[0].value, ast.Constant):
            skip.add(id(node.body[0].value))
        if isinstance(node, ast.JoinedStr):
            skip.update(id(part) for part in ast.walk(node))
    return [(node.lineno, node.value) for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and id(node) not in skip]


def _modules() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def _relative(path: Path) -> str:
    return path.relative_to(PACKAGE).as_posix()


#: The recording's column names and rules: their one home is ``formats/recording.py``.
COLUMN_HOME = "formats/recording.py"


def _column_problem(value: str) -> str | None:
    from spindlebench.formats.recording import (
        DRIFT_COLUMN,
        DRIVER_COLUMNS,
        NODE_PREFIX,
        TIME_COLUMN,
        TRUE_PREFIX,
    )

    if value in (TIME_COLUMN, DRIFT_COLUMN, *DRIVER_COLUMNS):
        return "a recording column"
    if value == TRUE_PREFIX or re.fullmatch(r"true_(T\d+_C|drift_um|node_\w+_C|Q_\w+_W)", value):
        return "the true_ rule"
    if value == NODE_PREFIX or re.fullmatch(r"node_\w+_C", value):
        return "the node_ rule"
    return None


def test_no_column_name_is_spelled_outside_its_home():
    offenders = [f"{_relative(path)}:{line}: {value!r} ({problem})"
                 for path in _modules() if _relative(path) != COLUMN_HOME
                 for line, value in _literals(path)
                 if (problem := _column_problem(value))]
    assert not offenders, "spelled outside formats/recording.py:\n" + "\n".join(offenders)


def test_the_column_check_could_fail(tmp_path):
    assert _column_problem("spindle_speed_rpm") and _column_problem("true_T3_C")
    assert _column_problem("node_housing_2_C") and not _column_problem("node_positions")
    source = 'x = frame["ambient_C"]\n'
    probe = tmp_path / "probe.py"
    probe.write_text(source)
    assert [v for _, v in _literals(probe) if _column_problem(v)] == ["ambient_C"]
    assert _module_attribute("selection/registry.make_selector") == (
        PACKAGE / "selection" / "registry.py", ["make_selector"])


#: Where a selection method's name may appear as a string although its home is
#: ``selection/`` (the registry and the implementations): each with its reason.
METHOD_NAME_EXCEPTIONS = {
    # the paper's method is the package's default everywhere, named on the ground floor
    ("core/names.py", "closure"),
    # the sweep's baselines are named after the method/regressor they run (their one home)
    ("studies/family/family_file.py", "top-k-correlated"),
    # the placement study's search labels: its forward search is still labelled "greedy"
    # (renaming the label changes place's outputs; contracts.md, phase 2 notes)
    *(("studies/placement/" + name, "greedy") for name in (
        "placement_file.py", "placement_report.py", "placement_run.py", "placements.py",
        "schematic.py")),
    # the placement study's own exhaustive search (judged across its seasons, with its
    # exhaustive_limit) keeps its label; the selection method of that name is the same
    # search on one training run (selection/exhaustive.py serves both)
    *(("studies/placement/" + name, "exhaustive") for name in (
        "placement_file.py", "placement_report.py", "placements.py", "schematic.py")),
    # the sweep report's "stability" table (the spread of scores), not the method
    ("studies/sweep/summary.py", "stability"),
    ("studies/sweep/sweep_report.py", "stability"),
    # ISO 230-3's thermal stability (the report's key), not the method
    ("commands/iso230_3.py", "stability"),
    # the no-selection method's name is a ground-floor name (the registry's entry uses it)
    ("core/names.py", "all-candidates"),
    # the benchmark's "stability" score column (spread over folds), not the method; pandas'
    # rank(method="average"), not the linkage
    ("studies/benchmark/scoring.py", "stability"),
    ("studies/benchmark/benchmark_report.py", "stability"),
    ("studies/benchmark/benchmark_report.py", "average"),
    # the twin page's evaluate protocol: the --method arguments it passes to the command
    # line, as a user types them (EVALUATE_ROWS)
    *(("identification/validation.py", name)
      for name in ("all-candidates", "top-k-correlated", "closure")),
}


def test_no_method_name_is_spelled_outside_the_selection_package():
    from spindlebench.selection.method_registry import METHOD_REGISTRY

    offenders = [f"{_relative(path)}:{line}: {value!r}"
                 for path in _modules() if not _relative(path).startswith("selection/")
                 for line, value in _literals(path)
                 if value in METHOD_REGISTRY
                 and (_relative(path), value) not in METHOD_NAME_EXCEPTIONS]
    assert not offenders, "method names spelled outside selection/:\n" + "\n".join(offenders)


# --------------------------------------------------------------------------- the examples

#: Every module whose docstrings hold ``>>>`` examples: run as doctests.
DOCTEST_MODULES = sorted(
    ".".join(("spindlebench", *path.relative_to(PACKAGE).with_suffix("").parts))
    .removesuffix(".__init__")
    for path in _modules() if ">>>" in path.read_text(encoding="utf-8"))


def test_the_doctest_list_covers_the_named_modules():
    for module in ("spindlebench", "spindlebench.selection.registry",
                   "spindlebench.selection.method_registry",
                   "spindlebench.studies.fingerprint.statistics",
                   "spindlebench.studies.compensation.controller",
                   "spindlebench.calibration.mapping", "spindlebench.core.limits"):
        assert module in DOCTEST_MODULES


@pytest.mark.parametrize("module", DOCTEST_MODULES)
def test_the_examples_of_the_package_run(module):
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0, f"{module}: {result.failed} of {result.attempted} examples fail"


# --------------------------------------------------------------------------- the recipes


class FirstK:
    """A made-up selector: the first ``k`` candidates (what a newcomer's entry builds)."""

    def __init__(self, k: int = 2):
        self.k = k

    def fit(self, X, y):
        self.selected_ = np.arange(self.k)
        return self


def test_recipe_add_a_selection_method(tmp_path, capsys):
    """One registry entry: ``spindlebench methods`` lists it, ``evaluate`` runs it and a
    study file may name it, with nothing else changed."""
    from spindlebench import evaluate, parse_method
    from spindlebench.commands import main as cli
    from spindlebench.selection.method_registry import Method, registered
    from spindlebench.studies.family.family_file import load_study

    entry = Method("first-k", "the first k candidates (a test's method)",
                   factory=lambda k, **_: FirstK(k))
    t = np.arange(0.0, 3600.0, 120.0)
    frame = pd.DataFrame({"time_s": t, "T1": 20 + t / 3600, "T2": 20 + np.sqrt(t / 3600),
                          "T3": 20 + np.sin(t / 600), "drift_um": 4 * t / 3600})
    study_text = (REPO / "scenarios" / "studies" / "tiny_sweep.toml").read_text()
    study = tmp_path / "study.toml"
    study.write_text(study_text + 'methods = ["closure", "first-k"]\n')
    with pytest.raises(Exception, match="unknown method 'first-k'"):
        parse_method("first-k")
    with registered(entry):
        assert cli.main(["methods"]) == 0
        assert "  first-k " in capsys.readouterr().out
        result = evaluate(frame, {"b": frame}, "drift_um", sensors=["T1", "T2", "T3"], k=2,
                          method="first-k")
        assert result.selected == ["T1", "T2"]
        assert load_study(study).methods.methods == ("closure", "first-k")
    with pytest.raises(Exception, match="first-k"):
        load_study(study)


def test_recipe_a_limit_is_the_fmus_declared_bound():
    """A physical limit of the inputs is one constant of ``core/limits.py``, equal to the
    bound the FMU declares for that input."""
    from fmpy import read_model_description
    from spindlebench.core import limits
    from spindlebench.core.paths import DEFAULT_FMU
    from spindlebench.formats.recording import FEED_X_COLUMN, FEED_Y_COLUMN, SPEED_COLUMN

    declared = {v.name: v for v in read_model_description(str(DEFAULT_FMU)).modelVariables
                if v.causality == "input"}
    assert float(declared[SPEED_COLUMN].max) == limits.MAX_RPM
    for feed in (FEED_X_COLUMN, FEED_Y_COLUMN):
        assert float(declared[feed].max) == limits.MAX_FEED_MM_PER_MIN


def test_recipe_a_scenario_above_the_declared_speed_is_refused_naming_the_key(tmp_path):
    from spindlebench import SpindlebenchError, load_scenario

    text = (REPO / "scenarios" / "paper" / "exp1.toml").read_text()
    path = tmp_path / "fast.toml"
    path.write_text(re.sub(r"(?m)^rpm = .*$", "rpm = 35000", text, count=1))
    bound = r"key 'speed.rpm'.*30000\] rev/min \(the FMU's declared range\), got 35000"
    with pytest.raises(SpindlebenchError, match=bound):
        load_scenario(path)


def test_recipe_add_a_machine_variant(tmp_path):
    """A machine variant is one TOML file; ``load_machine`` reads it by path (or by name
    under ``scenarios/machines/``)."""
    from spindlebench import load_machine

    variant = tmp_path / "stiff.toml"
    variant.write_text(textwrap.dedent("""\
        name = "stiff"
        description = "a test's variant"
        [parameters]
        T_ref = 293.15
        """))
    machine = load_machine(str(variant))
    assert machine.name == "stiff" and machine.parameters["T_ref"] == 293.15


def test_recipe_a_recording_column_is_read_through_its_name(tmp_path):
    """A column is a name of ``formats/recording.py``: the writer puts it in the CSV and
    readers find it by that name."""
    from spindlebench import read_recording, write_recording
    from spindlebench.formats.recording import SPEED_COLUMN, TIME_COLUMN

    frame = pd.DataFrame({TIME_COLUMN: [0.0, 60.0], SPEED_COLUMN: [0.0, 3000.0]})
    csv = write_recording(tmp_path / "r.csv", frame, {"source": "test"})
    assert read_recording(csv)[SPEED_COLUMN].tolist() == [0.0, 3000.0]


def test_importing_the_package_stays_cheap():
    """``import spindlebench`` loads no NumPy, pandas or scikit-learn (PEP 562 API)."""
    import subprocess
    import sys

    code = ("import sys, spindlebench; "
            "print(sorted(m for m in ('numpy', 'pandas', 'sklearn') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={"PYTHONPATH": str(PACKAGE.parent)})
    assert out.stdout.strip() == "[]"
    import spindlebench

    assert callable(spindlebench.rises) and "rises" in dir(spindlebench)
    with pytest.raises(AttributeError):
        spindlebench.no_such_name  # noqa: B018
