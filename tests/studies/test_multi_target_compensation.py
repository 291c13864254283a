"""``compensate`` with several ``[study] targets`` (issue 21 item 4): one simulation, each
target compensated on its own into its folder, the axial drift's files those of the drift
alone, each target's residual its true rise minus its applied offset."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.commands import main as cli

TINY = REPO / "scenarios" / "studies" / "tiny_compensate.toml"
TARGETS = ["drift_um", "drift_x_um"]
FILES = ("days.csv", "summary.csv", "timeseries.csv.gz")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("compensate")
    # one rule, consecutive days (one simulation): the shortest run that still trains,
    # faults and retrains
    text = TINY.read_text().replace('retrain = ["after-fault", "never"]',
                                    'retrain = ["after-fault"]')
    single = folder / "single.toml"
    single.write_text(text)
    multi = folder / "multi.toml"
    multi.write_text(text.replace('climate = "chongqing"',
                                  f'climate = "chongqing"\ntargets = {TARGETS}', 1))
    for name, path in (("single", single), ("multi", multi)):
        assert cli.main(["compensate", str(path), "-o", str(folder / name), "-q"]) == 0
    return folder, multi


@pytest.mark.slow
def test_the_drift_of_a_multi_target_compensation_is_the_drift_alone(runs):
    folder, _ = runs
    for name in FILES:
        assert (folder / "multi" / "drift_um" / name).read_bytes() == \
            (folder / "single" / name).read_bytes(), name
    readme = (folder / "multi" / "README.md").read_text()
    assert "| after-fault | all_raw |" in readme and "drift_x_um" in readme
    assert "| after-fault | six_diff@mtlasso |" in readme


@pytest.mark.slow
def test_a_joint_model_reads_one_sensor_set_for_every_target(runs):
    folder, _ = runs
    days = {t: pd.read_csv(folder / "multi" / "joint" / t / "days.csv", keep_default_na=False)
            for t in TARGETS}
    models = set(days["drift_um"]["model"])
    assert models == {f"{m}@{j}" for m in ("all_raw", "six_diff", "all_raw:greedy")
                      for j in ("union", "mtlasso", "pls-vip")}
    pd.testing.assert_series_equal(days["drift_um"]["inputs"], days["drift_x_um"]["inputs"])
    own = {t: pd.read_csv(folder / "multi" / t / "days.csv", keep_default_na=False)
           for t in TARGETS}
    first = {t: set(own[t].loc[(own[t]["model"] == "six_diff") & (own[t]["day"] == 2),
                                "inputs"].iloc[0].split(";")) for t in TARGETS}
    union = days["drift_um"]
    union = set(union.loc[(union["model"] == "six_diff@union") & (union["day"] == 2),
                          "inputs"].iloc[0].split(";"))
    assert union == first["drift_um"] | first["drift_x_um"]


@pytest.mark.slow
def test_each_targets_residual_is_its_true_rise_minus_its_offset(runs):
    from spindlebench.core.paths import DEFAULT_FMU
    from spindlebench.studies.compensation.compensation_file import load_compensation
    from spindlebench.studies.compensation.loop import simulate_days

    folder, multi = runs
    truths = simulate_days(load_compensation(multi), DEFAULT_FMU)
    series = pd.read_csv(folder / "multi" / "drift_x_um" / "timeseries.csv.gz")
    summary = pd.read_csv(folder / "multi" / "drift_x_um" / "summary.csv")
    drift = pd.read_csv(folder / "multi" / "drift_um" / "timeseries.csv.gz")
    for day, at in series[series["model"] == "all_raw"].groupby("day"):
        x = truths[day]["true_drift_x_um"].to_numpy()
        # the X drift's own true rise, not the axial drift's
        np.testing.assert_allclose(at["true_drift_um"], x - x[0], rtol=1e-5, atol=1e-4)
        z = drift[(drift["model"] == "all_raw") & (drift["day"] == day)]["true_drift_um"]
        assert not np.allclose(at["true_drift_um"], z)
        np.testing.assert_allclose(at["residual_um"], at["true_drift_um"] - at["offset_um"],
                                   atol=2e-5)
    everything = series[series["model"] == "all_raw"]
    row = summary[(summary["part"] == "all days") & (summary["model"] == "all_raw")].iloc[0]
    assert row["rms_um"] == pytest.approx(np.sqrt(np.mean(everything["residual_um"] ** 2)),
                                          rel=1e-4)
    uncompensated = summary[(summary["part"] == "all days")
                            & (summary["model"] == "uncompensated")].iloc[0]
    assert row["rms_um"] < uncompensated["rms_um"]  # the X drift's model compensates it
