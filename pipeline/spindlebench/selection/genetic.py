"""A genetic algorithm over clusters: which member of each cluster to keep.

Practitioners' tools (e.g. the PyQt tool this field uses) cluster the sensors and then let a
genetic algorithm choose one sensor per cluster by the model's validation error instead of by
correlation alone. Here a genome holds one member index per cluster; its fitness is
``forward.validation_score`` (OLS on the rises, trained on the first of ``n_blocks``
contiguous time blocks, mean RMSE on the others: greedy forward selection's objective), lower
is better.

The algorithm (seeded, so the same seed gives the same choice):

- ``POPULATION`` (30) genomes; the first is the |psi| choice (the paper's), the rest drawn
  uniformly;
- each of ``GENERATIONS`` (40) generations keeps the best genome (elitism) and fills the
  population with children of binary-tournament parents, by uniform crossover, then
  mutation (each gene replaced by a random member of its cluster with probability
  1 / number of clusters);
- the answer is the best genome ever scored (scores are cached: a genome is fitted once).

With every cluster a singleton there is nothing to choose; with few combinations (at most the
population) every combination is scored instead, which is then the exhaustive optimum.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from spindlebench.selection.errors import SelectionError
from spindlebench.selection.forward import Block, validation_score
from spindlebench.selection.randomness import as_generator

POPULATION = 30
GENERATIONS = 40


def blocks(X: np.ndarray, y: np.ndarray, n_blocks: int = 2) -> tuple[Block, Block]:
    """The training block (the first of ``n_blocks`` contiguous blocks) and the others."""
    if X.shape[0] < 2 * n_blocks:
        raise SelectionError(f"the genetic algorithm needs at least {2 * n_blocks} samples for "
                             f"{n_blocks} blocks, got {X.shape[0]}")
    edges = np.linspace(0, X.shape[0], n_blocks + 1).round().astype(int)
    train = Block(X[: edges[1]], y[: edges[1]], np.array([0]))
    valid = Block(X[edges[1]:], y[edges[1]:], np.asarray(edges[1:-1] - edges[1], dtype=np.intp))
    return train, valid


def genetic_choice(X: np.ndarray, y: np.ndarray, clusters: Sequence[np.ndarray],
                   start: Sequence[int], random_state=0, population: int = POPULATION,
                   generations: int = GENERATIONS, n_blocks: int = 2) -> tuple[np.ndarray, float]:
    """One column of ``X`` per cluster (``start``: the genome to seed the population with,
    as column indices); returns the chosen columns and their validation RMSE."""
    train, valid = blocks(X, y, n_blocks)
    if train.X.shape[0] < len(clusters) + 2:
        raise SelectionError(f"the genetic algorithm: {train.X.shape[0]} training sample(s) "
                             f"cannot fit {len(clusters)} input(s)")
    members = [np.asarray(c, dtype=np.intp) for c in clusters]
    sizes = np.array([m.size for m in members])
    cache: dict[tuple[int, ...], float] = {}

    def score(genome: tuple[int, ...]) -> float:
        if genome not in cache:
            columns = [int(m[g]) for m, g in zip(members, genome, strict=True)]
            value = validation_score(train, valid, columns)
            cache[genome] = value if np.isfinite(value) else np.inf
        return cache[genome]

    first = tuple(int(np.flatnonzero(m == s)[0]) for m, s in zip(members, start, strict=True))
    if int(np.prod(sizes.astype(float))) <= population:  # few: score them all
        for genome in itertools.product(*(range(n) for n in sizes)):
            score(tuple(genome))
    else:
        rng = as_generator(random_state)
        pool = [first] + [tuple(int(rng.integers(n)) for n in sizes)
                          for _ in range(population - 1)]
        rate = 1.0 / len(members)
        for _ in range(generations):
            fitness = np.array([score(g) for g in pool])
            children = [pool[int(np.argmin(fitness))]]
            while len(children) < population:
                a, b = (pool[min(rng.integers(population, size=2), key=lambda i: fitness[i])]
                        for _ in range(2))
                take = rng.random(len(members)) < 0.5
                child = [x if t else z for x, z, t in zip(a, b, take, strict=True)]
                mutate = rng.random(len(members)) < rate
                child = [int(rng.integers(n)) if m else g
                         for g, n, m in zip(child, sizes, mutate, strict=True)]
                children.append(tuple(child))
            pool = children
        for genome in pool:
            score(genome)
    best = min(cache, key=lambda g: (cache[g], g != first, g))
    columns = np.array([int(m[g]) for m, g in zip(members, best, strict=True)], dtype=np.intp)
    return columns, cache[best]
