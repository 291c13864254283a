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

import functools
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
import pandas as pd
from sklearn.linear_model import Ridge
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from spindlebench.core.console import one_line_error
from spindlebench.core.names import (
    ALL_RAW,
    DEFAULT_METHOD,
    DEFAULT_METHOD_SEED,
    DEFAULT_REGRESSOR,
    PAPER_SIX,
    SENSORS,
    SIX_DIFF,
    SIX_RAW,
)
from spindlebench.formats.recording import DRIFT_COLUMN, recording_name
from spindlebench.selection import PairwiseDifferences, rises
from spindlebench.selection.differences import pairwise_differences, with_differences_matrix
from spindlebench.selection.evaluate import CheckedRecording, evaluate_checked
from spindlebench.selection.registry import (
    MethodChoice,
    fit_regressor,
    fit_with,
    parse_method,
    select_with,
)
from spindlebench.selection.regression import LinearFit, rmse_each, rmse_rows, stacked_rows
from spindlebench.selection.regressors import (
    StandardisedRidge,
    blocked_cv_alpha,
    standardised_ridge,
)
from spindlebench.selection.selectors import correlation_ranking
from spindlebench.selection.similarity import constant_columns
from spindlebench.studies.family.family_file import RIDGE_BASELINE, TOP_K_BASELINE, Methods

TARGET = DRIFT_COLUMN
#: Column of each prepared frame holding the true drift rise (um), for ``rmse_true_um``.
TRUTH = "true_drift_rise_um"

ORACLE = "oracle"
GROUP_SENSORS = {ALL_RAW: SENSORS, SIX_RAW: PAPER_SIX, SIX_DIFF: PAPER_SIX}
#: Between a group and a selection method in a method's name (``six_diff:kmeans+grey``).
GROUP_SEPARATOR = ":"
#: The ``top-k-correlated`` baseline is that selection method on the raw sensors, then OLS.
TOP_K = parse_method(TOP_K_BASELINE)
T = TypeVar("T")


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


class SharedRuns:
    """The measured runs of one (replica, condition), converted and checked once for all of
    its training runs.

    Why: each training run of a (replica, condition) scores its methods on the same
    held-out frames; one job per training run measured, checked and subtracted every run
    again for each. The checks, rises and oracle fits here depend on the held-out run only,
    so every training run reads the same arrays and gets the bits it got on its own (tests
    compare the two).
    """

    def __init__(self, frames: Mapping[str, pd.DataFrame]) -> None:
        self.frames = {str(name): frame for name, frame in frames.items()}
        self._checked: dict[str, CheckedRecording] = {}
        self._stacked: tuple[dict[str, int], np.ndarray] | None = None
        self._stacked_made = False

    def checked(self, name: str, frame: pd.DataFrame) -> CheckedRecording:
        """Run ``name`` as a checked recording; ``frame`` must be this object's frame."""
        if self.frames.get(name) is not frame:
            raise ValueError(f"run {name!r} is not one of the shared frames")
        if name not in self._checked:
            self._checked[name] = CheckedRecording(name, frame)
        return self._checked[name]

    def raw_rises(self, name: str) -> np.ndarray:
        """The rises of the 20 raw sensors of run ``name`` (shared: do not modify)."""
        checked = self.checked(name, self.frames[name])
        return self.memo("raw rises", name,
                         lambda: rises(np.asfortranarray(checked.stack(SENSORS))))

    def stacked_raw_rises(self) -> tuple[dict[str, int], np.ndarray] | None:
        """Each run's position and every run's ``raw_rises(name).T`` stacked, (runs, 20,
        samples), made once (shared: do not modify); None when the runs differ in length or
        a run's rises cannot be made (each then raises its own error where it is read)."""
        if not self._stacked_made:
            self._stacked_made = True
            try:
                rises_each = [self.raw_rises(name) for name in self.frames]
                self._stacked = None if len({r.shape for r in rises_each}) != 1 else (
                    {name: i for i, name in enumerate(self.frames)},
                    np.stack([r.T for r in rises_each]))
            except Exception:  # read run by run, where it raises
                self._stacked = None
        return self._stacked

    def memo(self, what: str, name: str, compute: Callable[[], T]) -> T:
        """``compute()`` the first time ``what`` of run ``name`` is asked for, then kept
        (for results that depend on the held-out run only, like the oracle's): kept by the
        run's checked recording (``CheckedRecording.memo``)."""
        return self.checked(name, self.frames[name]).memo(what, compute)


class EvaluationData:
    """One evaluation's recordings, converted and checked once for every method and k.

    Why: each of a job's methods used to read, check and subtract the same frames again
    (``evaluate`` per group and k, the raw rises per baseline): 99 % of an evaluation's time,
    the selection maths 1 %. The frames are columns T1..T20, drift_um and
    true_drift_rise_um; every method reads them through here, so the results are those of
    the per-method path to the last bit (tests compare the two). ``runs`` (holding the test
    frames) shares the test runs' conversions with other training runs.
    """

    def __init__(self, train: pd.DataFrame, tests: Mapping[str, pd.DataFrame],
                 runs: SharedRuns | None = None,
                 checked_train: CheckedRecording | None = None) -> None:
        self.train = train
        self.tests = {str(name): frame for name, frame in tests.items()}
        self.runs = SharedRuns(self.tests) if runs is None else runs
        self.checked_train = CheckedRecording(recording_name(train, "train"), train) \
            if checked_train is None else checked_train
        self.checked_tests = {name: self.runs.checked(name, frame)
                              for name, frame in self.tests.items()}
        self._stacked_columns: dict[str, np.ndarray | None] = {}

    def raw_rises(self, name: str | None = None) -> np.ndarray:
        """The rises of the 20 raw sensors of test run ``name`` (None: the training run);
        shared: do not modify.

        Column-major, as ``frame.loc[:, SENSORS].to_numpy()`` gives them: the BLAS calls
        of the fits below may round differently on another memory layout."""
        if name is not None:
            return self.runs.raw_rises(name)
        checked = self.checked_train  # kept by it, as the models trained on it
        return checked.memo("raw rises", lambda: rises(np.asfortranarray(checked.stack(SENSORS))))

    def test_raw_rises(self, columns: np.ndarray) -> np.ndarray | None:
        """(test runs, samples, len(columns)): run i's ``raw_rises(name)[:, columns]``, the
        same values in the same (column-major) layout, for all test runs at once (so one
        product predicts them all, ``LinearFit.predict_stacked``); None where the runs are
        not stacked (``SharedRuns.stacked_raw_rises``)."""
        stacked = self.runs.stacked_raw_rises()
        if stacked is None:
            return None
        position, rises_T = stacked
        rows = [position[name] for name in self.tests]
        return np.swapaxes(rises_T[np.ix_(rows, np.asarray(columns, dtype=np.intp))], 1, 2)

    def target(self, name: str | None = None) -> np.ndarray:
        """The measured drift of test run ``name`` (None: the training run) as float
        (shared: do not modify): ``frame[TARGET].to_numpy(float)``, the same view of the
        frame's float block, kept by its checked recording instead of asked of pandas again
        by every baseline."""
        recording = self.checked_train if name is None else self.checked_tests[str(name)]
        return recording.values(TARGET)

    def column(self, name: str, column: str) -> np.ndarray:
        """Column ``column`` of test recording ``name`` as float (shared: do not modify)."""
        return self.checked_tests[str(name)].values(column)

    def stacked_column(self, column: str) -> np.ndarray | None:
        """Column ``column`` of every test run stacked, (runs, samples), made once for every
        method's scores (shared: do not modify); None when the runs differ in length."""
        if column not in self._stacked_columns:
            self._stacked_columns[column] = stacked_rows(
                [self.column(name, column) for name in self.tests])
        return self._stacked_columns[column]


def run_method(spec: MethodSpec, train: pd.DataFrame, tests: Mapping[str, pd.DataFrame],
               similarity: str, data: EvaluationData | None = None) -> dict[str, Score]:
    """Train ``spec`` on ``train`` (columns T1..T20, drift_um, true_drift_rise_um) and score
    it on every frame of ``tests``; ``data`` (of the same frames) shares their conversions
    with the job's other methods."""
    if data is None:
        data = EvaluationData(train, tests)
    if spec.group is not None:
        return _paper_group(spec, data, similarity)
    if spec.name == TOP_K_BASELINE:
        return _top_k_correlated(spec, data)
    if spec.name == RIDGE_BASELINE:
        return _ridge(data)
    if spec.name == ORACLE:
        return _oracle(data)
    raise ValueError(f"unknown method {spec.name!r}")


def _scores(data: EvaluationData, predictions: Mapping[str, np.ndarray], selected: str,
            rows: Mapping[str, np.ndarray] | None = None,
            measured_rmse: Mapping[str, float] | None = None,
            stacked: np.ndarray | None = None) -> dict[str, Score]:
    """Scores of the predictions of every test run (on its samples ``rows`` if given), each
    RMSE of all runs in one reduction (``rmse_each``); ``measured_rmse``: the RMSE against
    the measured drift where known already; ``stacked``: the predictions stacked already
    (runs, samples), in the order of ``data.tests``."""
    names = list(data.tests)
    whole = rows is None or all(len(rows[name]) >= len(data.checked_tests[name])
                                for name in names)
    scores = _whole_scores(data, predictions, selected, measured_rmse, stacked) \
        if whole else None
    if scores is not None:
        return scores
    truths, measured = [], []
    for name in names:
        truth, target = data.column(name, TRUTH), data.column(name, TARGET)
        if rows is not None and len(rows[name]) < len(truth):
            truth, target = truth[rows[name]], target[rows[name]]
        truths.append(truth)
        measured.append(target)
    predicted = [predictions[name] for name in names]
    scores = [measured_rmse[name] for name in names] if measured_rmse is not None else \
        rmse_each(measured, predicted)
    return {name: Score(score, truth_score, selected) for name, score, truth_score
            in zip(names, scores, rmse_each(truths, predicted), strict=True)}


def _whole_scores(data: EvaluationData, predictions: Mapping[str, np.ndarray], selected: str,
                  measured_rmse: Mapping[str, float] | None,
                  stacked: np.ndarray | None) -> dict[str, Score] | None:
    """``_scores`` of predictions of every sample of every test run, against the runs'
    columns stacked once per evaluation (``EvaluationData.stacked_column``) instead of per
    method: the same reductions on the same arrays (``rmse_rows``). None where the runs or
    predictions are not equally long float64 runs or a score is not finite: ``_scores``
    then scores run by run, with its errors."""
    names = list(data.tests)
    predicted = stacked_rows([predictions[name] for name in names]) if stacked is None \
        else stacked
    truths = data.stacked_column(TRUTH)
    if predicted is None or truths is None:
        return None
    if measured_rmse is not None:
        scores: list[float] | None = [measured_rmse[name] for name in names]
    else:
        measured = data.stacked_column(TARGET)
        scores = None if measured is None else rmse_rows(measured, predicted)
    truth_scores = None if scores is None else rmse_rows(truths, predicted)
    if truth_scores is None:
        return None
    return {name: Score(score, truth_score, selected) for name, score, truth_score
            in zip(names, scores, truth_scores, strict=True)}


def _paper_group(spec: MethodSpec, data: EvaluationData, similarity: str) -> dict[str, Score]:
    # A dropout reaches evaluate only as a whole-run NaN column (jobs.measured_frame holds a
    # dropped sensor at its last good reading): with "drop-rows" a group whose model does not
    # read that sensor is still scored; one that does fails with a one-line error.
    if spec.k is None:
        raise ValueError(f"{spec.name} needs a number of clusters k")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # constant candidates are dropped, as documented
        result = evaluate_checked(data.checked_train, data.checked_tests, TARGET,
                                  sensors=list(GROUP_SENSORS[spec.group]), k=spec.k,
                                  differences=spec.group == SIX_DIFF, similarity=similarity,
                                  missing="drop-rows", method=spec.choice, seed=spec.seed)
    # evaluate scored the measured drift already (the same arrays): only the truth is left
    return _scores(data, result.predictions, ";".join(result.selected), result.test_rows,
                   result.rmse_um)


def _top_k_correlated(spec: MethodSpec, data: EvaluationData) -> dict[str, Score]:
    X = data.raw_rises()
    y = data.target()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # constant candidates are dropped, as documented
        ranking = data.checked_train.memo("top-k ranking", lambda: _top_k_ranking(X, y))
        shared = ranking is not None and isinstance(spec.k, int) and 1 <= spec.k <= len(ranking)
        chosen = ranking[:spec.k] if shared else \
            select_with(TOP_K, X, y, spec.k, names=SENSORS).selected
    # kept by the training recording, as evaluate_checked keeps the groups' models
    fit = data.checked_train.memo(("top-k fit", tuple(int(i) for i in chosen)),
                                  lambda: fit_with(TOP_K, X[:, chosen], y))
    stacked = data.test_raw_rises(chosen) if isinstance(fit, LinearFit) else None
    predicted = None if stacked is None else fit.predict_stacked(stacked)
    predictions = dict(zip(data.tests, fit.predict_each(
        [data.raw_rises(name)[:, chosen] for name in data.tests]) if predicted is None
        else predicted, strict=True))
    return _scores(data, predictions, ";".join(SENSORS[i] for i in chosen),
                   stacked=predicted)


def _top_k_ranking(X: np.ndarray, y: np.ndarray) -> np.ndarray | None:
    """The top-k baseline's choice of every k at once: its selector ranks the candidates by
    |psi| (a stable sort) and keeps the first k, so each k's choice is the first k of the
    ranking of all of them (tests compare the two); the selection of all 20 is made once
    per training run instead of once per k. None where that selection fails (a constant
    sensor): each k then selects on its own, with its own error.

    Rises that ``select_with`` has nothing to refuse or drop in (finite, no constant column,
    a target that varies: a sweep's training runs) are ranked by the selector's own ranking
    (``correlation_ranking``) on the array it would rank, ``X[:, kept]``, without
    scikit-learn checking them again (two fifths of the baseline's time)."""
    if X.shape[0] >= 2 and X.shape[0] == y.shape[0] and np.isfinite(X).all() \
            and np.isfinite(y).all() and not constant_columns(y[:, None])[0]:
        kept = np.flatnonzero(~constant_columns(X))
        if kept.size == X.shape[1]:
            return correlation_ranking(X[:, kept], y)[1]
    try:
        return select_with(TOP_K, X, y, X.shape[1], names=SENSORS).selected
    except Exception:  # each k's own selection raises its own error
        return None


def _ridge(data: EvaluationData) -> dict[str, Score]:
    X, y = data.raw_rises(), data.target()
    # kept by the training recording, as evaluate_checked keeps the groups' models
    candidates, alpha, fitted = data.checked_train.memo("ridge fit", lambda: _ridge_fit(X, y))

    @functools.cache
    def model() -> Pipeline:
        """make_pipeline(PairwiseDifferences(), StandardScaler(), Ridge(alpha)).fit(X, y),
        step by step as Pipeline.fit runs it, on the candidates made for the CV: fitted
        only where ``standardised_ridge`` (the same fit) does not serve."""
        scaler = StandardScaler().fit(candidates)
        ridge = Ridge(alpha=alpha).fit(scaler.transform(candidates), y)
        return Pipeline([("pairwisedifferences", PairwiseDifferences().fit(X)),
                         ("standardscaler", scaler), ("ridge", ridge)])

    if fitted is None:  # raises where scikit-learn refuses the training run
        scaler, ridge = model().steps[1][1], model().steps[2][1]
        if ridge.coef_.ndim == 1:
            fitted = StandardisedRidge(scaler.mean_, scaler.scale_, ridge.coef_,
                                       ridge.intercept_)
    return _scores(data, _ridge_predictions(fitted, model, data),
                   f"all 210 candidates (alpha={alpha:.3g})")


def _ridge_fit(X: np.ndarray, y: np.ndarray
               ) -> tuple[np.ndarray, float, StandardisedRidge | None]:
    """The ridge baseline's candidates of training rises ``X``, its penalty (chosen by the
    blocked CV) and its fit (None where ``standardised_ridge`` does not serve)."""
    # finite rises: PairwiseDifferences().fit(X).transform(X) without its checks
    candidates = ridge_candidates(X) if np.isfinite(X).all() else \
        PairwiseDifferences().fit(X).transform(X)
    # the 210 candidates are the 20 rises times a fixed matrix: the CV's SVDs are then small
    alpha = blocked_cv_alpha(candidates, y, factors=(X, with_differences_matrix(X.shape[1])))
    return candidates, alpha, standardised_ridge(candidates, y, alpha)


def ridge_candidates(raw: np.ndarray) -> np.ndarray:
    """``PairwiseDifferences().fit(raw).transform(raw)`` of a run's float64 rises: the same
    two calls on the same array (``pairwise_differences``, then ``np.hstack``), so the same
    bits and layout, without scikit-learn validating the array twice (an eighth of the
    ridge baseline's time). Values that are not finite pass here: ``_ridge_predictions`` then
    takes ``model.predict``, which refuses them as before.

    Column-major rises (a run's, ``EvaluationData.raw_rises``), for which ``np.hstack``
    gives a column-major block, are written into one such block directly: each sensor's
    differences with the sensors after it in one subtraction, the same values as
    ``pairwise_differences``' gathered columns, without gathering two copies of them and
    copying the result again (the block was made 7 times per evaluation)."""
    n_sensors = raw.shape[1] if raw.ndim == 2 else 0
    if n_sensors < 2 or raw.dtype != np.float64 or raw.flags.c_contiguous \
            or not raw.flags.f_contiguous:
        return np.hstack([raw, pairwise_differences(raw)])
    out = np.empty((raw.shape[0], n_sensors * (n_sensors + 1) // 2), order="F")
    out[:, :n_sensors] = raw
    at = n_sensors
    for i in range(n_sensors - 1):  # T_i minus T_{i+1}, ..., T_n: the pairs' order
        np.subtract(raw[:, i:i + 1], raw[:, i + 1:], out=out[:, at:at + n_sensors - 1 - i])
        at += n_sensors - 1 - i
    return out


def _ridge_predictions(fitted: StandardisedRidge | None, model: Callable[[], Pipeline],
                       data: EvaluationData) -> dict[str, np.ndarray]:
    """``model().predict`` of every test run's raw rises, to the last bit, in a fraction of
    the time (``fitted``: the same fit's arrays): a run's 210 candidates do not depend on
    the training run (made once per run), and the scaler's and the ridge's arithmetic
    (``StandardScaler.transform``: minus ``mean_``, divided by ``scale_``;
    ``Ridge.predict``: ``X @ coef_ + intercept_``) runs on each run's own array in its own
    memory layout, as ``model.predict`` runs it (one product on the runs stacked, or on
    another layout, rounds differently; test_sweep_methods compares the two), without
    scikit-learn validating each of the 23 inputs twice. When a run's rises or candidates
    fail or a value is not finite, every run takes ``model().predict`` one by one, so the
    errors are those of that path, in its order."""
    def candidates(name: str) -> Callable[[], np.ndarray]:
        return lambda: ridge_candidates(data.raw_rises(name))

    try:
        blocks = [data.runs.memo("ridge candidates", name, candidates(name))
                  for name in data.tests]
    except Exception:  # model.predict below raises it where it did
        blocks = []
    if len(blocks) != len(data.tests) or fitted is None:
        return {name: model().predict(data.raw_rises(name)) for name in data.tests}
    # each run scaled into one reused buffer of the block's own layout (empty_like keeps
    # it, as ``(block - mean_) / scale_`` does): the same elementwise arithmetic and the
    # same product on the same layout, without two fresh arrays per run
    predictions: dict[str, np.ndarray] = {}
    buffer: np.ndarray | None = None
    for name, block in zip(data.tests, blocks, strict=True):
        if buffer is None or buffer.shape != block.shape or \
                buffer.flags.f_contiguous != block.flags.f_contiguous or \
                buffer.flags.c_contiguous != block.flags.c_contiguous:
            buffer = np.empty_like(block)
        np.subtract(block, fitted.mean, out=buffer)
        np.divide(buffer, fitted.scale, out=buffer)
        predictions[name] = buffer @ fitted.coef + fitted.intercept
    # a value of a scaled block that is not finite (which scikit-learn refuses) makes its
    # run's prediction not finite (inf times any coefficient, zero too, is not finite): one
    # check of the predictions instead of one of each 181 x 210 block
    if not np.isfinite(np.concatenate(list(predictions.values()))).all():
        return {name: model().predict(data.raw_rises(name)) for name in data.tests}
    return predictions


def _oracle(data: EvaluationData) -> dict[str, Score]:
    # Fitted on the held-out run itself, so the same for every training run: fitted once
    # per run (all fits first, then the scores: the errors of one pass each)
    def prediction(name: str) -> Callable[[], np.ndarray]:
        def fit() -> np.ndarray:
            X = data.raw_rises(name)
            return fit_regressor(DEFAULT_REGRESSOR, X, data.target(name)).predict(X)
        return fit

    predictions = {name: data.runs.memo(ORACLE, name, prediction(name)) for name in data.tests}
    return _scores(data, predictions, "all 20 sensors, fitted on the held-out run itself")


def score_all(specs: list[MethodSpec], train: pd.DataFrame, tests: Mapping[str, pd.DataFrame],
              similarity: str, runs: SharedRuns | None = None,
              checked_train: CheckedRecording | None = None) -> list[dict[str, object]]:
    """Rows (method, k, test, scores or error) for every spec; a failing method is recorded,
    never raised, so one bad fit does not cost the others. ``runs`` (holding the frames of
    ``tests``) shares the test runs' conversions with other training runs; ``checked_train``
    (``train`` checked, or a recording of the same content) the models trained on it with
    other evaluations."""
    rows: list[dict[str, object]] = []
    # the one pass: every spec works on its arrays
    data = EvaluationData(train, tests, runs, checked_train)
    for spec in specs:
        try:
            scores = run_method(spec, train, tests, similarity, data)
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
