"""``spindlebench place`` end to end on the committed FMU (the tiny study: 40-minute runs),
and one-line errors for bad placement study files."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.commands.main import main
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.studies.placement.candidates import candidate_set
from spindlebench.studies.placement.placement_file import (
    fmu_nodes,
    is_rotating,
    load_placement_study,
)
from spindlebench.studies.placement.placement_run import PlacementStudyRun

TINY = REPO / "scenarios" / "studies" / "tiny_placement.toml"
SHIPPED = REPO / "scenarios" / "studies" / "placement.toml"


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("place") / "tiny"
    status = main(["place", str(TINY), "-o", str(out), "--workers", "0", "--no-progress"])
    assert status == 0
    return out, pd.read_csv(out / "placements.csv", keep_default_na=False,
                            na_values=[""])


def test_shipped_studies_load():
    for path in (TINY, SHIPPED):
        study = load_placement_study(path)
        assert study.nodes == tuple(n for n in fmu_nodes(DEFAULT_FMU) if not is_rotating(n))
        assert study.test_replicas and study.design_replica not in study.test_replicas


def test_rotating_parts_are_no_candidates_unless_a_telemetry_study_asks(tmp_path, tiny_run):
    """``place`` recommended sensors on the spindle shaft and the tool, where no probe can be
    glued; the README now names the candidates and what was left out."""
    study = load_placement_study(TINY)
    rotating = [n for n in fmu_nodes(DEFAULT_FMU) if is_rotating(n)]
    assert {"tool", "spindle_shaft_1", "spindle_shaft_12", "z_screw"} <= set(rotating)
    assert not set(rotating) & set(study.nodes)
    assert study.rotating_excluded == tuple(rotating)
    telemetry = tmp_path / "telemetry.toml"
    telemetry.write_text(TINY.read_text(encoding="utf-8").replace(
        "[placement]", "[placement]\nrotating_nodes = true"), encoding="utf-8")
    assert load_placement_study(telemetry).nodes == tuple(fmu_nodes(DEFAULT_FMU))
    out, table = tiny_run
    readme = (out / "README.md").read_text(encoding="utf-8")
    assert f"- Candidate nodes ({len(study.nodes)}): front_bearing," in readme
    assert "Rotating parts left out" in readme and "spindle_shaft_12" in readme
    chosen = ";".join(table["variables"].fillna("")).replace("-", ";").split(";")
    assert not [n for n in chosen if n and is_rotating(n)]


def test_place_writes_every_output(tiny_run):
    out, table = tiny_run
    for name in ("README.md", "placements.csv", "scores.csv", "comparison.png",
                 "provenance.json", "schematic/nodes.png", "schematic/placement_m2.png",
                 "schematic/placement_m3.png"):
        assert (out / name).is_file(), name
    assert not list(out.rglob("*.part"))  # atomic writes leave no temporary files
    # 5 methods (the three searches and two of 'spindlebench methods') x 2 candidate sets x
    # budgets 2, 3
    assert len(table) == 20
    assert set(table["label"]) == {"fuzzy", "greedy", "exhaustive", "fuzzy+diff",
                                   "greedy+diff", "exhaustive+diff", "kmeans+grey",
                                   "kmeans+grey+diff", "lasso", "lasso+diff"}
    skipped = table[table["variables"].isna()]
    assert set(skipped["label"]) == {"exhaustive+diff"}
    assert skipped["note"].str.contains("exhaustive_limit").all()
    found = table[table["variables"].notna()]
    assert (found["variables"].str.split(";").str.len() == found["m"]).all()
    assert found[["design_rmse_um", "test_mean_rmse_um", "test_winter_rmse_um",
                  "test_summer_rmse_um"]].notna().all().all()
    provenance = json.loads((out / "provenance.json").read_text())
    assert provenance["fmu"]["sha256"] and provenance["settings"]["budgets"] == [2, 3]
    readme = (out / "README.md").read_text()
    assert "## Findings" in readme and "exhaustive+diff m = 2: skipped" in readme
    assert "![m2](schematic/placement_m2.png)" in readme
    assert f"Made by `spindlebench place {TINY}`" in readme  # the path as given
    assert "runs of 40 min from a cold start" in readme


def test_searches_rank_by_the_reported_design_score(tiny_run):
    """The search objective is the design RMSE the table reports (refit independently), and
    the exhaustive optimum is never beaten on it by greedy or fuzzy."""
    _, table = tiny_run
    searched = table[table["method"].isin(["greedy", "exhaustive"]) & table["variables"].notna()]
    np.testing.assert_allclose(searched["search_score_um"], searched["design_rmse_um"],
                               rtol=1e-6)
    nodes_only = table[~table["differences"].astype(bool)].set_index(["method", "m"])
    for m in (2, 3):
        best = nodes_only.loc[("exhaustive", m), "design_rmse_um"]
        assert best <= nodes_only.loc[("greedy", m), "design_rmse_um"] * (1 + 1e-6)
        assert best <= nodes_only.loc[("fuzzy", m), "design_rmse_um"] * (1 + 1e-6)
    greedy = nodes_only.loc["greedy"]["variables"]
    assert greedy.loc[3].startswith(greedy.loc[2])  # one nested forward path


def nodes_frame(study, run) -> pd.DataFrame:
    """A run's node rises as the frame ``CandidateSet.matrix`` reads (its rises are the same
    numbers: the first row is zero)."""
    return pd.DataFrame(run.node_rises, columns=list(study.nodes))


def test_test_scores_are_a_refit_on_the_test_replica(tiny_run):
    """Recompute one placement's test RMSE with numpy lstsq from the stored recordings."""
    out, table = tiny_run
    study = load_placement_study(TINY)
    row = table[(table["label"] == "greedy+diff") & (table["m"] == 2)].iloc[0]
    candidates = candidate_set(study, True)
    columns = [candidates.names.index(v) for v in row["variables"].split(";")]
    train_runs, held_out = PlacementStudyRun(study, out).runs(2)
    X = candidates.matrix(nodes_frame(study, train_runs[0]), columns)
    coef, *_ = np.linalg.lstsq(np.column_stack([np.ones(len(X)), X]), train_runs[0].drift_um,
                               rcond=None)
    errors = []
    for run in held_out:
        predicted = coef[0] + candidates.matrix(nodes_frame(study, run), columns) @ coef[1:]
        errors.append(np.sqrt(np.mean((run.drift_um - predicted) ** 2)))
    assert row["test_mean_rmse_um"] == pytest.approx(np.mean(errors), rel=1e-6)
    scores = pd.read_csv(out / "scores.csv")
    mine = scores[(scores["label"] == "greedy+diff") & (scores["m"] == 2)
                  & (scores["role"] == "test")]
    assert len(mine) == len(held_out) == 3


def test_a_rerun_resumes_and_reproduces_the_placements(tiny_run, capsys):
    out, table = tiny_run
    assert main(["place", str(TINY), "-o", str(out), "--workers", "0", "--no-progress"]) == 0
    assert "resumed: 0 simulation(s)" in capsys.readouterr().out
    again = pd.read_csv(out / "placements.csv", keep_default_na=False, na_values=[""])
    columns = ["label", "m", "variables", "design_rmse_um", "test_mean_rmse_um"]
    pd.testing.assert_frame_equal(table[columns], again[columns])


def test_resuming_ignores_comments_but_not_changed_values(tiny_run, tmp_path, capsys):
    import shutil

    out = tmp_path / "copy"
    shutil.copytree(tiny_run[0], out)
    commented = tmp_path / "commented.toml"
    commented.write_text("# my notes\n" + TINY.read_text(encoding="utf-8"), encoding="utf-8")
    assert main(["place", str(commented), "-o", str(out), "--workers", "0",
                 "--no-progress"]) == 0
    assert "resumed: 0 simulation(s)" in capsys.readouterr().out
    changed = tmp_path / "changed.toml"
    changed.write_text(study_text(**{"budgets = [2, 3]": "budgets = [2, 4]"}), encoding="utf-8")
    assert main(["place", str(changed), "-o", str(out), "--workers", "0",
                 "--no-progress"]) == 2
    assert capsys.readouterr().err.strip() == (
        f"error: {out}: holds results of a different study (study file key "
        "'placement.budgets': [2, 3] → [2, 4]); use a new output folder to run this study")


def study_text(**replace: str) -> str:
    text = TINY.read_text(encoding="utf-8")
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    return text


@pytest.mark.parametrize(
    ("replace", "expected"),
    [
        ({"budgets = [2, 3]": "budgets = [0, 3]"},
         "key 'placement.budgets': item 1 (0): must be in [1, 10]"),
        ({"budgets = [2, 3]": "budgets = [2, 99]"}, "key 'placement.budgets': item 2 (99)"),
        ({'methods = ["fuzzy", "greedy", "exhaustive", "kmeans+grey", "lasso"]':
          'methods = ["fuzzy", "random"]'},
         "key 'placement.methods': item 2 ('random'): must be one of fuzzy, greedy, "
         "exhaustive"),
        ({"with_differences = [false, true]": 'with_differences = "yes"'},
         "key 'placement.with_differences': must be true, false or a list of them"),
        ({"exhaustive_limit = 200000": "exhaustive_limit = -1"},
         "key 'placement.exhaustive_limit': must be in [0, 1e+09]"),
        ({"exhaustive_limit = 200000": "exhaustive_limt = 200000"},
         "key 'placement.exhaustive_limt': unknown key (did you mean 'exhaustive_limit'?)"),
        ({"exhaustive_limit = 200000": 'exhaustive_limit = 1\nexclude_nodes = ["hub"]'},
         "key 'placement.exclude_nodes': no node named 'hub' in the FMU"),
        ({"[placement]": "[methods]\nclusters = [2]\n\n[placement]"},
         "key 'methods': a placement study sets its methods in [placement]"),
        ({'noise = ["lab"]': 'noise = ["lab", "shop"]\n[noise.shop]\nnoise_C = 0.3'},
         "key 'axes.noise': a placement study measures with one noise level, got 2"),
        ({"[placement]": "[placment]"}, "key 'placment': unknown key"),
        ({"replicas = 2": "replicas = 0"}, "key 'study.replicas': must be in [1, 10000]"),
        # checked at load time: before, each failed once per simulation, on one huge line
        ({"[placement]": "[parameters]\nfoo = 1.0\n\n[placement]"},
         "key 'parameters.foo': the FMU SpindleBench.fmu has no parameter 'foo'"),
        ({"[placement]": "[parameters]\nfb_housing_G = nan\n\n[placement]"},
         "key 'parameters.fb_housing_G': must be a finite number, got nan"),
        ({"step_s = 120.0": "step_s = 1e-300"}, "key 'experiment.step_s': must be >= 0.001 s"),
    ],
)
def test_bad_study_gets_one_line_naming_file_and_key(tmp_path, capsys, replace, expected):
    path = tmp_path / "bad.toml"
    path.write_text(study_text(**replace), encoding="utf-8")
    with pytest.raises(SpindlebenchError) as info:
        load_placement_study(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(path)) and expected in message
    out = tmp_path / "out"
    assert main(["place", str(path), "-o", str(out), "--no-progress"]) == 2
    assert capsys.readouterr().err.strip() == f"error: {message}"
    assert not out.exists()  # nothing written for a bad study


def test_missing_placement_table_and_file(tmp_path):
    path = tmp_path / "sweep_only.toml"
    text = study_text()
    path.write_text(text[: text.index("[placement]")], encoding="utf-8")
    with pytest.raises(SpindlebenchError, match=r"key 'placement': missing table"):
        load_placement_study(path)
    with pytest.raises(SpindlebenchError, match="file not found"):
        load_placement_study(tmp_path / "nope.toml")


def test_when_every_run_fails_the_error_is_one_short_line(tmp_path, capsys, monkeypatch):
    import dataclasses

    from spindlebench.studies.running import simulations

    def broken(*args):
        return dataclasses.replace(real(*args), parameters={"no_such_parameter": 1.0})

    real = simulations.scenario_for
    monkeypatch.setattr(simulations, "scenario_for", broken)
    out = tmp_path / "out"
    assert main(["place", str(TINY), "-o", str(out), "--workers", "0", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and len(err[0]) < 600, err
    assert "8 of 8 simulations failed; first, r1 Jan-2000rpm-constant-off: " in err[0]
    assert err[0].count("no_such_parameter") == 2  # in the key and in the message, once
    assert err[0].endswith(f"see {out}/runs/r001/Jan-2000rpm-constant-off.error.json)")


def test_the_study_name_is_the_one_the_file_gives(tmp_path):
    # The loop over the extra tables once rebound 'name', so every placement study was
    # called 'placement' (and wrote to results/placement by default).
    assert load_placement_study(TINY).name == "tiny-placement"
