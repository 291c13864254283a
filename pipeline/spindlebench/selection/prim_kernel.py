"""Compiled steps of Prim's algorithm over sensors and their differences (``selection.pairs``).

Numba compiles it once and caches the machine code on disk; it is imported only when a
row-wise selection of more than ``pairs.COMPILED_ABOVE`` candidates runs (importing Numba and
loading the cached code cost ~1 s of CPU and ~100 MB here; below that size NumPy rows are
cheaper). Each call takes a batch of vertices, so the Python loop around it stays responsive
to Ctrl-C.

Tried and dropped: the row loop split over two threads (``prange``) was 20x slower in wall
time on this shared 2-core machine (a barrier per row, ~125 000 rows, threads descheduled).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: The tree members are squeezed out of the outside arrays when they make up this fraction
#: (1/8: the loop runs over at most 8/7 of the outside candidates; each squeeze is one copy).
SQUEEZE_DENOMINATOR = 8


@njit(cache=True, nogil=True, error_model="numpy")
def prim_steps(factor_rows, factor, ids, first, second, inverse_norm, best, parent, state,
               order, weight, tree_parent, start, stop):  # pragma: no cover (compiled)
    """Add vertices ``order[start:stop]`` to the tree; ``state`` = [position of the next
    vertex in the outside arrays, number of outside entries, entries of tree members].

    The outside arrays (``ids``, ``first``, ``second``, ``inverse_norm``, ``best``,
    ``parent``, in candidate order) hold every candidate not yet in the tree, plus joined
    ones until they make up 1/``SQUEEZE_DENOMINATOR`` (then they are squeezed out, order
    kept). ``factor_rows`` is G^T with a row of zeros appended ((m + 1) x r): a candidate's
    vector is row ``first`` minus row ``second`` (the zero row for a raw sensor). G
    (``factor``, r x m) is upper triangular, so that vector is zero below entry
    max(first, second) and only that many rows of G enter the product with it.

    A joined entry carries a NaN norm and a best of -inf, so no row raises it and it is never
    the largest: the next vertex is the outside one with the largest link, the first on ties;
    a parent changes only on a strictly larger similarity (the rules of
    ``closure.maximum_spanning_tree``). A row raises few links (each candidate's best link
    only grows), so the update branches: well predicted, and it rarely writes. With the
    narrower index types (``pairs``) this took 2.4x fewer CPU seconds than a branch-free update
    at 20 100 candidates, and with the shorter product and the squeeze at 1/8 1.6x at 125 250.
    """
    m = factor_rows.shape[0] - 1
    u = np.zeros(m + 1)
    at, n_active, dead = state[0], state[1], state[2]
    for position in range(start, stop):
        vertex = ids[at]
        order[position] = vertex
        if position:
            weight[vertex] = best[at]
            tree_parent[vertex] = parent[at]
        scale = inverse_norm[at]
        a, b = first[at], second[at]
        rows = min((a if b == m else max(a, b)) + 1, factor.shape[0])  # nonzero entries
        direction = (factor_rows[a, :rows] - factor_rows[b, :rows]) * scale
        u[:m] = direction @ factor[:rows]  # covariance of the new vertex with every sensor
        best[at] = -np.inf
        inverse_norm[at] = np.nan
        dead += 1
        if SQUEEZE_DENOMINATOR * dead > n_active:  # squeeze, keeping candidate order
            kept = 0
            for j in range(n_active):
                if not np.isnan(inverse_norm[j]):
                    ids[kept] = ids[j]
                    first[kept] = first[j]
                    second[kept] = second[j]
                    inverse_norm[kept] = inverse_norm[j]
                    best[kept] = best[j]
                    parent[kept] = parent[j]
                    kept += 1
            n_active = kept
            dead = 0
        top = -np.inf
        at = -1
        for j in range(n_active):
            r = min(abs(u[first[j]] - u[second[j]]) * inverse_norm[j], 1.0)
            link = best[j]
            if r > link:
                link = r
                best[j] = r
                parent[j] = vertex
            if link > top:
                top = link
                at = j
    state[0], state[1], state[2] = at, n_active, dead
    return at
