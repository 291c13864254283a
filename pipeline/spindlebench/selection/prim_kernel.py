"""Compiled steps of Prim's algorithm over sensors and their differences (``selection.pairs``).

Numba compiles it once and caches the machine code on disk; it is imported only when a
row-wise selection runs (the import costs ~0.3 s and ~100 MB). Each call takes a batch of
vertices, so the Python loop around it stays responsive to Ctrl-C.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, error_model="numpy")
def prim_steps(factor_rows, factor_t, ids, first, second, inverse_norm, best, parent, state,
               order, weight, tree_parent, start, stop):  # pragma: no cover (compiled)
    """Add vertices ``order[start:stop]`` to the tree; ``state`` = [position of the next
    vertex in the outside arrays, number of outside entries, entries of tree members].

    The outside arrays (``ids``, ``first``, ``second``, ``inverse_norm``, ``best``,
    ``parent``, in candidate order) hold every candidate not yet in the tree, plus joined
    ones until they make up half (then they are squeezed out, order kept). ``factor_rows``
    is G^T with a row of zeros appended ((m + 1) x r): a candidate's vector is row ``first``
    minus row ``second`` (the zero row for a raw sensor); ``factor_t`` is G^T alone, its own
    C-contiguous array (a slice would make ``@`` skip BLAS). A joined entry carries a NaN norm
    and a best of -inf, so no row raises it and it is never the largest: the next vertex is
    the outside one with the largest link, the first on ties; a parent changes only on a
    strictly larger similarity (the rules of ``closure.maximum_spanning_tree``).
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
        direction = (factor_rows[first[at]] - factor_rows[second[at]]) * scale
        best[at] = -np.inf
        inverse_norm[at] = np.nan
        dead += 1
        u[:m] = factor_t @ direction  # covariance of the new vertex with every raw sensor
        if 2 * dead > n_active:  # squeeze the tree members out, keeping candidate order
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
        for j in range(n_active):  # branch-free update: the comparisons are unpredictable
            r = min(abs(u[first[j]] - u[second[j]]) * inverse_norm[j], 1.0)
            b = best[j]
            closer = r > b
            b = r if closer else b
            best[j] = b
            parent[j] = vertex if closer else parent[j]
            if b > top:
                top = b
                at = j
    state[0], state[1], state[2] = at, n_active, dead
    return at
