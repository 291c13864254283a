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
from functools import cached_property

import numpy as np
import pandas as pd
from threadpoolctl import threadpool_limits

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import DEFAULT_REGRESSOR
from spindlebench.selection import CandidateSet, SelectionWarning, pairs, rmse
from spindlebench.selection.evaluate import row_wise
from spindlebench.selection.method_registry import METHOD_REGISTRY
from spindlebench.selection.pairs import PairCandidates, check_candidates
from spindlebench.selection.registry import (
    PAPER_METHOD,
    fit_regressor,
    parse_method,
    select_each,
    select_with,
)
from spindlebench.studies.placement.candidates import (
    Run,
    block,
    candidate_columns,
    candidate_set,
    physical_nodes,
    stacked_rises,
)
from spindlebench.studies.placement.placement_file import PlacementStudy
from spindlebench.studies.placement.search import (
    Block,
    exhaustive_search,
    greedy_forward,
    n_subsets,
    usable_candidates,
)

#: Above this many candidates the exhaustive search's Gram matrices (runs x p x p) get too big.
EXHAUSTIVE_MAX_CANDIDATES = 600
#: Greedy forward selection refuses design data of more candidate values than this
#: (candidates x design samples; 8 bytes each, and the search holds about three copies).
FORWARD_SEARCH_MAX_VALUES = 25_000_000


class Design:
    """The design replica's runs for one candidate set, as every method sees them.

    The runs' node rises are stacked once; candidate columns are formed only when a method
    needs them: the paper's selection over nodes and differences works from the node rises
    (``pairs.PairCandidates``), the exhaustive search from the columns of its pool (at most
    ``EXHAUSTIVE_MAX_CANDIDATES``), and only greedy search and the other registry methods
    ask for every column (:attr:`train`, :attr:`valid`, each formed once). With 500 nodes
    and all 124 750 differences the design matrix of 9 runs of 361 samples would take 3.3 GB.
    """

    def __init__(self, study: PlacementStudy, differences: bool, train_runs: Sequence[Run],
                 valid_runs: Sequence[Run]) -> None:
        self.study = study
        self.differences = differences
        self.candidates = candidate_set(study, differences)
        self.train_runs = list(train_runs)
        self.valid_runs = list(valid_runs)
        self.train_rises = stacked_rises(self.train_runs)
        self.train_y = np.concatenate([run.drift_um for run in self.train_runs])

    @property
    def n_candidates(self) -> int:
        return len(self.candidates.names)

    @property
    def n_samples(self) -> int:
        """Design samples: the training and the held-out runs'."""
        return sum(len(run) for run in (*self.train_runs, *self.valid_runs))

    @cached_property
    def train(self) -> Block:
        """Every candidate column of the training runs."""
        return block(self.train_runs, self.differences)

    @cached_property
    def valid(self) -> Block:
        """Every candidate column of the held-out design runs."""
        return block(self.valid_runs, self.differences)

    def selection_input(self) -> np.ndarray | PairCandidates:
        """What the paper's selection is given: the node rises standing for every candidate
        where it runs row-wise (``evaluate.row_wise``, the rule ``evaluate`` follows too),
        else the training matrix (small candidate sets keep the matrix path's bits)."""
        if row_wise(self.candidates, self.study.similarity, "fast"):
            return PairCandidates(self.train_rises)
        return self.train.X

    @cached_property
    def pool(self) -> np.ndarray:
        """Candidates that vary on the training runs (``search.usable_candidates``' mask),
        with differences found a node's differences at a time, without the matrix."""
        if not self.differences:
            return usable_candidates(self.train)
        constant = check_candidates(PairCandidates(self.train_rises), self.candidates.names)
        return np.flatnonzero(~constant)

    @cached_property
    def pool_blocks(self) -> tuple[Block, Block]:
        """(training, held-out) columns of :attr:`pool` only."""
        return (block(self.train_runs, self.differences, self.pool),
                block(self.valid_runs, self.differences, self.pool))

    def check_pairwise(self) -> None:
        """Methods that form an n x n matrix over the candidates (the fuzzy selection where
        it cannot run row-wise, the registry's ``pairwise`` methods) are refused, naming
        the key, above ``pairs.MAX_FORMED_CANDIDATES`` candidates, before any search: they
        would fail on memory (500 nodes with differences: 125 GB per matrix)."""
        n = self.n_candidates
        if n <= pairs.MAX_FORMED_CANDIDATES:
            return
        size = f"{n:,} candidates ({8 * n * n / 1e9:,.1f} GB per n x n matrix, at most " \
               f"{pairs.MAX_FORMED_CANDIDATES:,} candidates)"
        if "fuzzy" in self.study.methods and not row_wise(self.candidates,
                                                          self.study.similarity, "fast"):
            raise SpindlebenchError(
                f"{self.study.path}: key 'placement.similarity': 'fuzzy' with "
                f"{self.study.similarity!r} forms the similarity matrix of {size}; only "
                "abs-pearson selects row-wise over nodes and all their differences")
        for label in self.study.methods:
            if label not in ("fuzzy", "greedy", "exhaustive") and \
                    METHOD_REGISTRY[parse_method(label).method].pairwise:
                raise SpindlebenchError(
                    f"{self.study.path}: key 'placement.methods': {label!r} forms an n x n "
                    f"matrix over {size}; drop it or set with_differences = false")

    def check_forward_search(self) -> None:
        """Greedy search scores every candidate on every design run at every step, from the
        full design matrix: refused, naming the key, where that matrix is too large."""
        values = self.n_candidates * self.n_samples
        if "greedy" in self.study.methods and values > FORWARD_SEARCH_MAX_VALUES:
            raise SpindlebenchError(
                f"{self.study.path}: key 'placement.methods': 'greedy' with "
                f"{'differences' if self.differences else 'nodes'} needs every one of "
                f"{self.n_candidates:,} candidates on {self.n_samples:,} design samples "
                f"({values:,} values, over the limit of {FORWARD_SEARCH_MAX_VALUES:,}); drop "
                "'greedy' or set with_differences = false")


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


def fuzzy_placements(design: Design) -> list[Placement]:
    """The paper's selection on the training run(s), k = m clusters, for every budget m
    (row-wise, Prim's tree is built once for all budgets: ``registry.select_each``)."""
    study, candidates = design.study, design.candidates
    selections = select_each(PAPER_METHOD, design.selection_input(), design.train_y,
                             study.budgets, study.similarity, candidates.names)
    out = []
    for m in study.budgets:
        start = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", SelectionWarning)
            selection = next(selections)
        notes = [str(w.message) for w in caught if "tied similarities" in str(w.message)]
        out.append(_placement(
            "fuzzy", design.differences, m, candidates, selection.selected, math.nan,
            time.perf_counter() - start, "; ".join(notes),
            cluster_sizes=tuple(len(members) for members in selection.clusters),
            psi=tuple(float(v) for v in selection.selected_psi)))
    return out


def forward_search_placements(design: Design) -> list[Placement]:
    """The placement method ``greedy`` (a forward search over the nodes; named so here to keep
    it apart from the selection method ``greedy``, though both run
    ``selection.forward.greedy_forward``): one forward path up to the largest budget; the set
    of size m is its first m steps.

    It needs every candidate column of every design run (each step scores all of them on the
    held-out runs): ``Design.check_forward_search`` refuses designs over
    ``FORWARD_SEARCH_MAX_VALUES`` before any method runs. Refused rather than worked in column
    chunks: the forward path's state (every candidate's training residual, orthogonalised
    against the chosen ones) is itself candidates x training samples, so chunks would have to
    replay every earlier step's projections per chunk to give the same bits, and on 500 nodes
    with differences the search would still cost minutes per step.
    """
    study, differences, candidates = design.study, design.differences, design.candidates
    start = time.perf_counter()
    path = greedy_forward(design.train, design.valid, max(study.budgets), design.pool)
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


def exhaustive_placements(design: Design) -> list[Placement]:
    """Every m-subset where C(n, m) is within the study's limit; else skipped, saying why.
    Only the pool's columns are formed (at most ``EXHAUSTIVE_MAX_CANDIDATES``)."""
    study, differences, candidates = design.study, design.differences, design.candidates
    pool = design.pool
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
        train, valid = design.pool_blocks
        result = exhaustive_search(train, valid, m, np.arange(pool.size))
        out.append(_placement("exhaustive", differences, m, candidates,
                              pool[result.chosen], result.score, time.perf_counter() - start,
                              f"{result.evaluated:,} subsets scored"))
    return out


def find_placements(study: PlacementStudy, train_runs: Sequence[Run],
                    valid_runs: Sequence[Run]) -> list[Placement]:
    """Every method × candidate set × budget the study asks for, on the design runs.

    BLAS and OpenMP run single-threaded here (as in the sweep's ``evaluate_job``): the design
    matrices are small (tens to hundreds of samples), where threads only cost. Measured on
    the tiny study (a busy 2-core machine), scikit-learn's threaded k-means took 24.8 s of
    the 28.5 s search for ``kmeans+grey+diff`` (3 321 candidates, 21 samples), 73x the
    fuzzy method; its idle threads also spin on after each fit, charged to what runs next.
    """
    with threadpool_limits(limits=1):
        return _find_placements(study, train_runs, valid_runs)


def _find_placements(study: PlacementStudy, train_runs: Sequence[Run],
                     valid_runs: Sequence[Run]) -> list[Placement]:
    designs = [Design(study, differences, train_runs, valid_runs)
               for differences in study.with_differences]
    for design in designs:  # before any search runs
        design.check_forward_search()
        design.check_pairwise()
    placements: list[Placement] = []
    while designs:  # each design's formed columns go with it
        design = designs.pop(0)
        if "fuzzy" in study.methods:
            placements += fuzzy_placements(design)
        if "greedy" in study.methods:
            placements += forward_search_placements(design)
        if "exhaustive" in study.methods:
            placements += exhaustive_placements(design)
        for label in study.methods:
            if label not in ("fuzzy", "greedy", "exhaustive"):
                placements += method_placements(design, label)
    return placements


def method_placements(design: Design, label: str) -> list[Placement]:
    """A selection method of the registry (``spindlebench methods``) on the training run(s),
    m inputs per budget; scored like every placement (OLS refit). These methods are given
    every candidate column of the training run(s)."""
    study, differences, candidates = design.study, design.differences, design.candidates
    choice = parse_method(label)
    out = []
    for m in study.budgets:
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SelectionWarning)
                selection = select_with(choice, design.train.X, design.train.y, m,
                                        study.similarity, candidates.names)
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
    train = block(train_runs, placement.differences, placement.columns)
    fit = fit_regressor(DEFAULT_REGRESSOR, train.X, train.y)  # the same OLS for every method
    rows = []
    for run in test_runs:
        X = candidate_columns(run.node_rises, placement.differences, placement.columns)
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
