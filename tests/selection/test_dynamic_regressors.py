"""The identified models of issue 22 as ``--regressor`` on the selection protocol
(``selection.dynamic``): the same numbers as the estimators fitted by hand, the speed read
from each recording, the observer reading the selected rises, one line without the speed."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from spindlebench.identification.estimators import (
    ObserverRegressor,
    ThermalNetworkRegressor,
    TransferFunctionRegressor,
)
from spindlebench.identification.model import lag
from spindlebench.selection import evaluate
from spindlebench.selection.errors import SelectionError

SENSORS = ["T1", "T2", "T3"]


def recording(speed: float, seed: int, hours: float = 12.0, bump_C: float = 0.0,
              step_s: float = 60.0) -> pd.DataFrame:
    """A first-order machine: node rise (n / 4000)^1.5 with a 1.5 h time constant; error
    -30 um per unit node, sensors 1, 2, 3 K per unit (plus ``bump_C`` on T1 from 6 h)."""
    t = np.arange(0, hours * 3600, step_s)
    n = np.where((t // 7200) % 2 == 0, speed, 0.0)
    node = lag((n / 4000.0) ** 1.5, 5400.0, t)
    rng = np.random.default_rng(seed)
    frame = pd.DataFrame({"time_s": t, "spindle_speed_rpm": n, "ambient_C": np.full(t.size, 20.0)})
    for i, sensor in enumerate(SENSORS, start=1):
        frame[sensor] = 20 + i * node + rng.normal(0, 0.02, t.size)
    frame.loc[t >= 6 * 3600, "T1"] += bump_C
    drift = -30 * node + rng.normal(0, 0.05, t.size)
    frame["drift_um"] = drift - drift[0]
    return frame


@pytest.fixture(scope="module")
def runs():
    return recording(4000, 0), recording(3000, 1), recording(5000, 2)


def _drivers(frame: pd.DataFrame, *extra: str) -> np.ndarray:
    return frame[["time_s", "spindle_speed_rpm", *extra]].to_numpy(float)


def test_transfer_function_regressor_is_the_estimator_on_time_and_speed(runs):
    train, a, b = runs
    result = evaluate(train, {"a": a, "b": b}, "drift_um", sensors=SENSORS, k=2,
                      regressor="tf1")
    model = TransferFunctionRegressor(order=1).fit(_drivers(train), train["drift_um"])
    np.testing.assert_allclose(result.predictions["a"], model.predict(_drivers(a)))
    assert model.taus_s_[0] == pytest.approx(5400, rel=0.05)
    # speed alone predicts other speeds of a first-order machine: well below the range
    assert result.rmse_um["b"] < 0.05 * np.ptp(b["drift_um"])
    assert result.to_dict()["coefficients"] is None
    assert result.to_dict()["method"]["label"] == "closure+tf1"


@pytest.mark.slow
def test_network_regressors_read_the_speed_and_the_ambient(runs):
    train, a, _ = runs
    for regressor, extra, estimator in (
            ("network", (), ThermalNetworkRegressor()),
            ("network-ambient", ("ambient_C",), ThermalNetworkRegressor(ambient=True))):
        result = evaluate(train, {"a": a}, "drift_um", sensors=SENSORS, k=1,
                          regressor=regressor)
        model = estimator.fit(_drivers(train, *extra), train["drift_um"])
        np.testing.assert_allclose(result.predictions["a"], model.predict(_drivers(a, *extra)))


@pytest.mark.slow
def test_observer_reads_the_selected_rises_the_speed_models_do_not():
    train, a = recording(4000, 0, step_s=180.0), recording(3000, 1, step_s=180.0)
    bumped = recording(3000, 1, bump_C=2.0, step_s=180.0)  # T1 reads 2 K more from 6 h
    results = {}
    for regressor in ("tf1", "observer"):
        results[regressor] = [
            evaluate(train, {"a": test}, "drift_um", sensors=["T1"], k=1,
                     method="all-candidates", regressor=regressor).predictions["a"]
            for test in (a, bumped)]
    np.testing.assert_array_equal(*results["tf1"])
    early, late = slice(0, 6 * 20), slice(6 * 20, None)
    change = results["observer"][1] - results["observer"][0]
    np.testing.assert_array_equal(change[early], 0.0)  # a filter: nothing before the bump
    # the filter fitted on clean data trusts its model: a small but real answer to the bump
    assert np.abs(change[late]).min() > 0 and abs(change[-1]) > 1e-5
    fitted = evaluate(train, {"a": a}, "drift_um", sensors=["T1"], k=1,
                      method="all-candidates", regressor="observer").fit.estimator
    model = ObserverRegressor().fit(
        np.column_stack([_drivers(train), train["T1"] - train["T1"][0]]), train["drift_um"])
    X = np.column_stack([_drivers(a), a["T1"] - a["T1"][0]])
    np.testing.assert_allclose(fitted.predict(X), model.predict(X))


def test_a_recording_without_the_speed_is_one_line(runs):
    train, a, _ = runs
    with pytest.raises(SelectionError, match=r"recording a: regressor 'tf1' reads the column "
                       r"'spindle_speed_rpm'"):
        evaluate(train, {"a": a.drop(columns="spindle_speed_rpm")}, "drift_um",
                 sensors=SENSORS, k=1, regressor="tf1")
    with pytest.raises(SelectionError, match="'ambient_C'"):
        evaluate(train.drop(columns="ambient_C"), {"a": a}, "drift_um", sensors=SENSORS, k=1,
                 regressor="network-ambient")


def test_a_dynamic_regressor_is_not_a_pipeline_on_rises():
    from spindlebench.selection.registry import make_pipeline, parse_method

    with pytest.raises(SelectionError, match="dynamic model"):
        make_pipeline(parse_method("closure+observer"), k=2)


def test_cli_evaluate_regressor_tf1(runs, tmp_path, capsys):
    from spindlebench.commands import main as cli

    paths = []
    for name, frame in zip(("train", "a", "b"), runs, strict=True):
        paths.append(tmp_path / f"{name}.csv")
        frame.to_csv(paths[-1], index=False)
    out = tmp_path / "r.json"
    status = cli.main(["evaluate", "--train", str(paths[0]), "--test", *map(str, paths[1:]),
                       "--target", "drift_um", "--sensors", ",".join(SENSORS), "--clusters",
                       "1", "--regressor", "tf1", "--allow-target-copy", "--json", str(out)])
    printed, err = capsys.readouterr()
    assert status == 0, err
    assert "TransferFunctionRegressor of spindle_speed_rpm along time_s" in printed
    record = json.loads(out.read_text())
    assert record["method"]["regressor"] == "tf1" and record["mean_rmse_um"] < 1.0
