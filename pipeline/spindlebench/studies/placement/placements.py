"""Finding placements on the design runs and scoring them on every replica.

Every method chooses columns of the same candidate set on the same design data (replica 1):
``fuzzy`` looks only at the training run(s), as the paper does; ``greedy`` and
``exhaustive`` also look at the design replica's held-out runs (their objective is the mean
validation RMSE there). All placements are then scored the same way, by
:func:`score_placement`: refit OLS on the rises of the chosen candidates on a replica's
training run(s), predict that replica's held-out runs. On the design replica this is the
number the searches optimised (optimistic for them); on the test replicas (fresh days) it is
an honest estimate for every method.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from spindlebench.errors import SpindlebenchError
from spindlebench.names import DEFAULT_REGRESSOR
from spindlebench.selection import CandidateSet, SelectionWarning, rmse
from spindlebench.selection.registry import (
    PAPER_METHOD,
    fit_regressor,
    parse_method,
    select_with,
)
from spindlebench.studies.placement.candidates import (
    Run,
    block,
    candidate_set,
    physical_nodes,
)
from spindlebench.studies.placement.search import (
    Block,
    exhaustive_search,
    greedy_forward,
    n_subsets,
    usable_candidates,
)
from spindlebench.studies.placement.study import PlacementStudy

#: Above this many candidates the exhaustive search's Gram matrices (runs x p x p) get too big.
EXHAUSTIVE_MAX_CANDIDATES = 600


@dataclass(frozen=True)
class Placement:
    """One method's choice for one budget (``columns`` None when the method was skipped)."""

    method: str
    differences: bool
    budget: int
    columns: tuple[int, ...] | None
    variables: tuple[str, ...]
    nodes: tuple[str, ...]
    search_score_um: float  # the search's own objective value (NaN for fuzzy and skipped)
    seconds: float
    note: str = ""
    cluster_sizes: tuple[int, ...] = ()  # fuzzy only: members of each cluster of the cut
    psi: tuple[float, ...] = ()  # fuzzy only: correlation of each pick with the drift

    @property
    def label(self) -> str:
        return f"{self.method}+diff" if self.differences else self.method

    @property
    def found(self) -> bool:
        return self.columns is not None


def _placement(method: str, differences: bool, budget: int, candidates: CandidateSet,
               columns: Sequence[int],
               score: float, seconds: float, note: str = "", **fuzzy) -> Placement:
    names = candidates.names
    columns = tuple(int(c) for c in columns)
    return Placement(method, differences, budget, columns, tuple(names[c] for c in columns),
                     tuple(physical_nodes(candidates, columns)), score, seconds, note, **fuzzy)


def _skipped(method: str, differences: bool, budget: int, note: str) -> Placement:
    return Placement(method, differences, budget, None, (), (), math.nan, 0.0, note)


def fuzzy_placements(study: PlacementStudy, differences: bool,
                     train: Block) -> list[Placement]:
    """The paper's selection on the training run(s), k = m clusters."""
    candidates = candidate_set(study, differences)
    out = []
    for m in study.budgets:
        start = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", SelectionWarning)
            selection = select_with(PAPER_METHOD, train.X, train.y, m, study.similarity,
                                    candidates.names)
        notes = [str(w.message) for w in caught if "tied similarities" in str(w.message)]
        out.append(_placement(
            "fuzzy", differences, m, candidates, selection.selected, math.nan,
            time.perf_counter() - start, "; ".join(notes),
            cluster_sizes=tuple(len(members) for members in selection.clusters),
            psi=tuple(float(v) for v in selection.selected_psi)))
    return out


def greedy_placements(study: PlacementStudy, differences: bool, train: Block,
                      valid: Block) -> list[Placement]:
    """One forward path up to the largest budget; the set of size m is its first m steps."""
    candidates = candidate_set(study, differences)
    start = time.perf_counter()
    path = greedy_forward(train, valid, max(study.budgets), usable_candidates(train))
    seconds = time.perf_counter() - start
    out = []
    for m in study.budgets:
        if m > len(path.chosen):
            out.append(_skipped("greedy", differences, m, f"only {len(path.chosen)} "
                                "independent candidates"))
            continue
        out.append(_placement("greedy", differences, m, candidates, path.chosen[:m],
                              path.scores[m - 1], seconds, "nested: one forward path"))
    return out


def exhaustive_placements(study: PlacementStudy, differences: bool, train: Block,
                          valid: Block) -> list[Placement]:
    """Every m-subset where C(n, m) is within the study's limit; else skipped, saying why."""
    candidates = candidate_set(study, differences)
    pool = usable_candidates(train)
    out = []
    for m in study.budgets:
        count = n_subsets(pool.size, m)
        if count > study.exhaustive_limit:
            out.append(_skipped("exhaustive", differences, m,
                                f"skipped: C({pool.size}, {m}) = {count:,} subsets > "
                                f"exhaustive_limit {study.exhaustive_limit:,}"))
            continue
        if pool.size > EXHAUSTIVE_MAX_CANDIDATES:
            out.append(_skipped("exhaustive", differences, m,
                                f"skipped: {pool.size} candidates > "
                                f"{EXHAUSTIVE_MAX_CANDIDATES} (Gram matrices too large)"))
            continue
        start = time.perf_counter()
        result = exhaustive_search(train, valid, m, pool)
        out.append(_placement("exhaustive", differences, m, candidates, result.chosen,
                              result.score, time.perf_counter() - start,
                              f"{result.evaluated:,} subsets scored"))
    return out


def find_placements(study: PlacementStudy, train_runs: Sequence[Run],
                    valid_runs: Sequence[Run]) -> list[Placement]:
    """Every method × candidate set × budget the study asks for, on the design runs."""
    placements: list[Placement] = []
    for differences in study.with_differences:
        candidates = candidate_set(study, differences)
        train = block(train_runs, candidates)
        valid = block(valid_runs, candidates)
        if "fuzzy" in study.methods:
            placements += fuzzy_placements(study, differences, train)
        if "greedy" in study.methods:
            placements += greedy_placements(study, differences, train, valid)
        if "exhaustive" in study.methods:
            placements += exhaustive_placements(study, differences, train, valid)
        for label in study.methods:
            if label not in ("fuzzy", "greedy", "exhaustive"):
                placements += method_placements(study, differences, train, label)
    return placements


def method_placements(study: PlacementStudy, differences: bool, train: Block,
                      label: str) -> list[Placement]:
    """A selection method of the registry (``spindlebench methods``) on the training run(s),
    m inputs per budget; scored like every placement (OLS refit)."""
    candidates = candidate_set(study, differences)
    choice = parse_method(label)
    out = []
    for m in study.budgets:
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SelectionWarning)
                selection = select_with(choice, train.X, train.y, m, study.similarity,
                                        candidates.names)
        except SpindlebenchError as exc:
            out.append(_skipped(choice.label, differences, m, " ".join(str(exc).split())))
            continue
        out.append(_placement(choice.label, differences, m, candidates, selection.selected,
                              math.nan, time.perf_counter() - start))
    return out


def score_placement(study: PlacementStudy, placement: Placement, train_runs: Sequence[Run],
                    test_runs: Sequence[Run]) -> list[dict[str, object]]:
    """Refit on ``train_runs`` and score every run of ``test_runs``: one row per run."""
    assert placement.columns is not None
    candidates = candidate_set(study, placement.differences)
    train = block(train_runs, candidates, placement.columns)
    fit = fit_regressor(DEFAULT_REGRESSOR, train.X, train.y)  # the same OLS for every method
    rows = []
    for run in test_runs:
        X = candidates.matrix(run.nodes, placement.columns)
        predicted = fit.predict(X)
        rows.append({"experiment": run.experiment.id, "season": run.experiment.season,
                     "month": run.experiment.month, "speed_rpm": run.experiment.speed_rpm,
                     "rmse_um": rmse(run.drift_um, predicted),
                     "rmse_true_um": rmse(run.true_drift_um, predicted)})
    return rows


def score_all(study: PlacementStudy, placements: Sequence[Placement],
              runs: dict[int, tuple[list[Run], list[Run]]]) -> pd.DataFrame:
    """Tidy scores: placement × replica × held-out run (``role`` design or test)."""
    rows = []
    for placement in placements:
        if not placement.found:
            continue
        for replica, (train_runs, test_runs) in runs.items():
            role = "design" if replica == study.design_replica else "test"
            for row in score_placement(study, placement, train_runs, test_runs):
                rows.append({"label": placement.label, "method": placement.method,
                             "differences": placement.differences, "m": placement.budget,
                             "replica": replica, "role": role, **row})
    return pd.DataFrame(rows)


def placements_table(study: PlacementStudy, placements: Sequence[Placement],
                     scores: pd.DataFrame) -> pd.DataFrame:
    """One row per placement: sensors, design and test RMSE (mean, worst, per season)."""
    seasons = list(dict.fromkeys(study.family.climate.season_of(m)
                                 for m in study.family.months))
    test_role = "test" if len(study.test_replicas) and \
        study.test_replicas != (study.design_replica,) else "design"
    rows = []
    for placement in placements:
        row: dict[str, object] = {
            "label": placement.label, "method": placement.method,
            "differences": placement.differences, "m": placement.budget,
            "variables": ";".join(placement.variables), "sensors": ";".join(placement.nodes),
            "n_sensors": len(placement.nodes), "design_rmse_um": np.nan,
            "test_mean_rmse_um": np.nan, "test_worst_rmse_um": np.nan,
        }
        row.update({f"test_{season}_rmse_um": np.nan for season in seasons})
        if placement.found and len(scores):
            mine = scores[(scores["label"] == placement.label)
                          & (scores["m"] == placement.budget)]
            design = mine[mine["role"] == "design"]
            test = mine[mine["role"] == test_role]
            row["design_rmse_um"] = design["rmse_um"].mean()
            row["test_mean_rmse_um"] = test["rmse_um"].mean()
            row["test_worst_rmse_um"] = test["rmse_um"].max()
            for season, at in test.groupby("season", sort=False):
                row[f"test_{season}_rmse_um"] = at["rmse_um"].mean()
            row["test_mean_rmse_true_um"] = test["rmse_true_um"].mean()
        # no search time here: the table is reproducible bytes; timings go to the log
        row.update({"search_score_um": placement.search_score_um, "note": placement.note})
        rows.append(row)
    table = pd.DataFrame(rows)
    order = ["label", "method", "differences", "m", "variables", "sensors", "n_sensors",
             "design_rmse_um", "test_mean_rmse_um", "test_worst_rmse_um",
             *[f"test_{s}_rmse_um" for s in seasons], "test_mean_rmse_true_um",
             "search_score_um", "note"]
    for column in order:
        if column not in table:
            table[column] = np.nan
    return table.loc[:, order]
