"""CSV text of a float64 array: every value as Python's ``repr`` writes it, a NaN as nothing.

A sweep writes a thousand recordings of ~27 000 float64 values in its one coordinating
process; ``repr`` of each (CPython's ``dtoa``, ~350 ns a value here) was ~10 ms per
recording, most of that process's CPU while its workers simulate. orjson (a compiled JSON
writer) writes the same shortest round-trip digits (Ryu: the shortest decimal that reads
back to the same float, on ties of length the closest) about twenty times faster, a whole
array in one call; it differs from ``repr`` only in the notation of the decimal exponents
-5 to -9, which it writes as JavaScript does (``0.00001`` and ``1e-7`` for ``1e-05`` and
``1e-07``), and writes ``null`` for NaN and the infinities: from ``1e-10`` down and from
``1e16`` up both write the same exponent form (``1e-13``, ``1e+16``; the module once took
every value outside ``repr``'s positional range ``1e-4 <= |x| < 1e16`` as different, so
that a simulated recording's column of ~1e-13 W heat flows, 180 values, went through
``repr`` in every recording). So each value with ``1e-10 <= |x| < 1e-4`` (a decade of margin
below the last one that differs) or not finite is written by ``repr`` and every other is
orjson's text as it is. Those values are few but may be spread over the rows, so they are not
taken row by row: orjson writes them as NaN, whose ``null`` no number's text contains, and
the text is cut at each ``null`` and rejoined with their ``repr`` in between. Tests hold the
result equal to ``repr`` on awkward values and on hundreds of thousands of random ones.
"""

from __future__ import annotations

import numpy as np
import orjson

#: The finite values whose orjson text may not be their ``repr``: 1e-10 <= |x| < 1e-4 (orjson
#: writes the exponents -5 to -9 otherwise; below and above that range the two agree, tested on
#: every power of 2 and 10 and their neighbours, and on random bit patterns).
REPR_ONLY_FROM, REPR_ONLY_BELOW = 1e-10, 1e-4
#: The largest finite float64 (an infinity above it is written by neither).
_LARGEST = float(np.finfo(np.float64).max)


def csv_rows(values: np.ndarray) -> bytes:
    """The CSV lines of a 2-D float64 array (each row's values joined by commas, each line
    ending in a newline), every value as its ``repr`` and a NaN as an empty field."""
    values = np.ascontiguousarray(values, dtype=np.float64)
    if not values.size:
        return b"\n" * values.shape[0]
    odd = _odd(values)
    text = orjson.dumps(np.where(odd, np.nan, values) if odd.any() else values,
                        option=orjson.OPT_SERIALIZE_NUMPY)
    return _rows_of(text, [repr(v).encode() if v == v else b""
                           for v in values[odd].tolist()])  # row-major, as the nulls


def orjson_writes_repr(value: float) -> bool:
    """Whether orjson's text of the float ``value`` is its ``repr`` (``_odd`` of one value)."""
    magnitude = abs(value)
    return magnitude < REPR_ONLY_FROM or REPR_ONLY_BELOW <= magnitude <= _LARGEST


def _odd(values: np.ndarray) -> np.ndarray:
    """Where orjson's text of a value may not be its ``repr``: ``REPR_ONLY_FROM <= |x| <
    REPR_ONLY_BELOW``, NaN and the infinities."""
    magnitude = np.abs(values)
    with np.errstate(invalid="ignore"):  # NaN compares False: odd
        return ~((magnitude < REPR_ONLY_FROM)
                 | ((magnitude >= REPR_ONLY_BELOW) & (magnitude <= _LARGEST)))


def _rows_of(text: bytes, texts: list[bytes]) -> bytes:
    """orjson's ``[[a,b],[c,d]]`` of a non-empty 2-D array as CSV lines, the i-th ``null``
    replaced by ``texts[i]``.

    Each row lies between its ``[`` and ``]`` (the outer pair aside), and each ``null``
    starts with the one ``n`` of the text (no number's text has one): found as byte
    positions by numpy, the pieces between are joined as views of the text, so the text is
    copied once (cutting it with ``split`` at ``[`` and at ``n`` copied it four times, a
    quarter of a recording's write)."""
    codes = np.frombuffer(text, dtype=np.uint8)
    starts = (np.flatnonzero(codes == ord("["))[1:] + 1).tolist()
    ends = np.flatnonzero(codes == ord("]"))[:-1].tolist()
    nulls = np.flatnonzero(codes == ord("n")).tolist()
    nulls.append(len(text))  # a sentinel past every row's end
    view = memoryview(text)
    pieces: list[bytes | memoryview] = []
    odd = 0
    for start, end in zip(starts, ends, strict=True):
        while nulls[odd] < end:
            pieces += (view[start:nulls[odd]], texts[odd])
            start = nulls[odd] + len(b"null")
            odd += 1
        pieces += (view[start:end], b"\n")
    return b"".join(pieces)


def float_cells(values: np.ndarray) -> list[str]:
    """The CSV cells of a 1-D float64 array: each value as its ``repr``, a NaN as ``""``
    (``csv_rows`` of the one-column array, cut into its lines).

    Why: a sweep's result table has three float columns and is written column by column
    (one file per training run and condition, over a thousand); ``csv_rows`` of a column
    builds and cuts one line per value (~0.13 ms for 300 values), one orjson array cut at
    its commas is a fifth of that."""
    values = np.ascontiguousarray(values, dtype=np.float64)
    if not values.size:
        return []
    odd = _odd(values)
    cells = orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY)[1:-1].decode().split(",")
    for index in np.flatnonzero(odd).tolist():
        value = float(values[index])
        cells[index] = repr(value) if value == value else ""
    return cells
