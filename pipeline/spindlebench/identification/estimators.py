"""scikit-learn regressors of the identified models (``model``, ``observer``).

Their ``X`` is a recording's columns in time order, not a table of independent rows: column 0
is ``time_s``, column 1 the spindle speed (rev/min), then (``ThermalNetworkRegressor`` with
``ambient=True``) the ambient in degC, then (``feeds=k``) ``k`` further heat inputs used as
they are (e.g. ``|feed_x| + |feed_y|`` in mm/min), or (``ObserverRegressor``) the sensors in
degC. A model
is simulated through all of ``X`` from rest at its first row; ``sample_weight`` 0 leaves a
sample out of the fit while the simulation still runs through it (the held-out cycles of a
continuous recording).
"""

from __future__ import annotations

from numbers import Integral, Real
from typing import ClassVar

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, _fit_context
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted, validate_data

from spindlebench.identification.model import (
    Inputs,
    Structure,
    blocks,
    fit,
    rezeroed_rmse,
    select_order,
)
from spindlebench.identification.observer import ObserverError, build_observer

#: Orders tried when ``n_nodes="auto"``.
AUTO_ORDERS = (1, 2, 3)
#: The observer's candidates when ``n_nodes``/``disturbances`` are "auto".
AUTO_OBSERVER_NODES = (1, 2)
AUTO_DISTURBANCES = (0, 1, 2)


def _inputs(X: np.ndarray, ambient: bool = False, feeds: int = 0) -> Inputs:
    first = 3 if ambient else 2
    linear = X[:, first:first + feeds].T if feeds else np.empty((0, 0))
    return Inputs(X[:, 0], X[:, 1], linear, ambient_C=X[:, 2] if ambient else None)


def _mask(sample_weight, n: int) -> np.ndarray:
    return np.ones(n) if sample_weight is None else np.asarray(sample_weight, dtype=float)


class ThermalNetworkRegressor(RegressorMixin, BaseEstimator):
    """Grey-box thermal network from the speed programme (``model`` module docstring).

    Parameters
    ----------
    n_nodes : int or "auto", default="auto"
        Thermal nodes; "auto" picks 1, 2 or 3 by leave-one-cycle-out held-out error
        (``model.select_order``).
    speed_sources : int, default=1
        Heat sources of the speed, each ``(n / n_ref)^a`` with its own exponent.
    ambient : bool, default=False
        Column 2 of ``X`` is the ambient (degC), an input to every node.
    feeds : int, default=0
        The next ``feeds`` columns of ``X`` (after the ambient, if any) are heat inputs used
        as they are, one source each with its own weight per node (a Hammerstein input map:
        the feeds' heat is about proportional to the feed rate; the speed's goes through
        ``(n / n_ref)^a``). A user has them from the NC programme.
    initial : bool, default=False
        Fit each node's initial temperature (else the first sample is at rest).
    exponent : float or None, default=None
        A fixed heat-input exponent (None: fitted in [0.3, 3]).
    basis : tuple of float or None, default=None
        Fixed exponents, one speed source each, instead of ``speed_sources``/``exponent``:
        ``(0.0, 5/3)`` is a loss present whenever the spindle turns (exponent 0: the on/off
        indicator; feeds, a motor's base loss) plus Palmgren bearing friction. Fixed and
        distinct, so two sources cannot cancel with huge opposite weights as two fitted
        exponents at the same value do.
    starts : int, default=4
        Starting points of the least squares (the first fixed, the others seeded).
    random_state : int, default=0
        Seed of the starting points.

    Attributes
    ----------
    fit_ : model.FitResult
        Time constants, exponents, output weights, intervals, status.
    order_scores_ : list of dict
        Held-out RMSE per candidate order ("auto" only).

    Examples
    --------
    A first-order system, gain 5 um, time constant 2 h, heated by (n / 4000)^1:

    >>> import numpy as np
    >>> t = np.arange(0, 24 * 3600, 60.0)
    >>> n = np.where((t // 14400) % 2 == 0, 4000.0, 0.0)
    >>> from spindlebench.identification.model import lag
    >>> y = 5.0 * lag(n / 4000.0, 7200.0, t)
    >>> model = ThermalNetworkRegressor(n_nodes=1, exponent=1.0).fit(np.column_stack([t, n]), y)
    >>> round(float(model.fit_.taus_s[0]))
    7200
    """

    _parameter_constraints: ClassVar[dict] = {
        "n_nodes": [Interval(Integral, 1, 6, closed="both"), StrOptions({"auto"})],
        "speed_sources": [Interval(Integral, 1, 2, closed="both")],
        "ambient": ["boolean"],
        "feeds": [Interval(Integral, 0, None, closed="left")],
        "initial": ["boolean"],
        "exponent": [Interval(Real, 0, None, closed="neither"), None],
        "basis": ["array-like", None],
        "starts": [Interval(Integral, 1, None, closed="left")],
        "random_state": [Interval(Integral, 0, None, closed="left")],
    }

    def __init__(self, n_nodes="auto", speed_sources: int = 1, ambient: bool = False,
                 initial: bool = False, exponent=None, starts: int = 4, random_state: int = 0,
                 basis=None, feeds: int = 0):
        self.n_nodes = n_nodes
        self.feeds = feeds
        self.speed_sources = speed_sources
        self.ambient = ambient
        self.initial = initial
        self.exponent = exponent
        self.starts = starts
        self.random_state = random_state
        self.basis = basis

    def _structure(self, n_nodes: int) -> Structure:
        basis = () if self.basis is None else tuple(float(a) for a in self.basis)
        if any(not a >= 0 for a in basis) or len(set(basis)) < len(basis):
            raise ValueError(f"basis {self.basis!r}: exponents must be >= 0 and distinct")
        return Structure("network", n_nodes, self.speed_sources, int(self.feeds), self.ambient,
                         self.initial, self.exponent, basis=basis)

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y, sample_weight=None):
        """Identify the network on the samples with ``sample_weight`` > 0."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=10)
        if X.shape[1] < 2 + self.ambient + self.feeds:
            raise ValueError(f"X has {X.shape[1]} columns; time_s, speed"
                             f"{', ambient' if self.ambient else ''} and {self.feeds} feed "
                             "column(s) expected")
        inputs = _inputs(X, self.ambient, int(self.feeds))
        weight = _mask(sample_weight, len(y))
        self.order_scores_ = []
        if self.n_nodes == "auto":
            structure, self.order_scores_ = select_order(
                [self._structure(n) for n in AUTO_ORDERS], inputs, y, weight > 0,
                seed=self.random_state, starts=2)
        else:
            structure = self._structure(int(self.n_nodes))
        self.fit_ = fit(structure, inputs, y, weight, seed=self.random_state,
                        starts=self.starts, output_names=("error",))
        return self

    def predict(self, X):
        """The error simulated through ``X`` from rest at its first row (with the fitted
        initial state if ``initial``: meant for the training recording)."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self.fit_.predict(_inputs(X, self.ambient, int(self.feeds)),
                                 initial=self.initial)[:, 0]


class TransferFunctionRegressor(RegressorMixin, BaseEstimator):
    """The simplest baseline: a first- or second-order response to the speed's heat input.

    Parameters
    ----------
    order : {1, 2}, default=1
        ``K / (tau s + 1)`` or ``K / ((tau1 s + 1)(tau2 s + 1))`` on ``(n / n_ref)^a``.
    exponent : float or None, default=None
        A fixed exponent (None: fitted).
    starts : int, default=4
    random_state : int, default=0

    Attributes
    ----------
    fit_ : model.FitResult
    gain_ : float
        ``K`` (units of ``y``) at ``n = n_ref``.
    taus_s_ : ndarray
        The time constant(s), s.

    Examples
    --------
    >>> import numpy as np
    >>> from spindlebench.identification.model import lag
    >>> t = np.arange(0, 12 * 3600, 60.0)
    >>> n = np.where(t < 6 * 3600, 3000.0, 0.0)
    >>> y = -20.0 * lag(n / 3000.0, 3600.0, t) + 1.0
    >>> model = TransferFunctionRegressor(exponent=1.0).fit(np.column_stack([t, n]), y)
    >>> round(model.gain_, 3), round(float(model.taus_s_[0]))
    (-20.0, 3600)
    """

    _parameter_constraints: ClassVar[dict] = {
        "order": [Interval(Integral, 1, 2, closed="both")],
        "exponent": [Interval(Real, 0, None, closed="neither"), None],
        "starts": [Interval(Integral, 1, None, closed="left")],
        "random_state": [Interval(Integral, 0, None, closed="left")],
    }

    def __init__(self, order: int = 1, exponent=None, starts: int = 4, random_state: int = 0):
        self.order = order
        self.exponent = exponent
        self.starts = starts
        self.random_state = random_state

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y, sample_weight=None):
        """Fit the response on the samples with ``sample_weight`` > 0."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=10)
        structure = Structure(f"tf{self.order}", exponent=self.exponent)
        self.fit_ = fit(structure, _inputs(X), y, _mask(sample_weight, len(y)),
                        seed=self.random_state, starts=self.starts, output_names=("error",))
        self.gain_ = float(self.fit_.weights[0, 0])
        self.taus_s_ = self.fit_.taus_s
        return self

    def predict(self, X):
        """The error simulated through ``X`` from rest at its first row."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self.fit_.predict(_inputs(X))[:, 0]


class ObserverRegressor(RegressorMixin, BaseEstimator):
    """The error from the speed programme and a few sensors: a steady-state Kalman filter on
    a network identified on the error and those sensors (``observer``).

    Parameters
    ----------
    n_nodes : int or "auto", default="auto"
        Nodes of the network (auto: 1 or 2, leave-one-cycle-out with ``disturbances``).
    disturbances : int or "auto", default="auto"
        Random-walk disturbance states (the unknown room and other unmodelled heat;
        auto: 0, 1 or 2).
    starts : int, default=2
    random_state : int, default=0

    Attributes
    ----------
    fit_ : model.FitResult
        The network (outputs: the error, then each sensor).
    observer_ : observer.SteadyStateObserver
        Gain, noise scale and likelihood.
    n_nodes_, disturbances_ : int
        The structure used.
    choice_scores_ : list of dict
        Held-out RMSE of each candidate (auto only).

    Examples
    --------
    >>> import numpy as np
    >>> from spindlebench.identification.model import lag
    >>> t = np.arange(0, 24 * 3600, 60.0)
    >>> n = np.where((t // 14400) % 2 == 0, 4000.0, 0.0)
    >>> node = lag(n / 4000.0, 7200.0, t)
    >>> X = np.column_stack([t, n, 20 + 10 * node])
    >>> model = ObserverRegressor(n_nodes=1, disturbances=0).fit(X, -30 * node)
    >>> bool(np.abs(model.predict(X) + 30 * node).max() < 0.5)
    True
    """

    _parameter_constraints: ClassVar[dict] = {
        "n_nodes": [Interval(Integral, 1, 6, closed="both"), StrOptions({"auto"})],
        "disturbances": [Interval(Integral, 0, None, closed="left"), StrOptions({"auto"})],
        "starts": [Interval(Integral, 1, None, closed="left")],
        "random_state": [Interval(Integral, 0, None, closed="left")],
    }

    def __init__(self, n_nodes="auto", disturbances="auto", starts: int = 2,
                 random_state: int = 0):
        self.n_nodes = n_nodes
        self.disturbances = disturbances
        self.starts = starts
        self.random_state = random_state

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X, y, sample_weight=None):
        """Identify on the error and the sensors, then tune the filter's noise."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True, ensure_min_samples=10)
        if X.shape[1] < 3:
            raise ValueError("ObserverRegressor needs time_s, speed and at least one sensor")
        inputs = _inputs(X)
        weight = _mask(sample_weight, len(y))
        outputs = np.column_stack([y, X[:, 2:]])
        scales = outputs[weight > 0].std(axis=0)
        scales[scales == 0] = 1.0
        nodes = AUTO_OBSERVER_NODES if self.n_nodes == "auto" else (int(self.n_nodes),)
        dists = AUTO_DISTURBANCES if self.disturbances == "auto" else (int(self.disturbances),)
        self.choice_scores_ = []
        if len(nodes) * len(dists) > 1:
            nodes, dists = self._choose(inputs, outputs, weight, scales, nodes, dists)
        self.n_nodes_, self.disturbances_ = nodes[0], dists[0]
        self.fit_ = fit(Structure("network", self.n_nodes_), inputs, outputs, weight,
                        scales=scales, seed=self.random_state, starts=self.starts)
        self.observer_ = build_observer(self.fit_, inputs, outputs, weight > 0,
                                        self.disturbances_)
        return self

    def _choose(self, inputs, outputs, weight, scales, nodes, dists):
        """Nodes and disturbances by leave-one-cycle-out on the training samples: fitted
        and tuned without a cycle, scored on the error's change over it."""
        parts = blocks(inputs.time_s, inputs.speed_rpm, weight > 0)
        scores = {(n, r): [] for n in nodes for r in dists}
        for part in parts:
            w = weight.copy()
            w[part] = 0.0
            for n in nodes:
                fitted = fit(Structure("network", n), inputs, outputs, w, scales=scales,
                             seed=self.random_state, starts=self.starts)
                for r in dists:
                    try:
                        obs = build_observer(fitted, inputs, outputs, w > 0, r)
                    except ObserverError:  # no filter for this structure: never chosen
                        scores[(n, r)].append(np.inf)
                        continue
                    predicted = obs.run(inputs, outputs[:, 1:])
                    scores[(n, r)].append(rezeroed_rmse(predicted[part], outputs[part, 0]))
        self.choice_scores_ = [{"n_nodes": n, "disturbances": r, "held_out_rmse": v,
                                "mean": float(np.mean(v))} for (n, r), v in scores.items()]
        best = min(scores, key=lambda key: (np.mean(scores[key]), key))
        return (best[0],), (best[1],)

    def predict(self, X):
        """The filtered error: the speed and the sensors of ``X`` only."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        return self.observer_.run(_inputs(X), X[:, 2:])
