"""Compiled Prim's algorithm over sensors and their differences (``selection.pairs``).

Numba compiles it once and caches the machine code on disk; it is imported only when a
row-wise selection of more than ``pairs.COMPILED_ABOVE`` candidates runs (importing Numba and
loading the cached code cost ~1 s of CPU and ~100 MB here; below that size NumPy rows are
cheaper). Each call takes a batch of vertices, so the Python loop around it stays responsive
to Ctrl-C.

**The similarity** of two candidates is ``edge_similarity``: min(|s_v . s_w|, 1) of their unit
vectors in the orthonormal basis of the centred rises (``pairs.PairGeometry``), in a fixed
summation order. It is symmetric bit for bit (the products are the same numbers whichever
candidate is the row), so the tree is a maximum spanning tree of ONE symmetric matrix, and
every maximum spanning tree of it has the same edge weights and the same clusters at every
cut (``cut``). It costs O(r), so it is formed only where a comparison needs it.

**The screen** makes the n^2 visits cheap. Candidates are laid out in ``pair_indices`` order,
so the differences (i, k), k = i+1..m-1, of sensor i are one contiguous block (the raw
sensors one more, against the zero row m). For the new vertex v, two rows of the Gram matrix
C = G^T G give its covariance with every sensor, c_j = (C_aj - C_bj) / |s_v| (O(m),
float32), and |c_i - c_k| / |s_w| is the similarity of v and w = (i, k) up to ``row_margin``
(a rigorous bound on every rounding between those numbers and the exact similarity). A
visit reads one float32 threshold and one float32 of c, contiguously, and compares: the
loop is vectorised, ~0.1 ns a visit here (``_any``: a boolean OR in mask registers, whole
arrays at unsigned offsets; at 1 000 sensors the visits are ~70 % of the loop, the rest
the rescans of the blocks a row improves, the links replaced and each block's top).

**Lazy links.** A candidate's best link is kept as an interval [low, high] that holds its
exact similarity: the float64 Gram value widened by its own rounding bound (``d_margin``), or
the exact value itself. A row replaces a link whose high it beats for sure, ignores one it
cannot beat, and only when the two overlap forms both exact similarities and compares them.
The next vertex is the candidate with the largest high (each block keeps its top,
``block_top``): a top whose link is not exact is made exact and the top taken again, until
it is exact, which is then the largest exact link (the first on ties, since every other
high is an upper bound). So exact similarities are formed about once per vertex, plus
near-ties, instead of once per improvement (tens of millions at 1 000 sensors), and the tree
is the one the exact test of every candidate in every row gives (``screen=False``, the
reference the tests compare with, bit for bit), by the rules of ``closure.prim_tree`` (the
largest link, the first on ties; a parent changes only on a strictly larger similarity).

Tried and dropped: a block skipped whole by max_k |c_i - c_k| (suffix minima and maxima of
c) against a lower bound of its thresholds (almost never skips: as the previous kernel's
chunk bounds, the spread of c within a block is far above the thresholds of its
small-norm differences); a tournament tree for the largest link (replayed at every
improvement; the blocks' tops cost less); squeezing tree members out (the gather of c it
needs costs 2x the contiguous visit it saves); 16-bit (bfloat16) thresholds (no faster while
the float32 ones fit in the 2 MB L2 cache, up to ~1 000 sensors: the visit is bound by its
arithmetic; in a synthetic sweep 0.10 against 0.14 ns a visit at 1 400 sensors, so a
candidate for 2 000); a block's tail padded to whole vectors with masked lanes (slower).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Candidates per vectorised chunk of a block: a chunk where a candidate may pass the screen
#: is rescanned one candidate at a time.
CHUNK = 16
STATS = np.zeros(4, dtype=np.int64)
#: Unit roundoff of float64 and of float32.
UNIT = 2.0 ** -53
UNIT32 = 2.0 ** -24


@njit(cache=True, nogil=True)
def block_top(high, outside, offset, count):  # pragma: no cover (compiled)
    """The block's outside candidate with the largest ``high``, the first on ties (-1: none).

    Two branch-free-ish passes (the largest high, then the first outside candidate holding
    it), ~30 % faster than one pass that tests ``outside`` at every step: candidates not
    outside hold high = -inf (set when a vertex joins; the others never get a link), so the
    largest high over the block is the largest over the outside ones, and with -inf (no
    link yet) the first outside candidate is the first on ties, as before."""
    best = -np.inf
    for j in range(offset, offset + count):
        best = max(best, high[j])
    for j in range(offset, offset + count):
        if outside[j] and high[j] == best:
            return j
    return -1


@njit(cache=True, nogil=True, inline="always")
def _before(w, top, high):  # pragma: no cover (compiled)
    """Whether candidate ``w`` is a block's top rather than ``top`` (-1: none): the larger
    high, the first on ties."""
    return top < 0 or high[w] > high[top] or (high[w] == high[top] and w < top)


@njit(cache=True, nogil=True, inline="always")
def _top_of_all(high, tops):  # pragma: no cover (compiled)
    """The candidate with the largest ``high`` over the blocks' tops, the first on ties (the
    blocks are in candidate order)."""
    best = -1
    for block in range(tops.shape[0]):
        top = tops[block]
        if top >= 0 and (best < 0 or high[top] > high[best]):
            best = top
    return best


@njit(cache=True, nogil=True, inline="always")
def unit_vector(factor_rows, a, b, scale, length, out):  # pragma: no cover (compiled)
    """out[:length] = (g_a - g_b) * scale, the candidate's unit vector (g_m = 0); the rest of
    it is zero since G is upper triangular (``length`` = its nonzero entries)."""
    for t in range(length):
        out[t] = (factor_rows[a, t] - factor_rows[b, t]) * scale


@njit(cache=True, nogil=True, inline="always")
def edge_similarity(x, y, length):  # pragma: no cover (compiled)
    """min(|x . y|, 1) over the first ``length`` entries (beyond, one of them is zero), in
    four interleaved sums in a fixed order: the same bits whichever of x, y is which."""
    s0 = s1 = s2 = s3 = 0.0
    t = 0
    while t + 4 <= length:
        s0 += x[t] * y[t]
        s1 += x[t + 1] * y[t + 1]
        s2 += x[t + 2] * y[t + 2]
        s3 += x[t + 3] * y[t + 3]
        t += 4
    while t < length:
        s0 += x[t] * y[t]
        t += 1
    return min(abs((s0 + s1) + (s2 + s3)), 1.0)


@njit(cache=True, nogil=True, inline="always")
def exact_slack(r):  # pragma: no cover (compiled)
    """E: |edge_similarity - s_v . s_w / (|s_v| |s_w|)| < E, the exact similarity of the
    vectors in float64 arithmetic (a dot product of r terms: gamma_r; forming each unit
    vector: 2 roundings per entry; the computed norms: (r + 3) u), doubled as headroom."""
    gamma = r * UNIT / (1.0 - r * UNIT)
    return 2.0 * (gamma + (2 * r + 16) * UNIT)


@njit(cache=True, nogil=True, inline="always")
def link_threshold(low, inverse_norm, slack):  # pragma: no cover (compiled)
    """A float32 t with t <= (low - slack) |s_w|: a screened value (|c_i - c_k| + M_v) not
    above t proves the exact similarity does not beat a link of at least ``low`` (inf when
    nothing can: the similarity is clipped at 1; -inf when anything does)."""
    if low >= 1.0:
        return np.float32(np.inf)
    if low == -np.inf:
        return np.float32(-np.inf)
    value = (low - 2.0 * slack) / inverse_norm * (1.0 - 8 * UNIT)
    rounded = np.float32(value)
    if rounded > value:
        rounded = np.nextafter(rounded, np.float32(-np.inf))
    return rounded


@njit(cache=True, nogil=True, inline="always")
def row_margin(r, scale, spread):  # pragma: no cover (compiled)
    """M_v (float32, rounded up), twice a bound on | fl32(|c_i - c_k|) - |s_v . s_w| / |s_v| |
    for every candidate w = (i, k), plus the rounding of the float32 sum with M_v itself;
    ``spread`` = (|g_a| + |g_b|) max_j |g_j|.

    Each Gram entry is off by gamma_r |g_i| |g_j|; c_j = (C_aj - C_bj) * scale, rounded to
    float64 and then float32, is off by scale * spread * (gamma_r + 2 u + u32); two of them,
    the float32 difference (u32 of |c_i| + |c_k|) and the sum (3 u32) add up to
    scale * spread * (2 gamma_r + 4 u + 6 u32).
    """
    gamma = r * UNIT / (1.0 - r * UNIT)
    value = scale * spread * (4.0 * gamma + 8 * UNIT + 16 * UNIT32) * (1.0 + 1e-6)
    rounded = np.float32(value)
    if rounded < value:
        rounded = np.nextafter(rounded, np.float32(np.inf))
    return rounded


@njit(cache=True, nogil=True, inline="always")
def d_margin(r, scale, spread):  # pragma: no cover (compiled)
    """Twice a bound on |d - |s_v . s_w| / |s_v|| for d = |(C_ai - C_bi) - (C_ak - C_bk)|
    * scale in float64, ``spread`` = (|g_a| + |g_b|) (|g_i| + |g_k|): four Gram entries off
    by gamma_r |g_x| |g_y| each, three subtractions and the product rounded (4 u), the
    norms' own rounding (the factor 1 + 1e-6)."""
    gamma = r * UNIT / (1.0 - r * UNIT)
    return 2.0 * scale * spread * (gamma + 4 * UNIT) * (1.0 + 1e-6)


@njit(cache=True, nogil=True)
def _any(c, start, threshold, offset, count, fixed, margin):  # pragma: no cover (compiled)
    """Whether one of the ``count`` candidates from ``offset`` (their c from ``start``) may
    pass the screen: an OR of IEEE float32 comparisons (the same as the scalar test's),
    vectorised without fast-math. A boolean OR, not a count: LLVM keeps it in mask registers,
    8 candidates a step (0.10 ns a visit here), where a count was widened to int64 lanes, 4 a
    step (0.16 ns). Whole arrays and offsets, not slices: a slice is a new array whose
    reference count is raised and dropped (two atomic operations each), which cost ~13 % of
    the loop at 1 000 sensors (two slices per block and row). The indices are unsigned, so
    no wraparound test for negative ones keeps LLVM from vectorising (0.48 ns a visit)."""
    hit = False
    first_c, first_threshold = np.uint64(start), np.uint64(offset)
    for t in range(np.uint64(count)):
        hit |= abs(fixed - c[first_c + t]) + margin > threshold[first_threshold + t]
    return hit


@njit(cache=True, nogil=True, inline="always")
def _exact(p, w, factor_rows, first, second, inverse_norm, lengths, buffer_p, buffer_w):
    """The exact similarity of candidates p and w."""  # pragma: no cover (compiled)
    unit_vector(factor_rows, first[p], second[p], inverse_norm[p], lengths[p], buffer_p)
    unit_vector(factor_rows, first[w], second[w], inverse_norm[w], lengths[w], buffer_w)
    return edge_similarity(buffer_p, buffer_w, min(lengths[p], lengths[w]))


@njit(cache=True, nogil=True, error_model="numpy")
def prim_blocks(factor_rows, gram, norms, first, second, inverse_norm, lengths, blocks,
                block_alive, block_of, tops, outside, low, high, exact, parent, threshold,
                order, weight, tree_parent, start, stop, screen, counts):  # pragma: no cover
    """Add vertices ``order[start:stop]`` to the tree (positions are candidate indices).

    ``factor_rows`` is G^T with a zero row appended ((m + 1) x r), ``gram`` G^T G with a
    zero row and column ((m + 1)^2), ``norms`` |g_j| (0 for j = m); per candidate:
    ``first``, ``second`` (m for a raw sensor), ``inverse_norm``, ``lengths`` (nonzero
    entries of its vector), ``outside`` (a vertex not yet in the tree), its link's interval
    ``low``, ``high`` (-inf: none yet), ``exact`` (the interval is the exact similarity),
    ``parent``, ``threshold`` (float32; +inf once it joined, if it is not a vertex, or if
    nothing can beat its link); per block (fixed sensor, first k, offset, length) of
    ``blocks``, ``block_alive`` (its candidates still outside) and ``tops`` (its outside
    candidate with the largest ``high``, the first on ties; ``block_top``), and ``block_of``
    per candidate. ``counts`` gathers [visits, screened passes, exact similarities formed,
    links replaced].
    """
    m = factor_rows.shape[0] - 1
    r = factor_rows.shape[1]
    slack = exact_slack(r)
    norm_bound = norms.max() * (1.0 + 1e-6)
    row = np.zeros(r)
    buffer_p = np.zeros(r)
    buffer_w = np.zeros(r)
    c = np.zeros(m + 1, dtype=np.float32)
    for position in range(start, stop):
        vertex = _top_of_all(high, tops)
        while not exact[vertex]:  # the top's link made exact, until the top is exact
            value = _exact(parent[vertex], vertex, factor_rows, first, second, inverse_norm,
                           lengths, buffer_p, buffer_w)
            counts[2] += 1
            _relink(vertex, parent[vertex], value, value, True, inverse_norm, low, high,
                    exact, parent, threshold, slack)
            home = block_of[vertex]
            tops[home] = block_top(high, outside, blocks[home, 2], blocks[home, 3])
            vertex = _top_of_all(high, tops)
        order[position] = vertex
        if position:
            weight[vertex] = high[vertex]
            tree_parent[vertex] = parent[vertex]
        outside[vertex] = False
        high[vertex] = -np.inf
        threshold[vertex] = np.inf
        home = block_of[vertex]
        block_alive[home] -= 1
        tops[home] = block_top(high, outside, blocks[home, 2], blocks[home, 3])
        if position == order.shape[0] - 1:
            break
        a, b = first[vertex], second[vertex]
        scale = inverse_norm[vertex]
        length = lengths[vertex]
        unit_vector(factor_rows, a, b, scale, length, row)
        for j in range(m):
            c[j] = np.float32((gram[a, j] - gram[b, j]) * scale)
        margin = row_margin(r, scale, (norms[a] + norms[b]) * norm_bound)
        visits = 0  # counted here, stored once a row (a store per block is a chain of them)
        for block in range(blocks.shape[0]):
            if block_alive[block] == 0:
                continue
            fixed_index, k0, offset, count = blocks[block, 0], blocks[block, 1], \
                blocks[block, 2], blocks[block, 3]
            fixed = c[fixed_index]
            visits += count
            if screen and not _any(c, k0, threshold, offset, count, fixed, margin):
                continue
            top = tops[block]
            lowered = False
            for chunk in range(0, count, CHUNK):
                end = min(count, chunk + CHUNK)
                if screen and not _any(c, k0 + chunk, threshold, offset + chunk, end - chunk,
                                       fixed, margin):
                    continue
                for t in range(chunk, end):
                    w = offset + t
                    screened = abs(fixed - c[k0 + t])
                    if threshold[w] == np.inf or (screen and screened + margin <= threshold[w]):
                        continue
                    counts[1] += 1
                    if screen:  # the float64 Gram value and its own, tighter, bound
                        # w's sensors from its block, not from first/second (8 MB read at
                        # random): the raw block has them swapped, (m, k) for (k, m), which
                        # gives the same bits (|x - y| = |y - x|, a sum of two norms).
                        i, k = fixed_index, k0 + t
                        d = abs((gram[a, i] - gram[b, i]) - (gram[a, k] - gram[b, k])) * scale
                        spread = d_margin(r, scale, (norms[a] + norms[b])
                                          * (norms[i] + norms[k])) * inverse_norm[w]
                        upper = min(d * inverse_norm[w] * (1 + 4 * UNIT) + spread + slack, 1.0)
                        lower = max(d * inverse_norm[w] * (1 - 4 * UNIT) - spread - slack,
                                    0.0)
                        if lower > high[w]:  # beats the link for sure
                            counts[3] += 1
                            _relink(w, vertex, lower, upper, False, inverse_norm, low, high,
                                    exact, parent, threshold, slack)
                            if _before(w, top, high):
                                top = w
                            continue
                        if upper <= low[w]:  # cannot beat it
                            continue
                    if not exact[w]:  # overlapping: both exact (the link's high may fall)
                        value = _exact(parent[w], w, factor_rows, first, second,
                                       inverse_norm, lengths, buffer_p, buffer_w)
                        counts[2] += 1
                        _relink(w, parent[w], value, value, True, inverse_norm, low, high,
                                exact, parent, threshold, slack)
                        lowered = lowered or w == top
                    unit_vector(factor_rows, first[w], second[w], inverse_norm[w], lengths[w],
                                buffer_w)
                    value = edge_similarity(row, buffer_w, min(length, lengths[w]))
                    counts[2] += 1
                    if value > high[w]:
                        counts[3] += 1
                        _relink(w, vertex, value, value, True, inverse_norm, low, high,
                                exact, parent, threshold, slack)
                        if _before(w, top, high):
                            top = w
            tops[block] = block_top(high, outside, offset, count) if lowered else top
        counts[0] += visits


@njit(cache=True, nogil=True, inline="always")
def _relink(w, vertex, bottom, top, is_exact, inverse_norm, low, high, exact, parent,
            threshold, slack):  # pragma: no cover (compiled)
    """Candidate ``w``'s link becomes ``vertex`` with similarity in [bottom, top]."""
    low[w] = bottom
    high[w] = top
    exact[w] = is_exact
    parent[w] = vertex
    threshold[w] = link_threshold(bottom, inverse_norm[w], slack)
