"""The rollout metric and the dynamic entrants of the benchmark.

A **static** model (every selection method's regression on rises, and every built-in
regressor) predicts each sample from that sample's sensor rises, relative to the run's first
row. It carries no state from one sample to the next, so nothing in it can be reset or
corrected along the run: its prediction over the whole held-out run from its start *is* its
ordinary prediction, and its ``rollout_rmse_um`` equals its ``rmse_um``.

A **dynamic** model predicts from the programme over time (the identified grey-box and
observer models of ``identification``). Its ordinary prediction (``predict``) may use the
run's measurements as it goes (an observer corrects its state with the sensors at every
sample). Its rollout is the error predicted over the whole held-out run from the run's start
with no reset or correction of its state by the run's measurements: only the programme (and
the inputs the model takes as inputs) drive it. The hook is one method (the protocol
``docs/contracts.md`` names):

    predict_rollout(run: pandas.DataFrame) -> numpy.ndarray

``run`` is one whole recording in time order, its columns as read (``time_s``, the driver
inputs such as ``spindle_speed_rpm``, the sensors); the result has one value per row. The
benchmark calls it on the fitted estimator of any entrant that has it (a user's regressor by
import path too, or an identified model once it is a ``--regressor``), and uses the ordinary
prediction for every other one.

The dynamic entrants, labels ``dynamic:NAME`` (``DYNAMIC``), are the ``--regressor``
models of ``selection.dynamic`` (one home for how each is built: ``make_dynamic``) with fixed
orders, fitted on the training run itself (``X`` = ``time_s``, the spindle speed,
and for the observer the rises since the run's first row of the ``k`` sensors most
correlated with the error on that run: raw degC would make a held-out run that starts warmer
than the training one look like heating to the filter, which a held-out July run showed,
89 um against 4.2 um with rises on the ambient-following machine):

- ``dynamic:tf1``: ``TransferFunctionRegressor(order=1)``, the speed's heat input through
  one lag;
- ``dynamic:network``: ``ThermalNetworkRegressor(n_nodes=2)``, the grey-box network;
- ``dynamic:observer``: ``ObserverRegressor(n_nodes=1, disturbances=1)``, the network with
  a steady-state Kalman filter on the sensors; its rollout is the network alone, run open
  loop from the run's start.

Orders are fixed rather than ``"auto"``: the automatic choice refits per left-out cycle
(measured: 2.1 CPU-s for the network and 5.1 CPU-s for the observer on one 8 h run, against
0.07 and 0.23 s fixed), which times every task's folds would put the default suite over its
ten minutes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.recording import SPEED_COLUMN, TIME_COLUMN

#: The hook's name (one home: the benchmark looks it up with ``getattr``).
HOOK = "predict_rollout"
PREFIX = "dynamic:"
#: Dynamic entrant name (a ``selection.dynamic`` regressor) -> its fixed orders.
DYNAMIC: dict[str, dict[str, Any]] = {
    "tf1": {"order": 1},
    "network": {"n_nodes": 2},
    "observer": {"n_nodes": 1, "disturbances": 1},
}


def _estimator(name: str, seed: int):
    """The entrant's estimator: the ``--regressor`` model with the entrant's fixed orders."""
    from spindlebench.selection.dynamic import make_dynamic

    return make_dynamic(name, random_state=seed).set_params(**DYNAMIC[name])


def is_dynamic(label: str) -> bool:
    return isinstance(label, str) and label.startswith(PREFIX)


def rollout_of(estimator: object, run: pd.DataFrame, ordinary: np.ndarray) -> np.ndarray:
    """The rollout of ``estimator`` on ``run``: its hook's, or (a static model) ``ordinary``."""
    hook = getattr(estimator, HOOK, None)
    if hook is None:
        return ordinary
    values = np.asarray(hook(run), dtype=float).reshape(-1)
    if values.shape != (len(run),):
        raise SpindlebenchError(f"{type(estimator).__name__}.{HOOK} gave {values.size} "
                                f"value(s) for a run of {len(run)} rows; one each is needed")
    return values


@dataclass(frozen=True)
class DynamicChoice:
    """A dynamic entrant (``dynamic:NAME``): what the leaderboard names and records."""

    name: str

    @property
    def label(self) -> str:
        return PREFIX + self.name

    def to_dict(self) -> dict[str, Any]:
        from spindlebench.selection.dynamic import reads_rises

        cls = type(_estimator(self.name, 0)).__name__
        return {"dynamic": self.name, "estimator": f"spindlebench.identification.estimators:"
                f"{cls}", "params": DYNAMIC[self.name], "reads_sensors": reads_rises(self.name)}


def parse_dynamic(label: str) -> DynamicChoice:
    name = label[len(PREFIX):]
    if name not in DYNAMIC:
        raise SpindlebenchError(f"method {label!r}: unknown dynamic model {name!r}; choose one "
                                f"of {', '.join(PREFIX + n for n in DYNAMIC)}")
    return DynamicChoice(name)


class RunModel:
    """An identification estimator fitted on one run and predicting whole runs: ``X`` is the
    run's time, speed and (observer) the chosen sensors' rises (K since the run's first
    row, as every static model reads them)."""

    def __init__(self, choice: DynamicChoice, k: int, seed: int) -> None:
        from spindlebench.selection.dynamic import reads_rises

        self.reads_sensors = reads_rises(choice.name)
        self.estimator = _estimator(choice.name, seed)
        self.k = k
        self.sensors: tuple[str, ...] = ()

    def _inputs(self, run: pd.DataFrame) -> np.ndarray:
        missing = [c for c in (TIME_COLUMN, SPEED_COLUMN, *self.sensors) if c not in run]
        if missing:
            raise SpindlebenchError(f"a dynamic model needs column(s) {', '.join(missing)} "
                                    "in every run")
        X = run.loc[:, [TIME_COLUMN, SPEED_COLUMN, *self.sensors]].to_numpy(float, copy=True)
        X[:, 2:] -= X[0, 2:]
        return X

    def fit_run(self, run: pd.DataFrame, target: str, sensors: Sequence[str]) -> RunModel:
        y = run[target].to_numpy(float)
        if self.reads_sensors:  # the k sensors whose rise is most correlated with the error
            rises = run.loc[:, list(sensors)].to_numpy(float)
            rises = rises - rises[0]
            with np.errstate(invalid="ignore", divide="ignore"):
                r = np.array([abs(np.corrcoef(column, y)[0, 1]) for column in rises.T])
            order = np.argsort(-np.nan_to_num(r, nan=-1.0), kind="stable")[:self.k]
            self.sensors = tuple(sensors[i] for i in sorted(order))
        self.estimator.fit(self._inputs(run), y)
        return self

    def predict(self, run: pd.DataFrame) -> np.ndarray:
        """The ordinary prediction (an observer's filtered one)."""
        return np.asarray(self.estimator.predict(self._inputs(run)), dtype=float)

    def predict_rollout(self, run: pd.DataFrame) -> np.ndarray:
        """From the run's start, no correction by its measurements: the observer's network
        open loop; the others' ordinary prediction (already open loop)."""
        if not self.reads_sensors:
            return self.predict(run)
        from spindlebench.identification.model import Inputs

        X = self._inputs(run)
        return self.estimator.fit_.predict(Inputs(X[:, 0], X[:, 1]))[:, 0]
