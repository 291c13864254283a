"""The screened Prim loop (``prim_kernel.prim_blocks`` with ``screen``) builds the unscreened
loop's tree bit for bit: the screen only skips candidates that provably fail the exact test,
and the lazy links (intervals that hold the exact similarity) only decide where the interval
decides, so the order, parents and weights are those of the exact test of every candidate in
every row.

Random warm-ups with ties (duplicated sensors, an offset copy, a scaled copy, a sensor that
is another's difference partner twice) and a nearly collinear pair (cancellation, where the
screen's rounding bound is widest)."""

import importlib

import numpy as np
import pytest
from spindlebench.selection.pairs import (
    PairCandidates,
    PairGeometry,
    check_candidates,
    maximum_spanning_tree_of_pairs,
    standardized_centre,
)

pairs_module = importlib.import_module("spindlebench.selection.pairs")


def warm_up(n_sensors: int, n_samples: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_samples)[:, None]
    tau = rng.uniform(0.05, 0.8, n_sensors)
    gain = rng.uniform(0.5, 15.0, n_sensors)
    raw = gain * (1 - np.exp(-t / tau)) + rng.normal(0, 0.03, (n_samples, n_sensors))
    return raw - raw[0]


def with_ties(seed: int) -> np.ndarray:
    base = warm_up(36, 300, seed)
    rng = np.random.default_rng(seed + 100)
    return np.column_stack([base, base[:, 3], base[:, 7], base[:, 9] + 0.25,
                            3.0 * base[:, 11], base[:, 5] + 1e-7 * rng.normal(size=300)])


def trees(raw: np.ndarray, monkeypatch, include_raw: bool = True):
    monkeypatch.setattr(pairs_module, "COMPILED_ABOVE", 0)
    candidates = PairCandidates(raw, include_raw)
    constant = check_candidates(candidates, None)
    kept = np.flatnonzero(~constant)
    geometry = PairGeometry.of(candidates, standardized_centre(raw))
    counts = pairs_module.PRIM_COUNTS.copy()
    screened = maximum_spanning_tree_of_pairs(geometry, kept, screen=True)
    visits, passes, formed, _ = pairs_module.PRIM_COUNTS - counts
    assert passes < visits / 5 and formed < visits / 50  # the screen and the lazy links work
    return screened, maximum_spanning_tree_of_pairs(geometry, kept, screen=False)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_screened_tree_is_the_unscreened_tree_bit_for_bit(seed, monkeypatch):
    screened, reference = trees(with_ties(seed), monkeypatch)
    np.testing.assert_array_equal(screened.order, reference.order)
    np.testing.assert_array_equal(screened.parent, reference.parent)
    np.testing.assert_array_equal(screened.weight.view(np.int64),
                                  reference.weight.view(np.int64))
    assert (reference.weight[reference.order[1:]] >= 1.0).sum() >= 2  # the ties are there


def test_screened_tree_without_samples_to_spare(monkeypatch):
    """Fewer samples than sensors (G is r x m with r < m) and raw sensors included."""
    raw = warm_up(30, 20, 5)
    screened, reference = trees(raw, monkeypatch)
    np.testing.assert_array_equal(screened.order, reference.order)
    np.testing.assert_array_equal(screened.parent, reference.parent)
    np.testing.assert_array_equal(screened.weight, reference.weight)


def test_screened_tree_of_differences_only(monkeypatch):
    """Without the raw sensors (no block against the zero row), ties included."""
    screened, reference = trees(with_ties(3), monkeypatch, include_raw=False)
    np.testing.assert_array_equal(screened.order, reference.order)
    np.testing.assert_array_equal(screened.parent, reference.parent)
    np.testing.assert_array_equal(screened.weight.view(np.int64),
                                  reference.weight.view(np.int64))


def test_block_top_is_the_first_outside_candidate_with_the_largest_link():
    """``block_top``'s two passes against the definition, on the kernel's invariant
    (candidates not outside hold -inf), with ties and blocks with no link yet or none
    outside."""
    from spindlebench.selection.prim_kernel import block_top

    rng = np.random.default_rng(7)
    for _ in range(500):
        high = rng.choice([-np.inf, 0.25, 0.5, 0.5, 1.0], size=40)
        outside = rng.uniform(size=40) < rng.uniform()
        high[~outside] = -np.inf
        offset, count = int(rng.integers(0, 20)), int(rng.integers(1, 21))
        inside = [j for j in range(offset, offset + count) if outside[j]]
        expected = max(inside, key=lambda j: (high[j], -j)) if inside else -1
        assert block_top(high, outside, offset, count) == expected
