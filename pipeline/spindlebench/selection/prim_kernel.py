"""Compiled steps of Prim's algorithm over sensors and their differences (``selection.pairs``).

Numba compiles it once and caches the machine code on disk; it is imported only when a
row-wise selection of more than ``pairs.COMPILED_ABOVE`` candidates runs (importing Numba and
loading the cached code cost ~1 s of CPU and ~100 MB here; below that size NumPy rows are
cheaper). Each call takes a batch of vertices, so the Python loop around it stays responsive
to Ctrl-C.

The loop over the outside candidates is what costs (n^2 / 2 visits): per visit it reads two
int16 sensor indices and one threshold, and compares |u_first - u_second| with it. The
threshold of a candidate is the largest difference that does not beat its best link
(``link_threshold``, exact in floating point), so the similarity is only formed, and the link
updated, when it beats it (rare: a best link only grows). The largest link is kept in a
tournament tree (``tournament``) instead of a running maximum over the loop. Same trees,
bit for bit, as the running-maximum loop; 1.3x fewer CPU seconds at 500 sensors.

Tried and dropped: the row loop split over two threads (``prange``) was 20x slower in wall
time on this shared 2-core machine (a barrier per row, ~125 000 rows, threads descheduled);
a blockwise pre-scan (any link beaten in 32 candidates?) gained nothing.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: The tree members are squeezed out of the outside arrays when they make up this fraction
#: (1/8: the loop runs over at most 8/7 of the outside candidates; each squeeze is one copy).
SQUEEZE_DENOMINATOR = 8


@njit(cache=True, nogil=True, inline="always")
def link_threshold(link, inverse_norm):  # pragma: no cover (compiled)
    """The largest x with fl(x * inverse_norm) <= link (inf if no similarity beats
    ``link``, i.e. link = 1): min(d * inverse_norm, 1) > link exactly when d > x, since a
    product with a positive number rounds monotonically."""
    if link >= 1.0:
        return np.inf
    if link == -np.inf:
        return -np.inf
    x = link / inverse_norm
    while x * inverse_norm > link:
        x = np.nextafter(x, -np.inf)
    while np.nextafter(x, np.inf) * inverse_norm <= link:
        x = np.nextafter(x, np.inf)
    return x


@njit(cache=True, nogil=True, inline="always")
def _winner(best, a, b):  # pragma: no cover (compiled)
    """Of outside positions a < b (-1: none), the larger link, the earlier one on ties."""
    if b < 0:
        return a
    if a < 0:
        return b
    return a if best[a] >= best[b] else b


@njit(cache=True, nogil=True)
def tournament(best, tree, n_active):  # pragma: no cover (compiled)
    """Build the tournament over positions 0..n_active-1: leaves at tree[size + j] (size =
    len(tree) // 2, a power of two), each inner node the winner of its two children, so
    tree[1] is the position of the largest link (the first on ties)."""
    size = tree.shape[0] // 2
    for j in range(size):
        tree[size + j] = j if j < n_active else -1
    for node in range(size - 1, 0, -1):
        tree[node] = _winner(best, tree[2 * node], tree[2 * node + 1])


@njit(cache=True, nogil=True, inline="always")
def _replay(best, tree, position):  # pragma: no cover (compiled)
    """Replay the matches above leaf ``position`` after its link changed."""
    node = (tree.shape[0] // 2 + position) // 2
    while node >= 1:
        winner = _winner(best, tree[2 * node], tree[2 * node + 1])
        if tree[node] == winner and winner != position:
            return  # nothing above changes
        tree[node] = winner
        node //= 2


@njit(cache=True, nogil=True, error_model="numpy")
def prim_steps(factor_rows, factor, gram, norm_bound, ids, first, second, inverse_norm, best,
               parent, threshold, screen_threshold, tree, state, order, weight, tree_parent,
               start, stop, screen):  # pragma: no cover (compiled)
    """Add vertices ``order[start:stop]`` to the tree; ``state`` = [position of the next
    vertex in the outside arrays, number of outside entries, entries of tree members].

    The outside arrays (``ids``, ``first``, ``second``, ``inverse_norm``, ``best``,
    ``parent``, ``threshold``, in candidate order) hold every candidate not yet in the tree,
    plus joined ones until they make up 1/``SQUEEZE_DENOMINATOR`` (then they are squeezed
    out, order kept, and the tournament ``tree`` rebuilt). ``factor_rows`` is G^T with a row
    of zeros appended ((m + 1) x r): a candidate's vector is row ``first`` minus row
    ``second`` (the zero row for a raw sensor). G (``factor``, r x m) is upper triangular, so
    that vector is zero below entry max(first, second) and only that many rows of G enter the
    product with it.

    A joined entry carries a NaN norm, an infinite threshold and leaves the tournament, so no
    row raises it and it is never the largest: the next vertex is the outside one with the
    largest link, the first on ties; a parent changes only on a strictly larger similarity
    (the rules of ``closure.prim_tree``).

    With ``screen``, each candidate is first compared through the Gram matrix (``gram`` =
    G^T G with a zero row and column appended, (m + 1)^2): the new vertex's covariances with
    the sensors are a difference of two rows of it, O(m) instead of the O(m r) product.
    Those values differ from the product's by at most ``screen_margin`` (a rounding bound,
    ``norm_bound`` = the largest |g_j|), so a candidate whose screened difference is not
    above its threshold minus the margin cannot pass the exact test and is skipped. Only when
    one can, the product is formed (once per row) and the exact test decides with exactly
    the numbers of the unscreened loop: the same tree, bit for bit, as ``screen=False``.
    """
    m = factor_rows.shape[0] - 1
    r = factor.shape[0]
    size = tree.shape[0] // 2
    u = np.zeros(m + 1)
    near = np.zeros(m + 1)
    at, n_active, dead = state[0], state[1], state[2]
    for position in range(start, stop):
        vertex = ids[at]
        order[position] = vertex
        if position:
            weight[vertex] = best[at]
            tree_parent[vertex] = parent[at]
        scale = inverse_norm[at]
        a, b = first[at], second[at]
        rows = min((a if b == m else max(a, b)) + 1, r)  # nonzero entries
        best[at] = -np.inf
        inverse_norm[at] = np.nan
        threshold[at] = np.inf
        screen_threshold[at] = np.inf
        tree[size + at] = -1
        _replay(best, tree, at)
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
                    threshold[kept] = threshold[j]
                    screen_threshold[kept] = screen_threshold[j]
                    kept += 1
            n_active = kept
            dead = 0
            tournament(best, tree, n_active)
        formed = False
        if screen:
            for i in range(m):
                near[i] = (gram[a, i] - gram[b, i]) * scale
            spread = (np.sqrt(gram[a, a]) + np.sqrt(gram[b, b])) * scale
            margin = screen_margin(r, norm_bound, spread)
            for j in range(n_active):
                if abs(near[first[j]] - near[second[j]]) + margin > screen_threshold[j]:
                    if not formed:
                        direction = (factor_rows[a, :rows] - factor_rows[b, :rows]) * scale
                        u[:m] = direction @ factor[:rows]  # covariances with every sensor
                        formed = True
                    d = abs(u[first[j]] - u[second[j]])
                    if d > threshold[j]:  # the similarity beats the best link (exactly)
                        _link(j, d, vertex, inverse_norm, best, parent, threshold, tree)
                        screen_threshold[j] = below32(threshold[j])
        else:
            direction = (factor_rows[a, :rows] - factor_rows[b, :rows]) * scale
            u[:m] = direction @ factor[:rows]  # covariance of the new vertex with every sensor
            for j in range(n_active):
                d = abs(u[first[j]] - u[second[j]])
                if d > threshold[j]:  # the similarity beats the best link (exactly)
                    _link(j, d, vertex, inverse_norm, best, parent, threshold, tree)
        at = tree[1]
    state[0], state[1], state[2] = at, n_active, dead
    return at


@njit(cache=True, nogil=True, inline="always")
def _link(j, d, vertex, inverse_norm, best, parent, threshold, tree):  # pragma: no cover
    """Candidate ``j``'s best link becomes ``vertex`` with difference ``d``."""
    similarity = min(d * inverse_norm[j], 1.0)
    best[j] = similarity
    parent[j] = vertex
    threshold[j] = link_threshold(similarity, inverse_norm[j])
    _replay(best, tree, j)


@njit(cache=True, nogil=True, inline="always")
def below32(value):  # pragma: no cover (compiled)
    """The largest float32 not above ``value`` (half the bytes per visit of the screen)."""
    rounded = np.float32(value)
    if rounded > value:
        rounded = np.nextafter(rounded, np.float32(-np.inf))
    return rounded


@njit(cache=True, nogil=True, inline="always")
def screen_margin(r, norm_bound, spread):  # pragma: no cover (compiled)
    """A bound on |screened - exact| covariance difference of one row.

    With unit u = 2^-53, gamma = r u / (1 - r u) (a length-r dot product's relative
    rounding bound) and |g| <= ``norm_bound``: a Gram entry is off by at most gamma |g_i||g_j|,
    so the screened covariance (G_a - G_b) . g_j s is off by at most
    (gamma + 2u)(1 + u) s (|g_a| + |g_b|) |g_j| (``spread`` = s (|g_a| + |g_b|), at least
    |d| ~ 1, large when g_a ~ g_b); the product's is off by at most
    (gamma + 3u)(1 + gamma) |d| |g_j| with |d| <= 1 + 3u. Two covariances and the final
    subtraction of each way give the factor 2 and the last terms; the whole bound is doubled
    again as headroom for the rounding of this very formula and of the norms.
    """
    unit = 2.0 ** -53
    gamma = r * unit / (1.0 - r * unit)
    screened = (gamma + 2 * unit) * (1 + unit) * spread
    exact = (gamma + 3 * unit) * (1 + gamma) * (1 + 3 * unit)
    per_covariance = (screened + exact) * norm_bound
    return 2.0 * (2.0 * per_covariance + 2 * unit * (spread + 1.0) * 2.0 * norm_bound)
