"""The methods a sweep compares, each trained on one experiment and scored on the others.

- The paper's three candidate groups through ``spindlebench.selection.evaluate``: ``all_raw``
  (all 20 sensors), ``six_raw`` (T1, T6, T8, T10, T13, T16) and ``six_diff`` (those six plus
  their 15 pairwise differences), each at k clusters. With ``[methods] methods`` listing
  other selection methods (``spindlebench methods``), each also runs on every group, named
  ``group:label`` (``six_diff:kmeans+grey``, ``all_raw:lasso+ridge``).
- ``top-k-correlated``: what a practitioner tries first: the k raw sensors (of all 20) whose
  rises correlate most strongly with the error, then the same OLS on rises. Same k as the
  clusters, so it isolates what the fuzzy clustering adds.
- ``ridge``: no selection at all: ridge regression on the rises of all 20 sensors and their
  190 differences (standardised; the penalty is chosen by 5-fold cross-validation over
  contiguous time blocks of the training run). It has no k.

When the study asks for the ground truth, two references join them:

- every method also runs on the noise-free truth (true sensor temperatures and true drift,
  no faults): the same method with perfect instruments. This is what better sensors could
  buy, not a bound: selection by correlation can pick worse on perfectly smooth data.
- ``oracle``: OLS of the held-out run's drift on the rises of all 20 sensors, fitted on that
  run itself. Every method here predicts the drift as an intercept plus a linear combination
  of those rises (a difference is one too), so no method can score below the oracle on the
  same data: it is a true lower bound on the RMSE, and the gap to it is what selection and
  extrapolation from the training run cost.

Every score is the RMSE (um) of the predicted against the measured drift of the held-out run,
as in the paper; ``rmse_true_um`` scores the same prediction against the true drift, which is
what a compensation actually achieves.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd
from sklearn.linear_model import Ridge
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

from spindlebench.formats.recording import DRIFT_COLUMN
from spindlebench.names import (
    ALL_RAW,
    DEFAULT_METHOD,
    DEFAULT_METHOD_SEED,
    DEFAULT_REGRESSOR,
    PAPER_SIX,
    SENSORS,
    SIX_DIFF,
    SIX_RAW,
)
from spindlebench.selection import PairwiseDifferences, evaluate, rises, rmse
from spindlebench.selection.registry import (
    MethodChoice,
    fit_regressor,
    fit_with,
    parse_method,
    select_with,
)
from spindlebench.selection.regressors import blocked_cv_alpha
from spindlebench.studies.executor import one_line_error
from spindlebench.studies.study import Methods

TARGET = DRIFT_COLUMN
#: Column of each prepared frame holding the true drift rise (um), for ``rmse_true_um``.
TRUTH = "true_drift_rise_um"

ORACLE = "oracle"
GROUP_SENSORS = {ALL_RAW: SENSORS, SIX_RAW: PAPER_SIX, SIX_DIFF: PAPER_SIX}
#: Between a group and a selection method in a method's name (``six_diff:kmeans+grey``).
GROUP_SEPARATOR = ":"
#: The ``top-k-correlated`` baseline is that selection method on the raw sensors, then OLS.
TOP_K = parse_method("top-k-correlated")


@dataclass(frozen=True)
class MethodSpec:
    """One method at one k (``k`` None for methods without a sensor budget).

    ``name`` is the results' ``method`` column: a paper group alone (``six_diff``) for the
    paper's method, ``group:label`` (``six_diff:kmeans+grey``) for another selection method
    (``names.METHODS``) on that group; baselines and the oracle by their own names.
    """

    name: str
    k: int | None
    seed: int = DEFAULT_METHOD_SEED

    @property
    def label(self) -> str:
        return self.name if self.k is None else f"{self.name} k={self.k}"

    @property
    def group(self) -> str | None:
        """The paper group whose candidates the method selects from (None: a baseline)."""
        group = self.name.split(GROUP_SEPARATOR)[0]
        return group if group in GROUP_SENSORS else None

    @property
    def choice(self) -> MethodChoice:
        """The selection method on the group (the paper's when the name is a group alone)."""
        _, _, label = self.name.partition(GROUP_SEPARATOR)
        return parse_method(label or DEFAULT_METHOD)


def group_method_name(group: str, label: str) -> str:
    """The results' name of method ``label`` on ``group``: the group alone for the paper's."""
    return group if label == DEFAULT_METHOD else f"{group}{GROUP_SEPARATOR}{label}"


def method_specs(methods: Methods) -> list[MethodSpec]:
    """Every (method, k) the study asks for, groups first (each with every selection method
    of ``methods.methods``, the paper's first), in a stable order."""
    specs = [MethodSpec(group_method_name(group, label), k, methods.seed)
             for group in methods.groups for label in methods.methods
             for k in methods.clusters]
    for baseline in methods.baselines:
        if baseline == "ridge":
            specs.append(MethodSpec(baseline, None))
        else:
            specs.extend(MethodSpec(baseline, k) for k in methods.clusters)
    if methods.ground_truth:
        specs.append(MethodSpec(ORACLE, None))
    return specs


@dataclass(frozen=True)
class Score:
    """A method's result on one held-out run."""

    rmse_um: float
    rmse_true_um: float
    selected: str


def run_method(spec: MethodSpec, train: pd.DataFrame, tests: Mapping[str, pd.DataFrame],
               similarity: str) -> dict[str, Score]:
    """Train ``spec`` on ``train`` (columns T1..T20, drift_um, true_drift_rise_um) and score
    it on every frame of ``tests``."""
    if spec.group is not None:
        return _paper_group(spec, train, tests, similarity)
    if spec.name == "top-k-correlated":
        return _top_k_correlated(spec, train, tests)
    if spec.name == "ridge":
        return _ridge(train, tests)
    if spec.name == ORACLE:
        return _oracle(tests)
    raise ValueError(f"unknown method {spec.name!r}")


def _scores(tests: Mapping[str, pd.DataFrame], predictions: Mapping[str, np.ndarray],
            selected: str) -> dict[str, Score]:
    return {
        name: Score(rmse(frame[TARGET].to_numpy(float), predictions[name]),
                    rmse(frame[TRUTH].to_numpy(float), predictions[name]), selected)
        for name, frame in tests.items()
    }


def _paper_group(spec: MethodSpec, train: pd.DataFrame, tests: Mapping[str, pd.DataFrame],
                 similarity: str) -> dict[str, Score]:
    # A dropout reaches evaluate only as a whole-run NaN column (jobs.measured_frame holds a
    # dropped sensor at its last good reading): with "drop-rows" a group whose model does not
    # read that sensor is still scored; one that does fails with a one-line error.
    if spec.k is None:
        raise ValueError(f"{spec.name} needs a number of clusters k")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # constant candidates are dropped, as documented
        result = evaluate(train, dict(tests), TARGET, sensors=list(GROUP_SENSORS[spec.group]),
                          k=spec.k, differences=spec.group == SIX_DIFF,
                          similarity=similarity, missing="drop-rows", method=spec.choice,
                          seed=spec.seed)
    kept = {name: frame.iloc[result.test_rows[name]] for name, frame in tests.items()}
    return _scores(kept, result.predictions, ";".join(result.selected))


def _raw_rises(frame: pd.DataFrame) -> np.ndarray:
    return rises(frame.loc[:, list(SENSORS)].to_numpy(dtype=float))


def _top_k_correlated(spec: MethodSpec, train: pd.DataFrame,
                      tests: Mapping[str, pd.DataFrame]) -> dict[str, Score]:
    X = _raw_rises(train)
    y = train[TARGET].to_numpy(float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # constant candidates are dropped, as documented
        selection = select_with(TOP_K, X, y, spec.k, names=SENSORS)
    chosen = selection.selected
    fit = fit_with(TOP_K, X[:, chosen], y)
    predictions = {name: fit.predict(_raw_rises(frame)[:, chosen])
                   for name, frame in tests.items()}
    return _scores(tests, predictions, ";".join(SENSORS[i] for i in chosen))


def _ridge(train: pd.DataFrame, tests: Mapping[str, pd.DataFrame]) -> dict[str, Score]:
    X, y = _raw_rises(train), train[TARGET].to_numpy(float)
    candidates = PairwiseDifferences().fit(X)
    alpha = blocked_cv_alpha(candidates.transform(X), y)
    model = make_pipeline(PairwiseDifferences(), StandardScaler(), Ridge(alpha=alpha)).fit(X, y)
    predictions = {name: model.predict(_raw_rises(frame)) for name, frame in tests.items()}
    return _scores(tests, predictions, f"all 210 candidates (alpha={alpha:.3g})")


def _oracle(tests: Mapping[str, pd.DataFrame]) -> dict[str, Score]:
    predictions = {}
    for name, frame in tests.items():
        X = _raw_rises(frame)
        fit = fit_regressor(DEFAULT_REGRESSOR, X, frame[TARGET].to_numpy(float))
        predictions[name] = fit.predict(X)
    return _scores(tests, predictions, "all 20 sensors, fitted on the held-out run itself")


def score_all(specs: list[MethodSpec], train: pd.DataFrame, tests: Mapping[str, pd.DataFrame],
              similarity: str) -> list[dict[str, object]]:
    """Rows (method, k, test, scores or error) for every spec; a failing method is recorded,
    never raised, so one bad fit does not cost the others."""
    rows: list[dict[str, object]] = []
    for spec in specs:
        try:
            scores = run_method(spec, train, tests, similarity)
        except Exception as exc:  # failure isolation per method
            message = one_line_error(exc)
            rows.extend({"method": spec.name, "k": spec.k, "test_experiment": name,
                         "rmse_um": np.nan, "rmse_true_um": np.nan, "selected": "",
                         "error": message} for name in tests)
            continue
        rows.extend({"method": spec.name, "k": spec.k, "test_experiment": name,
                     "rmse_um": score.rmse_um, "rmse_true_um": score.rmse_true_um,
                     "selected": score.selected, "error": ""} for name, score in scores.items())
    return rows
