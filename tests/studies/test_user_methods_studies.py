"""A user's selector by import path in ``paper`` and ``place`` (issue 23): it runs exactly
like the same class registered as a built-in, and the study's provenance records its code's
package, version and source hash."""

from __future__ import annotations

import hashlib
import json

import pandas as pd
import pytest
from conftest import REPO
from selection_data import experiment_files
from spindlebench.commands.main import main
from spindlebench.selection.method_registry import Method, registered

USER_METHOD_DIR = REPO / "docs" / "examples" / "user-method"
USER = "my_selector:DecorrelatedSelector"
TINY_PLACEMENT = REPO / "scenarios" / "studies" / "tiny_placement.toml"


@pytest.fixture
def as_built_in(monkeypatch):
    """The example's class on the path, and registered as the built-in ``decorrelated``."""
    monkeypatch.syspath_prepend(str(USER_METHOD_DIR))
    from my_selector import DecorrelatedSelector

    entry = Method("decorrelated", "the example user method, registered for a test",
                   factory=lambda k, **_: DecorrelatedSelector(k))
    with registered(entry):
        yield


def _code_record(provenance: dict) -> dict:
    (code,) = provenance["methods"][USER]["code"]
    source = USER_METHOD_DIR / "my_selector.py"
    assert code["source_sha256"] == hashlib.sha256(source.read_bytes()).hexdigest()
    assert code["package"] == "my_selector" and "version" in code
    return code


@pytest.mark.slow
def test_user_method_in_paper_runs_like_a_built_in(tmp_path, as_built_in):
    files = experiment_files(tmp_path, count=3)
    config = tmp_path / "study.toml"
    six = '["T1", "T6", "T8", "T10", "T13", "T16"]'
    config.write_text(f'tests = ["exp2", "exp3"]\nclusters = [2, 3]\nsensors_all = {six}\n'
                      f'six = {six}\nmethods = ["closure", "{USER}", "decorrelated"]\n')
    out = tmp_path / "out"
    assert main(["paper", "--recordings", str(files[0].parent), "--config", str(config),
                 "--out", str(out)]) == 0
    table = pd.read_csv(out / "methods_rmse.csv")
    mine = table[table["method"] == USER].drop(columns="method").reset_index(drop=True)
    built_in = table[table["method"] == "decorrelated"].drop(columns="method") \
        .reset_index(drop=True)
    assert len(mine) == 2 * 3  # k = 2, 3 on every group
    pd.testing.assert_frame_equal(mine, built_in)
    assert f"| {USER} |" in (out / "README.md").read_text() or USER in \
        (out / "README.md").read_text()
    provenance = json.loads((out / "provenance.json").read_text())
    assert provenance["methods"]["decorrelated"] == {
        "method": "decorrelated", "within": "psi", "regressor": "ols"}
    _code_record(provenance)


@pytest.mark.slow
def test_user_method_in_place_runs_like_a_built_in(tmp_path, as_built_in):
    study = tmp_path / "place.toml"
    text = TINY_PLACEMENT.read_text().replace(
        'methods = ["fuzzy", "greedy", "exhaustive", "kmeans+grey", "lasso"]',
        f'methods = ["fuzzy", "{USER}", "decorrelated"]').replace(
        "with_differences = [false, true]", "with_differences = [false]").replace(
        "budgets = [2, 3]", "budgets = [3]")
    assert USER in text
    study.write_text(text)
    out = tmp_path / "out"
    assert main(["place", str(study), "-o", str(out), "--workers", "0", "--no-progress"]) == 0
    table = pd.read_csv(out / "placements.csv", keep_default_na=False, na_values=[""])
    columns = [c for c in table.columns if c not in ("label", "method")]
    mine = table[table["label"] == USER][columns].reset_index(drop=True)
    built_in = table[table["label"] == "decorrelated"][columns].reset_index(drop=True)
    assert len(mine) == 1 and mine["variables"].str.count(";").tolist() == [2]  # m = 3
    pd.testing.assert_frame_equal(mine, built_in)
    provenance = json.loads((out / "provenance.json").read_text())
    assert "fuzzy" not in provenance["methods"]  # the study's own search, not a label
    _code_record(provenance)
