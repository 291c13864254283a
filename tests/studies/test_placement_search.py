"""Placement searches on synthetic test data (made here, not from the FMU): the greedy path's
scores equal a direct least-squares refit, greedy is really greedy, the exhaustive search
finds the known optimum, and the schematic knows every node of the model."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.selection import CandidateSet
from spindlebench.studies.placement.candidates import physical_nodes
from spindlebench.studies.placement.placement_file import fmu_nodes
from spindlebench.studies.placement.schematic import node_positions
from spindlebench.studies.placement.search import (
    Block,
    exhaustive_search,
    greedy_forward,
    subset_batches,
    validation_score,
)


def synthetic_runs(rng, n_runs, n_samples, n_nodes, true_columns, coefficients, noise=0.05):
    """Test data: node rises as mixtures of a few smooth heating curves, drift linear in a
    known subset of them plus noise; stacked run by run like the study's blocks."""
    X, y = [], []
    t = np.linspace(0.0, 1.0, n_samples)[:, None]
    for _ in range(n_runs):
        tau = rng.uniform(0.1, 2.0, size=4)
        curves = 1.0 - np.exp(-t / tau)  # four heating time constants
        nodes = curves @ rng.uniform(0.0, 3.0, size=(4, n_nodes))
        nodes += 0.02 * rng.standard_normal(nodes.shape)
        nodes -= nodes[0]
        X.append(nodes)
        y.append(nodes[:, true_columns] @ coefficients + noise * rng.standard_normal(n_samples))
    return Block(np.vstack(X), np.concatenate(y), np.arange(n_runs) * n_samples)


def lstsq_score(train: Block, valid: Block, columns) -> float:
    """Independent reference: lstsq with a column of ones, mean per-run RMSE."""
    columns = list(columns)
    A = np.column_stack([np.ones(train.X.shape[0]), train.X[:, columns]])
    coef, *_ = np.linalg.lstsq(A, train.y, rcond=None)
    predicted = coef[0] + valid.X[:, columns] @ coef[1:]
    runs = np.split(valid.y - predicted, valid.starts[1:])
    return float(np.mean([np.sqrt(np.mean(r**2)) for r in runs]))


def with_all_differences(block: Block) -> Block:
    first, second = np.triu_indices(block.X.shape[1], k=1)
    X = np.hstack([block.X, block.X[:, first] - block.X[:, second]])
    return Block(X, block.y, block.starts)


@pytest.mark.parametrize("differences", [False, True])
def test_greedy_scores_equal_a_direct_refit_of_the_chosen_set(differences):
    rng = np.random.default_rng(3)
    train = synthetic_runs(rng, 1, 90, 9, [1, 4, 6], np.array([2.0, -1.5, 0.7]))
    valid = synthetic_runs(rng, 4, 70, 9, [1, 4, 6], np.array([2.0, -1.5, 0.7]))
    if differences:  # 9 nodes + 36 differences: many exactly collinear combinations
        train, valid = with_all_differences(train), with_all_differences(valid)
    path = greedy_forward(train, valid, 6)
    assert len(path.chosen) == 6 and len(set(path.chosen)) == 6
    for size in range(1, 7):
        direct = lstsq_score(train, valid, path.chosen[:size])
        assert path.scores[size - 1] == pytest.approx(direct, rel=1e-7, abs=1e-10)
        assert validation_score(train, valid, path.chosen[:size]) == pytest.approx(direct,
                                                                                   rel=1e-9)


def test_greedy_adds_the_best_candidate_at_every_step():
    rng = np.random.default_rng(5)
    train = synthetic_runs(rng, 1, 60, 8, [0, 5], np.array([1.0, 3.0]), noise=0.2)
    valid = synthetic_runs(rng, 3, 50, 8, [0, 5], np.array([1.0, 3.0]), noise=0.2)
    path = greedy_forward(train, valid, 4)
    for size in range(1, 5):
        prefix = path.chosen[: size - 1]
        options = {j: lstsq_score(train, valid, [*prefix, j]) for j in range(8) if j not in prefix}
        best = min(options, key=options.get)
        assert path.chosen[size - 1] == best
        assert path.scores[size - 1] == pytest.approx(options[best], rel=1e-7)


def test_greedy_never_picks_a_difference_already_spanned():
    rng = np.random.default_rng(8)
    base = synthetic_runs(rng, 1, 80, 5, [0, 1], np.array([1.0, -1.0]), noise=0.0)
    valid = with_all_differences(synthetic_runs(rng, 2, 80, 5, [0, 1], np.array([1.0, -1.0]),
                                                noise=0.0))
    train = with_all_differences(base)
    path = greedy_forward(train, valid, 15)
    # 5 nodes span every difference: at most 5 independent directions exist.
    assert len(path.chosen) == 5
    rank = np.linalg.matrix_rank(train.X[:, path.chosen] - train.X[:, path.chosen].mean(0))
    assert rank == 5
    assert np.all(np.isfinite(path.scores))


def test_exhaustive_finds_the_known_optimum():
    rng = np.random.default_rng(11)
    truth = [2, 5, 8]
    train = synthetic_runs(rng, 1, 120, 10, truth, np.array([1.5, -2.0, 1.0]), noise=0.01)
    valid = synthetic_runs(rng, 5, 80, 10, truth, np.array([1.5, -2.0, 1.0]), noise=0.01)
    result = exhaustive_search(train, valid, 3, chunk=17)
    assert sorted(result.chosen) == truth
    assert result.evaluated == 120  # C(10, 3)
    brute = min(itertools.combinations(range(10), 3),
                key=lambda c: lstsq_score(train, valid, c))
    assert list(brute) == truth
    assert result.score == pytest.approx(lstsq_score(train, valid, truth), rel=1e-6)


def test_exhaustive_matches_brute_force_where_the_optimum_is_not_obvious():
    rng = np.random.default_rng(2)
    train = synthetic_runs(rng, 1, 50, 9, [0, 3, 7], np.array([1.0, 1.0, -2.0]), noise=0.5)
    valid = synthetic_runs(rng, 3, 40, 9, [1, 3, 6], np.array([1.0, 1.0, -2.0]), noise=0.5)
    for size in (1, 2, 3):
        result = exhaustive_search(train, valid, size)
        scores = {c: lstsq_score(train, valid, c) for c in itertools.combinations(range(9), size)}
        best = min(scores, key=scores.get)
        assert tuple(result.chosen) == best
        assert result.score == pytest.approx(scores[best], rel=1e-6)
        path = greedy_forward(train, valid, size)
        assert result.score <= path.scores[-1] + 1e-9  # the optimum is never worse than greedy


@pytest.mark.parametrize(("n", "size", "chunk"), [(6, 1, 4), (6, 2, 4), (9, 4, 7), (12, 5, 50),
                                                 (5, 5, 3)])
def test_subset_batches_are_the_combinations_in_order(n, size, chunk):
    got = np.vstack(list(subset_batches(n, size, chunk)))
    expected = np.array(list(itertools.combinations(range(n), size)))
    np.testing.assert_array_equal(got, expected)


def test_a_difference_needs_both_of_its_nodes():
    candidates = CandidateSet(("a", "b", "c"), True)  # a, b, c, a-b, a-c, b-c
    assert physical_nodes(candidates, [0, 5]) == ["a", "b", "c"]
    assert physical_nodes(candidates, [4, 0]) == ["a", "c"]


def test_schematic_places_every_node_of_the_model_on_its_part():
    nodes = fmu_nodes(DEFAULT_FMU)
    positions, unknown = node_positions(nodes)
    assert unknown == [] and set(positions) == set(nodes)
    assert len(set(positions.values())) == len(nodes)  # no two nodes drawn on one spot
    # The shaft's first node sits at the nose, below its last; the column grows upwards.
    shaft = sorted((n for n in nodes if n.startswith("spindle_shaft_")),
                   key=lambda n: int(n.rsplit("_", 1)[1]))
    assert positions[shaft[0]][1] < positions[shaft[-1]][1]
    assert positions["column_1"][1] < positions["spindle_motor"][1]
    # A node the drawing does not know is still drawn, in the strip beneath the machine.
    positions, unknown = node_positions([*nodes, "coolant_tank"])
    assert unknown == ["coolant_tank"] and positions["coolant_tank"][1] < 0


def test_findings_name_the_budgets_a_method_wins():
    from spindlebench.studies.placement.placement_report import findings

    rows = [  # greedy wins at m = 3 only; at m = 2 fuzzy is better; differences help at m = 2
        ("fuzzy", 2, 0.8), ("greedy", 2, 0.9), ("fuzzy", 3, 0.8), ("greedy", 3, 0.7),
        ("fuzzy+diff", 2, 0.6), ("fuzzy+diff", 3, 0.9),
    ]
    table = pd.DataFrame([{"label": label, "method": label, "m": m, "test_mean_rmse_um": rmse,
                           "design_rmse_um": rmse, "variables": "a;b", "n_sensors": 2}
                          for label, m, rmse in rows])
    text = "\n".join(findings(table, honest=True))
    assert "- greedy beats fuzzy at 1 of 2 budget(s) (m = 3) on the test days." in text
    assert "- fuzzy+diff beats fuzzy at 1 of 2 budget(s) (m = 2) on the test days." in text
