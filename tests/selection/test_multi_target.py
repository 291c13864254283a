"""Several targets at once (issue 21 item 4): per-target results equal single-target ones,
a joint selection is one sensor set for every target, one target keeps its old output."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from selection_data import synthetic_experiment
from spindlebench.core.errors import SpindlebenchError
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.method_registry import joint_names, method_names
from spindlebench.selection.multi_output import MultiTaskLassoSelector, PLSVIPSelector

TARGETS = ["drift_um", "drift_y_um", "tilt_a_urad"]
SIX = ["T1", "T6", "T8", "T10", "T13", "T16"]


def five_probe_experiment(seed: int, speed: float) -> pd.DataFrame:
    """``synthetic_experiment`` with a Y drift on the slow column sensor T6 and a tilt on
    T6 and T13: three components, two of which share a sensor."""
    frame = synthetic_experiment(seed, speed=speed)
    rng = np.random.default_rng(100 + seed)
    y = 3.0 * (frame["T6"] - frame["T10"])
    tilt = 5.0 * (frame["T6"] - frame["T10"]) - 4.0 * (frame["T13"] - frame["T10"])
    frame["drift_y_um"] = y - y.iloc[0] + rng.normal(0, 0.2, len(frame))
    frame["tilt_a_urad"] = tilt - tilt.iloc[0] + rng.normal(0, 0.5, len(frame))
    return frame


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("targets")
    paths = []
    for seed in range(3):
        path = folder / f"exp{seed + 1}.csv"
        five_probe_experiment(seed, 0.5 + 0.4 * seed).to_csv(path, index=False)
        paths.append(path)
    return paths


def test_multi_output_methods_are_registered_once_and_not_in_all():
    assert set(method_names(multi_output=True)) == {"mtlasso", "pls-vip"}
    assert joint_names()[0] == "union"
    assert not set(method_names(multi_output=True)) & set(method_names(multi_output=False))


@pytest.mark.parametrize("cls", [MultiTaskLassoSelector, PLSVIPSelector])
def test_joint_selector_finds_the_shared_support(cls):
    rng = np.random.default_rng(3)
    X = rng.normal(size=(200, 8))
    Y = np.c_[2 * X[:, 2] + X[:, 6], X[:, 6] - 0.5 * X[:, 2], 3 * X[:, 2]]
    Y = Y + 0.05 * rng.normal(size=Y.shape)
    selector = cls(2).fit(X, Y)
    assert sorted(selector.selected_.tolist()) == [2, 6]
    assert selector.get_support().sum() == 2
    assert len(cls(3).fit(X, Y[:, 0]).selected_) == 3  # one component works too
    with pytest.raises(SelectionError, match="constant"):
        cls(2).fit(X, np.c_[Y[:, 0], np.ones(200)])


def test_multi_target_evaluate_equals_single_evaluates_and_joint_is_one_set(files):
    from spindlebench.selection import evaluate
    from spindlebench.selection.evaluate import load_recordings
    from spindlebench.selection.multi_target import evaluate_targets

    train, *tests = files
    recordings = load_recordings(train, tests)
    result = evaluate_targets(*recordings, TARGETS, sensors=SIX, k=2, differences=True,
                              joint=joint_names())
    for target in TARGETS:
        single = evaluate(train, tests, target, sensors=SIX, k=2, differences=True)
        assert result.per_target[target].to_dict() == single.to_dict()
    assert list(result.joint) == list(joint_names())
    union = result.joint["union"]
    assert set(union.selected) == {c for t in TARGETS for c in result.per_target[t].selected}
    for name, joint in result.joint.items():
        for target in TARGETS:  # the same set fitted for every target
            assert joint.per_target[target].selected == joint.selected, (name, target)
        if name != "union":
            assert len(joint.selected) == 2
    # the joint LASSO's set is the selector's own on the training rises and all targets
    from spindlebench.selection.evaluate import CandidateSet

    frame = pd.read_csv(train)
    matrix = CandidateSet(tuple(SIX), True).matrix(frame)
    names = result.per_target["drift_um"].candidates
    direct = MultiTaskLassoSelector(2).fit(matrix, frame[TARGETS].to_numpy())
    assert result.joint["mtlasso"].selected == [names[i] for i in direct.selected_]
    rows = result.comparison_rows()
    assert [r["selection"] for r in rows] == ["per-target", *joint_names()]
    assert rows[1]["n_sensors"] == len(union.sensors)


def test_cli_several_targets_json_and_single_target_shape(files, tmp_path, capsys):
    from spindlebench.commands import main as cli
    from spindlebench.selection import evaluate

    train, *tests = files
    out = tmp_path / "multi.json"
    base = ["evaluate", "--train", str(train), "--test", *map(str, tests), "--clusters", "2",
            "--sensors", *SIX]
    assert cli.main([*base, "--target", *TARGETS, "--joint", "mtlasso", "--json",
                     str(out)]) == 0
    printed = capsys.readouterr().out
    assert "=== joint selection mtlasso" in printed and "per-target" in printed
    record = json.loads(out.read_text())
    assert record["targets"] == TARGETS and list(record["joint"]) == ["mtlasso"]
    for target in TARGETS:
        single = evaluate(train, tests, target, sensors=SIX, k=2)
        assert record["per_target"][target] == json.loads(json.dumps(single.to_dict()))
    one = tmp_path / "one.json"
    assert cli.main([*base, "--target", "drift_um", "--json", str(one)]) == 0
    record = json.loads(one.read_text())
    assert record["provenance"]["target"] == "drift_um" and "joint" not in record
    assert record["selected"] == evaluate(train, tests, "drift_um", sensors=SIX, k=2).selected
    capsys.readouterr()
    assert cli.main([*base, "--target", "drift_um", "--joint", "union"]) == 2
    assert "needs several --target" in capsys.readouterr().err
    assert cli.main([*base, "--target", "drift_um", "drift_um"]) == 2
    assert "given twice" in capsys.readouterr().err
    assert cli.main([*base, "--target", "drift_um", "nope_um"]) == 2
    assert "nope_um" in capsys.readouterr().err


def test_targets_of_refuses_an_unknown_joint_name():
    import argparse

    from spindlebench.commands.arguments import targets_of

    with pytest.raises(SpindlebenchError, match="not a joint selection"):
        targets_of(argparse.Namespace(target=["a", "b"], joint=["lasso"]))


def test_cli_fingerprint_reports_each_target(files, capsys):
    from spindlebench.commands import main as cli
    from spindlebench.studies.fingerprint.recordings import fingerprint_recording

    assert cli.main(["fingerprint", str(files[0]), str(files[1]), "--target", "drift_um",
                     "tilt_a_urad", "--sensors", *SIX]) == 0
    printed = capsys.readouterr().out
    assert f"{files[0]} [tilt_a_urad]" in printed and "median [drift_um]" in printed
    from spindlebench.formats.roles import ColumnRoles

    tilt = fingerprint_recording(files[0], "tilt_a_urad", ColumnRoles(sensors=tuple(SIX)))[0]
    line = next(row for row in printed.splitlines() if row.startswith(f"{files[0]} [tilt"))
    assert f"{tilt.stats['best_raw_psi']:.3f}" in line


@pytest.mark.slow
def test_cli_paper_several_targets_each_folder_as_alone_and_the_joint_table(tmp_path, capsys):
    from spindlebench.commands import main as cli
    from spindlebench.selection import evaluate

    folder = tmp_path / "recordings"
    folder.mkdir()
    for seed in range(3):
        five_probe_experiment(seed, 0.5 + 0.4 * seed).to_csv(folder / f"exp{seed + 1}.csv",
                                                             index=False)
    base = ["paper", "--recordings", str(folder), "--sensors-all", *SIX, "--six", *SIX,
            "--clusters", "2", "--train", "exp1", "--tests", "exp2", "exp3"]
    several, alone = tmp_path / "several", tmp_path / "alone"
    assert cli.main([*base, "--out", str(several), "--target", "drift_um", "drift_y_um",
                     "--joint", "union", "mtlasso"]) == 0
    assert cli.main([*base, "--out", str(alone), "--target", "drift_y_um"]) == 0
    capsys.readouterr()
    for name in sorted(p.name for p in alone.iterdir() if p.suffix == ".csv"):
        assert (several / "drift_y_um" / name).read_bytes() == (alone / name).read_bytes()
    record = json.loads((several / "joint.json").read_text())
    rows = {(r["group"], r["selection"]): r for r in record["rows"] if r["k"] == 2}
    tests = [folder / "exp2.csv", folder / "exp3.csv"]
    for target in ("drift_um", "drift_y_um"):
        own = evaluate(folder / "exp1.csv", tests, target, sensors=SIX, k=2)
        assert rows[("all_raw", "per-target")][target] == pytest.approx(own.mean_rmse_um)
    assert rows[("all_raw", "mtlasso")]["n_sensors"] <= 2
    assert "| all raw | 2 | union |" in (several / "README.md").read_text()
