"""Row-wise selection over sensors plus differences (selection.pairs) against the matrix path."""

import dataclasses
import importlib
import warnings

import numpy as np
import pytest
from selection_data import real_temperatures, synthetic_experiment
from spindlebench.selection.closure import maximum_spanning_tree
from spindlebench.selection.cut import cut_tree_for_clusters
from spindlebench.selection.differences import difference_names, pairwise_differences
from spindlebench.selection.errors import SelectionError, SelectionWarning
from spindlebench.selection.evaluate import evaluate
from spindlebench.selection.pairs import (
    PairCandidates,
    PairGeometry,
    check_candidates,
    maximum_spanning_tree_of_pairs,
    select_among_pairs,
    standardized_centre,
)
from spindlebench.selection.select import select_sensitive_points
from spindlebench.selection.similarity import LITERAL_MAX_CANDIDATES, similarity_matrix

# the package exports the function ``evaluate`` under the module's name
evaluate_module = importlib.import_module("spindlebench.selection.evaluate")
pairs_module = importlib.import_module("spindlebench.selection.pairs")


@pytest.fixture(autouse=True, params=["numpy-rows", "compiled"])
def prim_path(request, monkeypatch):
    """Every test twice: Prim's loop in NumPy rows (small candidate sets) and compiled
    (``prim_kernel``, large ones; here forced for every size, squeezes included)."""
    if request.param == "compiled":
        monkeypatch.setattr(pairs_module, "COMPILED_ABOVE", 0)
    return request.param


def warm_up(n_sensors: int, n_samples: int, seed: int) -> np.ndarray:
    """Rises of sensors with their own time constants and gains, ambient wander, noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_samples)[:, None]
    tau = rng.uniform(0.05, 0.8, n_sensors)
    gain = rng.uniform(0.5, 15.0, n_sensors)
    ambient = np.cumsum(rng.normal(0, 0.02, n_samples))[:, None]
    raw = ambient + gain * (1 - np.exp(-t / tau)) + rng.normal(0, 0.03, (n_samples, n_sensors))
    return raw - raw[0]


def both_ways(raw, y, k, include_raw=True):
    """(matrix path, row-wise path) with the warnings each gave."""
    diffs = pairwise_differences(raw)
    X = np.hstack([raw, diffs]) if include_raw else diffs
    with warnings.catch_warnings(record=True) as matrix_warnings:
        warnings.simplefilter("always")
        matrix = select_sensitive_points(X, y, k)
    with warnings.catch_warnings(record=True) as row_warnings:
        warnings.simplefilter("always")
        rows = select_among_pairs(raw, y, k, include_raw=include_raw)
    return (matrix, [str(w.message) for w in matrix_warnings],
            rows, [str(w.message) for w in row_warnings])


def assert_same(matrix, rows):
    """Same clusters, picks and dropped candidates; eta, psi and R to rounding.

    A pick is the same unless two members of its cluster have |psi| equal to rounding (an
    exact copy with an offset): then either is the strongest, in either path."""
    assert len(matrix.clusters) == len(rows.clusters)
    for a, b in zip(matrix.clusters, rows.clusters, strict=True):
        np.testing.assert_array_equal(a, b)
    strength = np.abs(matrix.psi)
    for members, a, b in zip(matrix.clusters, matrix.selected, rows.selected, strict=True):
        tied = members[np.abs(strength[members] - strength[a]) <= 1e-12]
        assert b == a or (tied.size > 1 and b in tied)
    np.testing.assert_array_equal(matrix.kept, rows.kept)
    np.testing.assert_array_equal(matrix.dropped, rows.dropped)
    assert rows.eta == pytest.approx(matrix.eta, abs=1e-12)
    np.testing.assert_array_equal(np.isnan(matrix.psi), np.isnan(rows.psi))
    np.testing.assert_allclose(rows.psi, matrix.psi, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rows.similarity, matrix.similarity, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rows.closure, matrix.closure, rtol=0, atol=1e-12)


@pytest.mark.parametrize("n_sensors, n_samples, seed", [(3, 50, 0), (8, 200, 1), (25, 360, 2)])
@pytest.mark.parametrize("include_raw", [True, False])
def test_random_warm_ups_give_the_matrix_paths_result(n_sensors, n_samples, seed, include_raw):
    raw = warm_up(n_sensors, n_samples, seed)
    y = 3.0 * (raw[:, 0] - raw[:, -1]) + np.random.default_rng(seed).normal(0, 0.3, n_samples)
    for k in (1, 2, 3):
        matrix, _, rows, _ = both_ways(raw, y, k, include_raw)
        assert_same(matrix, rows)


def test_the_spanning_tree_is_the_matrix_trees():
    raw = warm_up(12, 300, 4)
    X = np.hstack([raw, pairwise_differences(raw)])
    reference = maximum_spanning_tree(similarity_matrix(X))
    candidates = PairCandidates(raw)
    geometry = PairGeometry.of(candidates, standardized_centre(raw))
    tree = maximum_spanning_tree_of_pairs(geometry, np.arange(X.shape[1]))
    np.testing.assert_array_equal(tree.order, reference.order)
    np.testing.assert_array_equal(tree.parent, reference.parent)
    np.testing.assert_allclose(tree.weight, reference.weight, rtol=0, atol=1e-12)


def test_ties_duplicates_offsets_scaled_copies_and_constant_sensors():
    """A duplicated sensor (similarity 1 with its twin), a copy with a constant offset (the
    difference is constant: dropped, warned), a scaled copy (|r| = 1) and a constant sensor
    (dropped, while its differences vary)."""
    base = warm_up(5, 240, 7)
    raw = np.column_stack([base, base[:, 1], base[:, 2] + 0.5, 2.0 * base[:, 3], np.zeros(240)])
    y = 4.0 * base[:, 0] - 2.0 * base[:, 4] + np.random.default_rng(3).normal(0, 0.2, 240)
    for k in (2, 3, 4, 6):
        matrix, matrix_warnings, rows, row_warnings = both_ways(raw, y, k)
        assert_same(matrix, rows)
        assert row_warnings == matrix_warnings
        assert any("dropping" in w for w in row_warnings)


def test_quantised_real_recording_gives_the_matrix_paths_result():
    frame = real_temperatures()
    sensors = [f"t{i}_C" for i in range(1, 17)]
    raw = frame[sensors].to_numpy(float)
    raw = raw - raw[0]
    y = frame["ch3_um"].to_numpy(float)
    for k in (2, 3, 4, 6):
        matrix, _, rows, _ = both_ways(raw, y, k)
        assert_same(matrix, rows)


def test_evaluate_row_wise_equals_the_matrix_path(monkeypatch):
    train, test = synthetic_experiment(0), synthetic_experiment(1, speed=0.7)
    matrix = evaluate(train, [test], "drift_um", k=3, differences=True).to_dict()
    monkeypatch.setattr(evaluate_module, "ROW_WISE_ABOVE", 5)
    rows = evaluate(train, [test], "drift_um", k=3, differences=True)
    assert evaluate_module.row_wise(evaluate_module.CandidateSet(tuple(rows.sensors), True),
                                    "abs-pearson", "fast")
    rows = rows.to_dict()
    assert rows["selected"] == matrix["selected"] and rows["clusters"] == matrix["clusters"]
    assert rows["eta"] == pytest.approx(matrix["eta"], abs=1e-12)
    assert rows["psi"] == pytest.approx(matrix["psi"], abs=1e-12)
    assert rows["rmse_um"] == pytest.approx(matrix["rmse_um"], rel=1e-9)


def test_names_reach_the_constant_warning():
    raw = warm_up(3, 60, 5)
    raw = np.column_stack([raw, raw[:, 0] + 1.0])
    names = ["a", "b", "c", "d"]
    y = raw[:, 1] + np.random.default_rng(0).normal(0, 0.1, 60)
    with pytest.warns(SelectionWarning, match="dropping 1 constant candidate.*a-d"):
        select_among_pairs(raw, y, 2, names=names + difference_names(names))


def test_bad_input_is_one_line():
    raw = warm_up(3, 20, 0)
    with pytest.raises(SelectionError, match="cannot make 7 clusters from 6"):
        select_among_pairs(raw, raw[:, 0], 7)
    with pytest.raises(SelectionError, match="finite"):
        select_among_pairs(np.where(raw > 1, np.nan, raw), raw[:, 0], 2)
    with pytest.raises(SelectionError, match="2 name"):
        select_among_pairs(raw, raw[:, 0], 2, names=["a", "b"])
    big = 1e308 * np.linspace(-1, 1, 20)
    huge = np.column_stack([big, -big])  # finite, but their difference overflows
    with pytest.raises(SelectionError, match="overflow"):
        select_among_pairs(huge, raw[:, 1], 1)


def test_literal_similarity_states_its_size_limit():
    X = np.random.default_rng(0).normal(size=(3, LITERAL_MAX_CANDIDATES + 1))
    with pytest.raises(SelectionError, match=f"at most {LITERAL_MAX_CANDIDATES} candidates"):
        similarity_matrix(X, "literal")


def test_compiled_and_numpy_rows_build_the_same_tree(monkeypatch, prim_path):
    """60 sensors, two of them duplicated (ties: the twin's differences have similarity 1
    with the original's), 1 828 candidates: the compiled loop's symmetric similarity and the
    NumPy rows' products differ in the last bits, so on ties the two may join the other
    twin first, and which tree they build differs there; every maximum spanning tree has
    the same multiset of edge weights, every edge is an edge of R, and the clusters of every
    cut (the selection) are the same."""
    if prim_path == "compiled":
        pytest.skip("compares both paths itself")
    base = warm_up(58, 400, 11)
    raw = np.column_stack([base, base[:, 3], base[:, 40]])
    candidates = PairCandidates(raw)
    geometry = PairGeometry.of(candidates, standardized_centre(raw))
    kept = np.flatnonzero(~check_candidates(candidates, None))  # the twins' zero differences
    assert kept.size == candidates.n_candidates - 2
    rows = maximum_spanning_tree_of_pairs(geometry, kept)
    monkeypatch.setattr(pairs_module, "COMPILED_ABOVE", 0)
    compiled = maximum_spanning_tree_of_pairs(geometry, kept)
    assert (compiled.order != rows.order).sum() < 200  # only around the ties
    np.testing.assert_allclose(np.sort(compiled.weight), np.sort(rows.weight), rtol=0,
                               atol=1e-12)
    R = geometry.similarity(kept)
    for tree in (compiled, rows):
        joined = tree.order[1:]
        np.testing.assert_allclose(R[joined, tree.parent[joined]], tree.weight[joined],
                                   rtol=0, atol=1e-12)
    for k in (2, 3, 5, 10, 50, 200, 1000, 1700):
        a, b = cut_tree_for_clusters(rows, k), cut_tree_for_clusters(compiled, k)
        assert a.eta == pytest.approx(b.eta, abs=1e-12)
        assert len(a.clusters) == len(b.clusters)
        for one, other in zip(a.clusters, b.clusters, strict=True):
            np.testing.assert_array_equal(one, other)
    assert (rows.weight[1:] > 1 - 1e-12).sum() > 1  # the twins' differences link at 1


def test_constant_candidates_are_refused_by_the_tree():
    """A zero vector (norm 0: no similarity) is refused, not linked through NaN."""
    raw = warm_up(4, 50, 3)
    candidates = PairCandidates(raw)
    geometry = PairGeometry.of(candidates, standardized_centre(raw))
    inverse = geometry.inverse_norm.copy()
    inverse[5] = np.inf
    geometry = dataclasses.replace(geometry, inverse_norm=inverse)
    with pytest.raises(SelectionError, match="non-constant candidates"):
        maximum_spanning_tree_of_pairs(geometry, np.arange(candidates.n_candidates))


def test_raw_sensors_with_differences_are_recognised_bit_for_bit():
    from spindlebench.selection.pairs import sensors_with_differences

    raw = warm_up(9, 50, 3)
    X = np.hstack([raw, pairwise_differences(raw)])
    assert sensors_with_differences(X) == 9
    assert sensors_with_differences(pairwise_differences(raw)) is None  # no raw columns
    assert sensors_with_differences(X[:, ::-1]) is None
    nudged = X.copy()
    nudged[7, -1] = np.nextafter(nudged[7, -1], np.inf)  # one value off by one ulp
    assert sensors_with_differences(nudged) is None
    assert sensors_with_differences(X[:, :-1]) is None  # not a triangular count


def test_estimator_and_matrix_input_select_row_wise_with_the_same_result(monkeypatch):
    """FuzzyClusterSelector after PairwiseDifferences (and select_sensitive_points on such a
    matrix) above ROW_WISE_ABOVE columns runs row-wise: the matrix path's result."""
    from spindlebench.selection.estimators import FuzzyClusterSelector, PairwiseDifferences

    raw = warm_up(25, 300, 6)  # 325 candidates
    y = 2.0 * (raw[:, 2] - raw[:, 20]) + np.random.default_rng(6).normal(0, 0.2, 300)
    X = PairwiseDifferences().fit_transform(raw)
    matrix = FuzzyClusterSelector(4).fit(X, y)
    monkeypatch.setattr(pairs_module, "ROW_WISE_ABOVE", 100)
    calls = []
    real = pairs_module.select_among_pairs
    monkeypatch.setattr(pairs_module, "select_among_pairs",
                        lambda *args, **kwargs: calls.append(1) or real(*args, **kwargs))
    rows = FuzzyClusterSelector(4).fit(X, y)
    assert calls == [1]
    assert_same(matrix.selection_, rows.selection_)
    np.testing.assert_array_equal(rows.selected_, matrix.selected_)
    np.testing.assert_allclose(rows.similarity_, matrix.similarity_, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(rows.transform(X), matrix.transform(X))
    assert select_sensitive_points(X, y, 4).eta == pytest.approx(matrix.eta_, abs=1e-12)
    assert len(calls) == 2


@pytest.mark.slow
def test_medium_set_selects_as_the_numpy_rows(monkeypatch, prim_path):
    """150 sensors (11 325 candidates, compiled by default) with ties: two duplicated
    sensors, a scaled copy and an offset copy (its difference is constant and dropped). The
    compiled loop's selection is the NumPy rows' (today's path below ``COMPILED_ABOVE``) for
    every k: same clusters and picks, eta and psi to rounding."""
    if prim_path == "compiled":
        pytest.skip("compares both paths itself")
    base = warm_up(146, 720, 21)
    raw = np.column_stack([base, base[:, 10], base[:, 99], 2.5 * base[:, 20],
                           base[:, 30] + 0.75])
    y = 2.0 * (raw[:, 5] - raw[:, 77]) + np.random.default_rng(5).normal(0, 0.2, 720)
    k_values = (2, 4, 8, 30, 300)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SelectionWarning)
        compiled = pairs_module.PairSelection(raw, y, max(k_values))
        assert compiled.kept.size > pairs_module.COMPILED_ABOVE  # compiled by default
        monkeypatch.setattr(pairs_module, "COMPILED_ABOVE", 10**9)
        rows = pairs_module.PairSelection(raw, y, max(k_values))
    for k in k_values:
        a, b = rows.select(k), compiled.select(k)
        assert len(a.clusters) == len(b.clusters)
        for one, other in zip(a.clusters, b.clusters, strict=True):
            np.testing.assert_array_equal(one, other)
        np.testing.assert_array_equal(a.selected, b.selected)
        assert b.eta == pytest.approx(a.eta, abs=1e-12)
        np.testing.assert_array_equal(a.psi, b.psi)
