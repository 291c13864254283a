"""Compiled steps of Prim's algorithm over sensors and their differences (``selection.pairs``).

Numba compiles it once and caches the machine code on disk; it is imported only when a
row-wise selection runs (the import costs ~0.3 s and ~100 MB). Each call takes a batch of
vertices, so the Python loop around it stays responsive to Ctrl-C.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, error_model="numpy")
def prim_steps(factor_rows, inverse_norm, first, second, include_raw, best, parent, weight,
               order, start, stop, vertex):  # pragma: no cover (compiled)
    """Add the vertices ``order[start:stop]`` to the tree, beginning with ``vertex``; return
    the next vertex (-1 when none is left).

    ``factor_rows`` is G^T with a row of zeros appended ((m + 1) x r); a candidate's vector
    is row ``first`` minus row ``second`` (the zero row for a raw sensor). Tree members and
    candidates outside the selection carry a NaN ``inverse_norm`` and a ``best`` of -inf, so
    no row raises them and they are never the largest: the next vertex is the outside one
    with the largest link, the first on ties; a parent changes only on a strictly larger
    similarity (the rules of ``closure.maximum_spanning_tree``).
    """
    m = factor_rows.shape[0] - 1
    factor_t = factor_rows[:m]
    for position in range(start, stop):
        order[position] = vertex
        if position:
            weight[vertex] = best[vertex]
        scale = inverse_norm[vertex]
        best[vertex] = -np.inf
        inverse_norm[vertex] = np.nan
        direction = (factor_rows[first[vertex]] - factor_rows[second[vertex]]) * scale
        u = factor_t @ direction  # covariance of the new vertex with every raw sensor
        top = -np.inf
        vertex = -1
        j = 0
        if include_raw:
            for i in range(m):
                r = min(abs(u[i]) * inverse_norm[i], 1.0)
                if r > best[i]:
                    best[i] = r
                    parent[i] = order[position]
                if best[i] > top:
                    top = best[i]
                    vertex = i
            j = m
        for i in range(m - 1):
            ui = u[i]
            for k in range(i + 1, m):
                r = min(abs(ui - u[k]) * inverse_norm[j], 1.0)
                if r > best[j]:
                    best[j] = r
                    parent[j] = order[position]
                if best[j] > top:
                    top = best[j]
                    vertex = j
                j += 1
    return vertex
