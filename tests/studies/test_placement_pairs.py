"""The placement study without the full candidate matrix, on small synthetic fields (made
here, not from the FMU): the fuzzy selection from the node rises gives the bits the matrix
way gave, the exhaustive search on its pool's columns the same optimum and score, the
scoring columns the bits of ``CandidateSet.matrix``, and greedy search over too large a
design is refused in one line naming the key and the limit."""

from __future__ import annotations

import dataclasses
import sys
import warnings

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.core.errors import SpindlebenchError
from spindlebench.selection import SelectionWarning, pairs
from spindlebench.selection.registry import PAPER_METHOD, select_each, select_with
from spindlebench.selection.regression import rises
from spindlebench.studies.family.experiments import experiments
from spindlebench.studies.placement import placements
from spindlebench.studies.placement.candidates import Run, candidate_columns, candidate_set
from spindlebench.studies.placement.placement_file import load_placement_study
from spindlebench.studies.placement.placements import (
    Design,
    exhaustive_placements,
    find_placements,
    fuzzy_placements,
)
from spindlebench.studies.placement.search import Block, exhaustive_search, usable_candidates

TINY = REPO / "scenarios" / "studies" / "tiny_placement.toml"


FIELDS: dict[int, np.ndarray] = {}  # id(run) -> its node temperatures (degC)


def field_runs(study, n_nodes: int, n_runs: int, n_samples: int, seed: int = 0) -> list[Run]:
    """Runs of a synthetic field: warm-up curves, ambient wander, 0.1 K quantisation (so
    there are ties), one node that never changes and one that copies another (a constant
    difference), drift from a few nodes. ``FIELDS`` keeps each run's temperatures."""
    rng = np.random.default_rng(seed)
    experiment = experiments(study.family)[0]
    t = np.linspace(0.0, 1.0, n_samples)[:, None]
    out = []
    for _ in range(n_runs):
        tau = rng.uniform(0.05, 1.5, n_nodes)
        gain = rng.uniform(0.2, 8.0, n_nodes)
        ambient = np.cumsum(rng.normal(0, 0.03, n_samples))[:, None]
        T = 20 + ambient + gain * (1 - np.exp(-t / tau)) + rng.normal(0, 0.05,
                                                                      (n_samples, n_nodes))
        T = np.round(T / 0.1) * 0.1
        T[:, 1] = 21.0  # a node that never changes
        T[:, 3] = T[:, 2] + 0.5  # a constant offset: the difference n2-n3 is constant
        drift = 4.0 * T[:, 0] - 2.5 * T[:, n_nodes // 2] + rng.normal(0, 0.3, n_samples)
        out.append(Run(1, experiment, rises(T), drift - drift[0], drift - drift[0]))
        FIELDS[id(out[-1])] = T
    return out


@pytest.fixture(scope="module")
def small_study():
    study = load_placement_study(TINY)
    nodes = tuple(f"n{i}" for i in range(14))
    return dataclasses.replace(study, nodes=nodes, budgets=(2, 3, 4), with_differences=(True,),
                               methods=("fuzzy", "exhaustive"), exhaustive_limit=10**6)


def matrix_way(study, runs: list[Run], differences: bool) -> Block:
    """The design matrix as the study formed it before: every candidate of every run from a
    DataFrame of the node readings through ``CandidateSet.matrix``."""
    candidates = candidate_set(study, differences)
    frames = [pd.DataFrame(FIELDS[id(run)], columns=list(study.nodes)) for run in runs]
    X = np.vstack([candidates.matrix(frame) for frame in frames])
    y = np.concatenate([run.drift_um for run in runs])
    return Block(X, y, np.cumsum([0] + [len(run) for run in runs[:-1]]))


def fuzzy_fields(placement) -> tuple:
    return (placement.columns, placement.cluster_sizes, placement.psi, placement.note)


@pytest.mark.parametrize("row_wise", [False, True])
def test_fuzzy_from_node_rises_has_the_matrix_ways_bits(small_study, monkeypatch, row_wise):
    """Below ``ROW_WISE_ABOVE`` both ways form R; above it (forced here on 119 candidates)
    the study now hands the node rises to the row-wise selection, where the matrix way had
    it detect them in the formed matrix: same columns, cluster sizes, psi and notes."""
    if row_wise:
        monkeypatch.setattr(pairs, "ROW_WISE_ABOVE", 0)
        monkeypatch.setattr(sys.modules["spindlebench.selection.evaluate"], "ROW_WISE_ABOVE", 0)
    runs = field_runs(small_study, 14, 3, 60)
    design = Design(small_study, True, runs[:1], runs[1:])
    assert isinstance(design.selection_input(), pairs.PairCandidates) is row_wise
    new = fuzzy_placements(design)
    assert "train" not in design.__dict__ or not row_wise  # the matrix was never formed
    train = matrix_way(small_study, runs[:1], True)
    names = candidate_set(small_study, True).names
    for placement, m in zip(new, small_study.budgets, strict=True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SelectionWarning)
            old = select_with(PAPER_METHOD, train.X, train.y, m, names=names)
        assert placement.columns == tuple(int(c) for c in old.selected)
        assert placement.cluster_sizes == tuple(len(c) for c in old.clusters)
        assert placement.psi == tuple(float(v) for v in old.selected_psi)  # bit for bit


def test_select_each_builds_one_tree_for_every_k(small_study, monkeypatch):
    """The row-wise selections of several k from one Prim's tree equal one selection per k."""
    runs = field_runs(small_study, 14, 1, 80, seed=3)
    source = pairs.PairCandidates(runs[0].node_rises)
    built = []
    original = pairs.maximum_spanning_tree_of_pairs
    monkeypatch.setattr(pairs, "maximum_spanning_tree_of_pairs",
                        lambda *a: built.append(1) or original(*a))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        each = list(select_each(PAPER_METHOD, source, runs[0].drift_um, [2, 5, 9]))
        assert len(built) == 1
        for k, selection in zip([2, 5, 9], each, strict=True):
            alone = select_with(PAPER_METHOD, source, runs[0].drift_um, k)
            assert np.array_equal(selection.selected, alone.selected)
            assert all(np.array_equal(a, b) for a, b in
                       zip(selection.clusters, alone.clusters, strict=True))
            assert np.array_equal(selection.psi, alone.psi, equal_nan=True)
            assert selection.eta == alone.eta


def test_exhaustive_on_its_pool_columns_equals_the_full_matrix(small_study):
    """The pool (varying candidates, found without the matrix: the constant node and the
    constant difference are out) and the optimum and score of every budget."""
    study = dataclasses.replace(small_study, nodes=small_study.nodes[:10], budgets=(2, 3))
    runs = field_runs(study, 10, 4, 50, seed=1)
    design = Design(study, True, runs[:1], runs[1:])
    train, valid = matrix_way(study, runs[:1], True), matrix_way(study, runs[1:], True)
    pool = usable_candidates(train)
    names = candidate_set(study, True).names
    assert np.array_equal(design.pool, pool)
    assert {"n1", "n2-n3"} <= {names[i] for i in set(range(len(names))) - set(pool)}
    for placement, m in zip(exhaustive_placements(design), study.budgets, strict=True):
        result = exhaustive_search(train, valid, m, pool)
        assert placement.columns == tuple(result.chosen)
        assert placement.search_score_um == result.score  # bit for bit
    assert "train" not in design.__dict__ and "valid" not in design.__dict__


@pytest.mark.parametrize("differences", [False, True])
def test_scoring_columns_are_candidate_set_matrix_bits(small_study, differences):
    run = field_runs(small_study, 14, 1, 30, seed=2)[0]
    candidates = candidate_set(small_study, differences)
    columns = [0, 5, len(candidates.names) - 1, 13]
    frame = pd.DataFrame(FIELDS[id(run)], columns=list(small_study.nodes))
    expected = candidates.matrix(frame, columns)
    assert np.array_equal(candidate_columns(run.node_rises, differences, columns), expected)
    assert np.array_equal(candidate_columns(run.node_rises, differences),
                          candidates.matrix(frame))


def test_greedy_over_too_large_a_design_is_refused_in_one_line(small_study, monkeypatch):
    study = dataclasses.replace(small_study, methods=("fuzzy", "greedy"),
                                with_differences=(False, True))
    runs = field_runs(study, 14, 3, 40)
    monkeypatch.setattr(placements, "FORWARD_SEARCH_MAX_VALUES", 14 * 120)  # nodes pass, 105 do not
    with pytest.raises(SpindlebenchError) as caught:
        find_placements(study, runs[:1], runs[1:])
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{study.path}: key 'placement.methods': 'greedy' with "
                              "differences")
    assert "105 candidates on 120 design samples (12,600 values, over the limit of 1,680)" \
        in message


def test_pair_candidates_drop_the_constant_ones_the_matrix_way_does():
    """A candidate that varies by 4e-7 K next to one outlier cell of 1e6 K: the matrix rule
    (``similarity.constant_columns``) judges it against the median range and keeps it; the
    row-wise check must too (it judged against the largest range and dropped it)."""
    from spindlebench.selection.differences import pairwise_differences
    from spindlebench.selection.similarity import constant_columns

    rng = np.random.default_rng(5)
    raw = rng.normal(0.0, 1.0, (40, 6))
    raw[:, 2] = 1e-8 * np.arange(40)  # tiny but real variation
    raw[7, 5] = 1e6  # one sentinel cell
    X = np.hstack([raw, pairwise_differences(raw)])
    expected = constant_columns(X)
    assert not expected[2]
    assert np.array_equal(pairs.check_candidates(pairs.PairCandidates(raw), None), expected)


def test_methods_that_form_an_n_by_n_matrix_are_refused_above_its_limit(small_study,
                                                                         monkeypatch):
    """With 105 candidates over a limit of 50 (patched): 'ward' is refused before any
    search, naming the key; k-means (candidates as points) and the row-wise fuzzy are not;
    the fuzzy selection with the literal similarity is refused naming placement.similarity."""
    monkeypatch.setattr(pairs, "MAX_FORMED_CANDIDATES", 50)
    monkeypatch.setattr(sys.modules["spindlebench.selection.evaluate"], "ROW_WISE_ABOVE", 0)
    runs = field_runs(small_study, 14, 2, 40)
    study = dataclasses.replace(small_study, methods=("fuzzy", "kmeans", "ward"),
                                budgets=(2,))
    with pytest.raises(SpindlebenchError) as caught:
        find_placements(study, runs[:1], runs[1:])
    assert str(caught.value) == (
        f"{study.path}: key 'placement.methods': 'ward' forms an n x n matrix over 105 "
        "candidates (0.0 GB per n x n matrix, at most 50 candidates); drop it or set "
        "with_differences = false")
    found = find_placements(dataclasses.replace(study, methods=("fuzzy", "kmeans")),
                            runs[:1], runs[1:])
    assert [p.found for p in found] == [True, True]
    literal = dataclasses.replace(study, methods=("fuzzy",), similarity="literal")
    with pytest.raises(SpindlebenchError, match=r"key 'placement.similarity': 'fuzzy' with "
                       r"'literal' forms the similarity matrix of 105 candidates"):
        find_placements(literal, runs[:1], runs[1:])
