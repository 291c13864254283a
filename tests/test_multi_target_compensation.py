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
TARGETS = ["drift_um", "tilt_a_urad"]
FILES = ("days.csv", "summary.csv", "timeseries.csv.gz")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("compensate")
    # one rule, cold starts: the shortest run that still trains, faults and retrains
    text = TINY.read_text().replace('retrain = ["after-fault", "never"]',
                                    'retrain = ["after-fault"]')
    single = folder / "single.toml"
    single.write_text(text)
    multi = folder / "multi.toml"
    multi.write_text(text.replace('climate = "chongqing"',
                                  f'climate = "chongqing"\ntargets = {TARGETS}', 1))
    for name, path in (("single", single), ("multi", multi)):
        assert cli.main(["compensate", str(path), "-o", str(folder / name), "-q",
                         "--days", "cold-starts"]) == 0
    return folder, multi


@pytest.mark.slow
def test_the_drift_of_a_multi_target_compensation_is_the_drift_alone(runs):
    folder, _ = runs
    for name in FILES:
        assert (folder / "multi" / "drift_um" / name).read_bytes() == \
            (folder / "single" / name).read_bytes(), name
    readme = (folder / "multi" / "README.md").read_text()
    assert "| after-fault | all_raw |" in readme and "tilt_a_urad" in readme


@pytest.mark.slow
def test_each_targets_residual_is_its_true_rise_minus_its_offset(runs):
    from spindlebench.core.paths import DEFAULT_FMU
    from spindlebench.studies.compensation.compensation_file import load_compensation
    from spindlebench.studies.compensation.loop import simulate_days

    folder, multi = runs
    study = load_compensation(multi)
    from dataclasses import replace

    truths = simulate_days(replace(study, days="cold-starts"), DEFAULT_FMU)
    series = pd.read_csv(folder / "multi" / "tilt_a_urad" / "timeseries.csv.gz")
    summary = pd.read_csv(folder / "multi" / "tilt_a_urad" / "summary.csv")
    drift = pd.read_csv(folder / "multi" / "drift_um" / "timeseries.csv.gz")
    for day, at in series[series["model"] == "all_raw"].groupby("day"):
        tilt = truths[day]["true_tilt_a_urad"].to_numpy()
        # the tilt's own true rise (µrad), not the axial drift's
        np.testing.assert_allclose(at["true_drift_um"], tilt - tilt[0], rtol=1e-5, atol=1e-4)
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
    assert row["rms_um"] < uncompensated["rms_um"]  # the tilt's model compensates the tilt
