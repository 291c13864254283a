"""A sweep with several ``[study] targets`` (issue 21 item 4): each target's sweep in its own
folder, the axial drift's rows those of the drift alone, the other targets measured as the
recording measures them, and the joint selections' per-target rows those of each target."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import REPO

TARGETS = ["drift_um", "drift_y_um", "tilt_a_urad"]
KEYS = ["replica", "noise", "fault", "train_experiment", "test_experiment", "method", "k"]


def _study(folder, targets: list[str] | None):
    """tiny_sweep cut to one replica, two experiments, no fault and k = 2."""
    text = (REPO / "scenarios/studies/tiny_sweep.toml").read_text()
    text = text.replace("replicas = 2", "replicas = 1").replace('months = ["Jan", "Jul"]',
                                                                'months = ["Jan"]')
    text = text.replace('faults = ["none", "T1-stuck"]', 'faults = ["none"]')
    text = text[:text.index("[faults.T1-stuck]")] + text[text.index("[training]"):]
    text = text.replace("clusters = [2, 3]", "clusters = [2]")
    if targets is not None:
        text = text.replace('climate = "chongqing"',
                            f'climate = "chongqing"\ntargets = {targets}', 1)
    path = folder / ("multi.toml" if targets else "single.toml")
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    from spindlebench.studies.sweep.sweep_run import run_sweep

    folder = tmp_path_factory.mktemp("sweeps")
    single = run_sweep(_study(folder, None), folder / "single", workers=0, progress=False)
    multi = run_sweep(_study(folder, TARGETS), folder / "multi", workers=0, progress=False)
    return folder, single, multi


@pytest.mark.slow
def test_the_drift_rows_of_a_multi_target_sweep_are_the_single_target_sweeps(sweeps):
    folder, single, multi = sweeps
    assert multi.out_dir == folder / "multi" / "drift_um"
    for target in TARGETS:
        assert (folder / "multi" / target / "results.csv").is_file()
    alone = (folder / "single" / "results.csv").read_bytes()
    assert (folder / "multi" / "drift_um" / "results.csv").read_bytes() == alone
    pd.testing.assert_frame_equal(single.results, multi.results)
    tilt = pd.read_csv(folder / "multi" / "tilt_a_urad" / "results.csv")
    # the tilt is its own target: another error, scored in µrad
    assert not np.allclose(tilt["rmse_um"], single.results["rmse_um"])


@pytest.mark.slow
def test_another_target_is_measured_as_the_recording_measures_it(sweeps):
    from spindlebench.formats.recording import read_recording
    from spindlebench.studies.family.family_file import load_study
    from spindlebench.studies.running.jobs import measured_frame
    from spindlebench.studies.running.simulations import recording_path
    from spindlebench.studies.sweep.sweep_run import Sweep

    folder, _, _ = sweeps
    study = load_study(folder / "multi.toml")
    sweep = Sweep(study, folder / "multi", "tilt_a_urad")
    condition = sweep.conditions[0]  # the study's first noise, healthy: the recording's own
    job = sweep.evaluation_task(1, condition, sweep.trains).args[0]
    for experiment in sweep.family:
        frame = read_recording(sweep.store.path(recording_path(1, experiment)))
        measured = measured_frame(job, experiment)
        np.testing.assert_allclose(measured["drift_um"], frame["tilt_a_urad"], atol=1e-6)
        truth = frame["true_tilt_a_urad"].to_numpy()
        np.testing.assert_allclose(measured["true_drift_rise_um"], truth - truth[0])


@pytest.mark.slow
def test_joint_per_target_rows_are_each_targets_sweep_and_every_joint_is_scored(sweeps):
    folder, _, _ = sweeps
    joint = pd.read_csv(folder / "multi" / "joint.csv", keep_default_na=False,
                        na_values=[""])
    assert set(joint["selection"]) == {"per-target", "union", "mtlasso", "pls-vip"}
    assert joint["error"].isna().all()
    for target in TARGETS:
        own = pd.read_csv(folder / "multi" / target / "results.csv")
        own = own[own["data"] == "measured"]
        rows = joint[(joint["selection"] == "per-target") & (joint["target"] == target)]
        both = rows.merge(own, on=KEYS)
        assert len(both) == len(rows) == len(own[own["method"].isin(set(rows["method"]))])
        np.testing.assert_array_equal(both["rmse"], both["rmse_um"])
    lasso = joint[joint["selection"] == "mtlasso"]
    assert (lasso["n_sensors"] <= 2 * lasso["k"]).all()  # k candidates (a difference: two)
    readme = (folder / "multi" / "README.md").read_text()
    assert "| six_diff | 2 | union |" in readme and "tilt_a_urad" in readme
