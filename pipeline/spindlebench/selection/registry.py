"""The one front door from a method's name to its scikit-learn estimators.

A method choice is a selection method (``method_registry.METHOD_REGISTRY``), the choice
inside a cluster (``names.WITHIN``, cluster methods only) and a regressor
(``names.REGRESSORS``). Written as one label, ``method[+within][+regressor]`` with the
defaults (psi, ols) left out, e.g.
``closure`` (the paper's method), ``kmeans+grey``, ``lasso+ridge``, ``ward+grey+pls``: that
label is what study files list and what report tables use as a column name.

A part may also be a user's class by import path (``selection.user_methods``):
``mypkg.sel:MySel``, ``mypkg.sel:MySel[alpha=0.5]+ridge``,
``all-candidates+mypkg.reg:MyRegressor`` (``all-candidates`` keeps every candidate, so the
regressor or pipeline sees them all). It runs through the same ``select_with`` /
``fit_with`` as a built-in.

Examples
--------
>>> choice = parse_method("kmeans+grey+pls")
>>> choice.method, choice.within, choice.regressor, choice.label
('kmeans', 'grey', 'pls', 'kmeans+grey+pls')
>>> make_pipeline(choice, k=2, differences=True).named_steps.keys()
dict_keys(['differences', 'select', 'regress'])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import (
    DEFAULT_METHOD,
    DEFAULT_METHOD_SEED,
    DEFAULT_REGRESSOR,
    DEFAULT_SIMILARITY,
    DEFAULT_WITHIN,
    LINEAR_REGRESSORS,
    REGRESSORS,
    WITHIN,
)
from spindlebench.selection.dynamic import is_dynamic, make_dynamic
from spindlebench.selection.errors import SelectionError
from spindlebench.selection.method_registry import METHOD_REGISTRY, descriptions, method_names
from spindlebench.selection.user_methods import (
    UserMethod,
    is_import_path,
    parse_params,
    parse_user_part,
    split_label,
)

if TYPE_CHECKING:  # scikit-learn is imported only by the functions that build estimators:
    # ``evaluate`` with the paper's method never needs it (~3 s of CPU at start-up here)
    from sklearn.base import BaseEstimator
    from sklearn.pipeline import Pipeline


@dataclass(frozen=True)
class MethodChoice:
    """A selection method, the choice inside its clusters and the regressor after it."""

    method: str = DEFAULT_METHOD
    within: str = DEFAULT_WITHIN
    regressor: str = DEFAULT_REGRESSOR

    def __post_init__(self) -> None:
        for value, known, what in ((self.method, METHOD_REGISTRY, "method"),
                                   (self.within, WITHIN, "within"),
                                   (self.regressor, REGRESSORS, "regressor")):
            if what != "within" and isinstance(value, str) and is_import_path(value):
                user = parse_user_part(value)  # checked: imports, and is a selector/regressor
                object.__setattr__(self, what, user.label)
                user.build(role=what)
                continue
            if value not in known:
                raise SelectionError(f"unknown {what} {value!r}; choose one of "
                                     f"{', '.join(known)} (see 'spindlebench methods')")
        if self.within != DEFAULT_WITHIN and not self.clustered:
            clustered = ", ".join(method_names(clustered=True))
            raise SelectionError(f"method {self.method!r} has no clusters; 'within' "
                                 f"({self.within!r}) applies to {clustered}")

    @property
    def clustered(self) -> bool:
        entry = METHOD_REGISTRY.get(self.method)  # None: a user's class by import path
        return entry is not None and entry.clustered

    @property
    def user_method(self) -> UserMethod | None:
        """The user's selector when the method is an import path."""
        return parse_user_part(self.method) if is_import_path(self.method) else None

    @property
    def user_regressor(self) -> UserMethod | None:
        """The user's regressor (or pipeline) when the regressor is an import path."""
        return parse_user_part(self.regressor) if is_import_path(self.regressor) else None

    @property
    def is_paper(self) -> bool:
        """The paper's method exactly (closure, |psi|, OLS)."""
        return self == MethodChoice()

    @property
    def label(self) -> str:
        parts = [self.method]
        if self.within != DEFAULT_WITHIN:
            parts.append(self.within)
        if self.regressor != DEFAULT_REGRESSOR:
            parts.append(self.regressor)
        return "+".join(parts)

    def to_dict(self) -> dict[str, Any]:
        """Method, within, regressor; with a user's class, ``code``: its package, version
        and source hash (``UserMethod.provenance``)."""
        out: dict[str, Any] = {"method": self.method, "within": self.within,
                               "regressor": self.regressor}
        users = [user for user in (self.user_method, self.user_regressor) if user is not None]
        if users:
            out["code"] = [user.provenance() for user in users]
        return out


#: The paper's method exactly (closure, |psi|, OLS): ``place``'s ``fuzzy``.
PAPER_METHOD = MethodChoice()


def parse_method(label: str) -> MethodChoice:
    """``method[+within][+regressor]`` -> ``MethodChoice``; one-line error otherwise."""
    if not isinstance(label, str) or not label.strip():
        raise SelectionError(f"a method label must be a non-empty string, got {label!r}")
    parts = split_label(label)
    method, rest = parts[0], parts[1:]
    within, regressor = DEFAULT_WITHIN, DEFAULT_REGRESSOR
    seen_within = seen_regressor = False
    for part in rest:
        if part in WITHIN and not seen_within and not seen_regressor:
            within, seen_within = part, True
        elif (part in REGRESSORS or is_import_path(part)) and not seen_regressor:
            regressor, seen_regressor = part, True
        else:
            raise SelectionError(
                f"method {label!r}: {part!r} is not a choice inside clusters "
                f"({', '.join(WITHIN)}) or a regressor ({', '.join(REGRESSORS)}), or comes "
                "twice or out of order (method+within+regressor)")
    return MethodChoice(method, within, regressor)


def check_labels(labels, where: str) -> tuple[str, ...]:
    """Study-file list of method labels, each parsed (one line naming ``where``), canonical
    and without repeats."""
    out: list[str] = []
    for label in labels:
        try:
            canonical = parse_method(label).label
        except SelectionError as exc:
            raise SpindlebenchError(f"{where}: {exc}") from None
        if canonical in out:
            raise SpindlebenchError(f"{where}: {canonical!r} is listed twice")
        out.append(canonical)
    return tuple(out)


def methods_record(labels) -> dict[str, dict[str, Any]]:
    """``{label: MethodChoice.to_dict()}`` of study method labels: what a study's provenance
    records of its methods (a user's class with its package, version and source hash, as
    ``evaluate --json`` and ``benchmark`` record it)."""
    return {label: parse_method(label).to_dict() for label in labels}


def with_params(choice: MethodChoice, params: str | list[str] | None) -> MethodChoice:
    """``choice`` with ``name=value`` parameters (``--method-param``) added to its user
    class: the method's if it is one, else the regressor's."""
    if not params:
        return choice
    text = ",".join([params] if isinstance(params, str) else params)
    user, slot = ((choice.user_method, "method") if choice.user_method is not None
                  else (choice.user_regressor, "regressor"))
    if user is None:
        raise SelectionError("--method-param applies to a method or regressor given by import "
                             f"path (package.module:Class); {choice.label!r} has none")
    added = dict(user.params)
    for name, value in parse_params(text, "--method-param"):
        added[name] = value
    updated = UserMethod(user.path, tuple(added.items())).label
    return MethodChoice(**{**{"method": choice.method, "within": choice.within,
                              "regressor": choice.regressor}, slot: updated})


def make_selector(choice: MethodChoice, k: int, similarity: str = DEFAULT_SIMILARITY,
                  random_state=DEFAULT_METHOD_SEED) -> BaseEstimator:
    """The selector of ``choice`` keeping ``k`` candidates: a user's class by import path, or
    the factory of its registry entry (``method_registry``)."""
    if choice.user_method is not None:
        return choice.user_method.build(k, random_state, role="method")
    return METHOD_REGISTRY[choice.method].make(k, within=choice.within, similarity=similarity,
                                               random_state=random_state)


def make_regressor(choice: MethodChoice, random_state=DEFAULT_METHOD_SEED) -> BaseEstimator:
    """The regressor of ``choice`` (seeded ones get ``random_state``)."""
    from spindlebench.selection import nonlinear, regressors
    from spindlebench.selection.estimators import RiseRegressor

    if choice.user_regressor is not None:
        return choice.user_regressor.build(None, random_state, role="regressor")
    if is_dynamic(choice.regressor):  # time and speed in front of the rises (``dynamic``)
        return make_dynamic(choice.regressor, random_state)
    if choice.regressor == "gbr":
        return nonlinear.BoostedRiseRegressor(random_state=random_state)
    if choice.regressor == "mlp":
        return nonlinear.MLPRiseRegressor(random_state=random_state)
    return {"ols": RiseRegressor, "ridge": regressors.RidgeRiseRegressor,
            "pls": regressors.PLSRiseRegressor}[choice.regressor]()


def make_pipeline(choice: MethodChoice, k: int, differences: bool = False,
                  similarity: str = DEFAULT_SIMILARITY,
                  random_state: int = DEFAULT_METHOD_SEED) -> Pipeline:
    """differences (optional) -> selector -> regressor; feed it rises (``rises(X, groups)``)."""
    from sklearn.pipeline import Pipeline

    from spindlebench.selection.estimators import PairwiseDifferences

    if is_dynamic(choice.regressor):
        raise SelectionError(f"regressor {choice.regressor!r} is a dynamic model that reads a "
                             "recording's time and speed besides the rises; it runs through "
                             "evaluate, not a Pipeline on rises")
    steps = [("differences", PairwiseDifferences())] if differences else []
    steps += [("select", make_selector(choice, k, similarity, random_state)),
              ("regress", make_regressor(choice, random_state))]
    return Pipeline(steps)


def add_method_arguments(parser) -> None:
    """``--method``, ``--within``, ``--regressor`` and ``--seed`` of a command that runs one
    method (``evaluate``); ``choice_from_args`` reads them back."""
    parser.add_argument("--method", default=DEFAULT_METHOD, metavar="METHOD",
                        help="selection method: a name ('spindlebench methods' lists them; "
                        "default: the paper's closure), a whole label (kmeans+grey+ridge), or "
                        "your selector by import path (mypkg.sel:MySel)")
    parser.add_argument("--within", choices=list(WITHIN), default=DEFAULT_WITHIN,
                        help="choice inside a cluster (cluster methods only)")
    parser.add_argument("--regressor", default=DEFAULT_REGRESSOR, metavar="REGRESSOR",
                        help=f"regression on the selected rises ({', '.join(REGRESSORS)}, or "
                        "your regressor or pipeline by import path)")
    parser.add_argument("--method-param", action="append", default=[], metavar="NAME=VALUE",
                        help="a parameter of the method (or regressor) given by import path; "
                        "repeat for more (values are TOML literals: 3, 0.5, true, \"text\")")
    parser.add_argument("--seed", type=int, default=DEFAULT_METHOD_SEED,
                        help="seed of the seeded methods (fcm, kmeans, stability, ga, gbr, "
                        "mlp, a user's random_state; recorded in --json)")


def method_seed_problem(seed: object) -> str | None:
    """Why ``seed`` cannot seed the methods (None when it can): an integer in
    0 .. ``MAX_METHOD_SEED``."""
    from spindlebench.core.names import MAX_METHOD_SEED

    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= MAX_METHOD_SEED:
        return f"must be an integer from 0 to {MAX_METHOD_SEED} (2**32 - 1), got {seed!r}"
    return None


def choice_from_args(args) -> MethodChoice:
    """The ``MethodChoice`` of ``add_method_arguments``' options (checked: one line)."""
    problem = method_seed_problem(getattr(args, "seed", DEFAULT_METHOD_SEED))
    if problem:
        raise SpindlebenchError(f"--seed: {problem}")
    if len(split_label(args.method)) > 1:  # a whole label in --method
        if args.within != DEFAULT_WITHIN or args.regressor != DEFAULT_REGRESSOR:
            raise SelectionError(f"--method {args.method!r} is a whole label; give --within "
                                 "and --regressor in it, not beside it")
        choice = parse_method(args.method)
    else:
        choice = MethodChoice(args.method, args.within, args.regressor)
    return with_params(choice, getattr(args, "method_param", None))


def listing() -> str:
    """What ``spindlebench methods`` prints: every name with its line."""
    methods = descriptions()
    width = max(len(name) for name in (*methods, *WITHIN, *REGRESSORS))
    lines = ["selection methods (--method; cluster methods first, the paper's is closure):"]
    lines += [f"  {name:<{width}}  {text}" for name, text in methods.items()]
    lines += ["choice inside a cluster (--within; cluster methods only):"]
    lines += [f"  {name:<{width}}  {text}" for name, text in WITHIN.items()]
    lines += ["regressors (--regressor):"]
    lines += [f"  {name:<{width}}  {text}" for name, text in REGRESSORS.items()]
    lines += ["In study files a combination is one label, method[+within][+regressor], "
              "defaults (psi, ols) left out: closure, kmeans+grey, lasso+ridge.",
              "Your own scikit-learn selector, regressor or pipeline by import path: "
              "mypkg.sel:MySel, mypkg.sel:MySel[alpha=0.5]+ridge, "
              "all-candidates+mypkg.reg:MyRegressor (docs/benchmark.md)."]
    return "\n".join(lines)


def select_with(choice: MethodChoice, X, y, k: int, similarity: str = DEFAULT_SIMILARITY,
                names=None, random_state: int = DEFAULT_METHOD_SEED, closure: str = "fast"):
    """Steps 2-5 by any method: a ``select.Selection`` over the candidates ``X``.

    The one front door to selection: ``evaluate`` (hence ``paper``, ``sweep`` and
    ``compensate``) and ``place`` select through here, so every command runs the code the
    scikit-learn estimators wrap. The paper's method is ``select_sensitive_points`` (what
    ``FuzzyClusterSelector`` wraps, ``closure`` choosing the implementation of t(R)); every
    other method is its selector of ``make_selector``.

    ``X`` is the candidate matrix, or a ``pairs.PairCandidates`` (raw rises standing for
    themselves plus every pairwise difference): the paper's method (|psi|, fast closure) then
    selects row-wise without forming the candidates or R (``pairs.select_among_pairs``, same
    clusters and psi, eta to rounding); other methods get the formed matrix.

    Constant candidates are dropped with a ``SelectionWarning`` first, as the paper's
    selector does, so every method sees the same candidates. Fields a method does not have
    are empty: ``similarity``/``closure`` (0 x 0) and ``eta`` (NaN); the clusters of a method
    without clusters are its selected candidates, one each.
    """
    import numpy as np

    from spindlebench.selection.pairs import PairCandidates, select_among_pairs
    from spindlebench.selection.select import (
        Selection,
        _check_inputs,
        select_sensitive_points,
        split_constant,
    )
    from spindlebench.selection.similarity import constant_columns, correlation_with

    if isinstance(X, PairCandidates):
        if choice.is_paper and similarity == DEFAULT_SIMILARITY and closure == "fast":
            return select_among_pairs(X.raw, y, k, X.include_raw, names=names)
        X = X.columns(np.arange(X.n_candidates))
    if choice.method == DEFAULT_METHOD and choice.within == DEFAULT_WITHIN:
        return select_sensitive_points(X, y, k, similarity, closure, names=names)
    X, y = _check_inputs(X, y, k)
    kept, dropped = split_constant(constant_columns(X), names, k, making=f"select {k}")
    kept_names = None if names is None else [str(names[i]) for i in kept]
    X_kept = X[:, kept]
    selector = make_selector(choice, k, similarity, random_state).fit(X_kept, y)
    chosen = getattr(selector, "selected_", None)
    if chosen is None:  # a user's selector: its support mask, in column order
        chosen = np.flatnonzero(np.asarray(selector.get_support(), dtype=bool))
    if len(chosen) == 0:
        raise SelectionError(f"method {choice.method!r} selected no candidate")
    selected = kept[np.asarray(chosen, dtype=np.intp)]
    psi = np.full(X.shape[1], np.nan)
    psi[kept] = _fitted_psi(selector, kept.size)
    if np.isnan(psi[kept]).any():  # not a ClusterSelector's, or a column it left out
        psi[kept] = correlation_with(X_kept, y, kept_names)
    clusters = [kept[c] for c in selector.clusters_] if choice.clustered else \
        [np.array([i]) for i in selected]
    empty = np.empty((0, 0))
    return Selection(kept=kept, dropped=dropped, similarity_source=empty, closure_source=empty,
                     eta=float("nan"), clusters=clusters, psi=psi, selected=selected)


def _fitted_psi(selector, n_kept: int):
    """A built-in ``ClusterSelector``'s ``psi_`` over the kept candidates it was fitted on:
    ``correlation_with`` of the same columns (constant ones are already dropped, so the
    selector keeps all of them), the same bits; NaN where another selector does not have
    it, so the caller computes it (also where the selector's psi_ has a NaN, e.g. a
    column it found constant among fewer)."""
    import numpy as np

    from spindlebench.selection.selectors import ClusterSelector

    psi = getattr(selector, "psi_", None)
    if type(selector) is ClusterSelector and psi is not None and psi.shape == (n_kept,):
        return psi
    return np.full(n_kept, np.nan)


def sensitive_points(choice: MethodChoice, X, y, similarity: str = DEFAULT_SIMILARITY,
                     names=None, closure: str = "fast"):
    """The ``select.SensitivePoints`` through which ``select_with(choice, X, y, k, ...)``
    selects, for every k at once (its k-independent steps done once), or None where
    ``select_with`` takes another way (another method or choice inside clusters, or a
    ``pairs.PairCandidates``)."""
    from spindlebench.selection.pairs import PairCandidates
    from spindlebench.selection.select import SensitivePoints

    if isinstance(X, PairCandidates) or choice.method != DEFAULT_METHOD \
            or choice.within != DEFAULT_WITHIN:
        return None
    return SensitivePoints(X, y, similarity, closure, names=names)


def select_each(choice: MethodChoice, X, y, ks, similarity: str = DEFAULT_SIMILARITY,
                names=None, random_state: int = DEFAULT_METHOD_SEED, closure: str = "fast"):
    """``select_with`` for each k of ``ks``, one ``Selection`` per ``next()``: a generator,
    so a caller can time and catch the warnings of each k on its own.

    The same selections as calling ``select_with`` per k; on the row-wise path (the paper's
    method on a ``pairs.PairCandidates``) the k-independent work, Prim's tree over every
    candidate, is done once for all k (``pairs.PairSelection``), at the first ``next()``.
    """
    from spindlebench.selection.pairs import PairCandidates, PairSelection

    ks = [int(k) for k in ks]
    if (isinstance(X, PairCandidates) and choice.is_paper and similarity == DEFAULT_SIMILARITY
            and closure == "fast"):
        prepared = None
        for k in ks:
            if prepared is None:
                prepared = PairSelection(X.raw, y, max(ks), X.include_raw, names=names)
            yield prepared.select(k)
        return
    for k in ks:
        yield select_with(choice, X, y, k, similarity, names, random_state, closure)


def fit_regressor(regressor: str, X, y, names=None, random_state=DEFAULT_METHOD_SEED):
    """The regression ``regressor`` (``names.REGRESSORS``, or a user's by import path) on
    rises ``X``: a linear one as a ``regression.LinearFit`` (``ols`` is
    ``regression.fit_ols``, what ``RiseRegressor`` wraps; ``ridge``, ``pls`` their estimator of
    ``make_regressor``), any other as a ``regression.EstimatorFit`` around the fitted
    estimator. Refits that are OLS by definition (the placement score, the sweep's oracle)
    call it with ``DEFAULT_REGRESSOR``."""
    import numpy as np

    from spindlebench.selection.regression import EstimatorFit, LinearFit, fit_ols, r2_score

    if regressor == DEFAULT_REGRESSOR:
        return fit_ols(X, y, names=names)
    model = make_regressor(MethodChoice(regressor=regressor), random_state).fit(X, y)
    if regressor not in LINEAR_REGRESSORS:
        return EstimatorFit(model, r2=r2_score(y, EstimatorFit(model, 0.0).predict(X)))
    penalty = None
    if hasattr(model, "alpha_"):  # ridge: its penalty, the grid it was chosen on, its edge
        grid = np.asarray(getattr(model, "alphas_", None) if getattr(model, "alphas_", None)
                          is not None else model.alphas, float)
        penalty = {"alpha": float(model.alpha_), "grid": [float(grid.min()), float(grid.max())],
                   "at_edge": model.alpha_at_edge_}
    return LinearFit(intercept=float(model.intercept_), coefficients=model.coef_,
                     r2=float(model.r2_), penalty=penalty)


def fit_with(choice: MethodChoice, X, y, names=None, random_state=DEFAULT_METHOD_SEED):
    """The regression of ``choice`` on rises ``X`` (``fit_regressor``)."""
    return fit_regressor(choice.regressor, X, y, names, random_state)
