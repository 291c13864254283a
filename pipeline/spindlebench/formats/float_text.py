"""CSV text of a float64 array: every value as Python's ``repr`` writes it, a NaN as nothing.

A sweep writes a thousand recordings of ~27 000 float64 values in its one coordinating
process; ``repr`` of each (CPython's ``dtoa``, ~350 ns a value here) was ~10 ms per
recording, most of that process's CPU while its workers simulate. orjson (a compiled JSON
writer) writes the same shortest round-trip digits (Ryu: the shortest decimal that reads
back to the same float, on ties of length the closest) about twenty times faster, a whole
array in one call; it differs from ``repr`` only in the notation outside ``repr``'s
positional range (``0.00001`` for ``1e-05``, ``1e16`` for ``1e+16``) and writes ``null``
for NaN and the infinities. So each value outside ``1e-4 <= |x| < 1e16`` (zero aside) is
written by ``repr`` and every other is orjson's text as it is. Those values are few but
spread (a simulated recording has a column of ~1e-13 W in every row: ``repr`` of every such
row was ~11 ms a recording), so they are not taken row by row: orjson writes them as NaN,
whose ``null`` no number's text contains, and the text is cut at each ``null`` and rejoined
with their ``repr`` in between (~1 ms a recording). Tests hold the result equal to ``repr``
on awkward values and on hundreds of thousands of random ones.
"""

from __future__ import annotations

import numpy as np
import orjson

#: ``repr`` writes |x| in [1e-4, 1e16) positionally, as orjson does; outside it, an exponent.
_POSITIONAL_FROM, _POSITIONAL_BELOW = 1e-4, 1e16


def csv_rows(values: np.ndarray) -> bytes:
    """The CSV lines of a 2-D float64 array (each row's values joined by commas, each line
    ending in a newline), every value as its ``repr`` and a NaN as an empty field."""
    values = np.ascontiguousarray(values, dtype=np.float64)
    if not values.size:
        return b"\n" * values.shape[0]
    magnitude = np.abs(values)
    with np.errstate(invalid="ignore"):  # NaN compares False: not positional
        odd = ~(((magnitude >= _POSITIONAL_FROM) & (magnitude < _POSITIONAL_BELOW))
                | (values == 0.0))
    if not odd.any():
        return _orjson_rows(values)
    # cut at the "n" of each "null" (no number's text has an "n") and drop the "ull" after it
    pieces = _orjson_rows(np.where(odd, np.nan, values)).split(b"n")
    texts = [repr(v).encode() if v == v else b"" for v in values[odd].tolist()]  # row-major
    joined: list[bytes] = [b""] * (2 * len(texts) + 1)
    joined[0], joined[2::2] = pieces[0], [piece[3:] for piece in pieces[1:]]
    joined[1::2] = texts
    return b"".join(joined)


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
    magnitude = np.abs(values)
    with np.errstate(invalid="ignore"):  # NaN compares False: not positional
        odd = ~(((magnitude >= _POSITIONAL_FROM) & (magnitude < _POSITIONAL_BELOW))
                | (values == 0.0))
    cells = orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY)[1:-1].decode().split(",")
    for index in np.flatnonzero(odd).tolist():
        value = float(values[index])
        cells[index] = repr(value) if value == value else ""
    return cells


def _orjson_rows(values: np.ndarray) -> bytes:
    """orjson's text of a non-empty 2-D array as CSV lines (NaN and the infinities as null).

    Cut at each row's "[" (a search for one byte; "],[" as a whole took three times as
    long): ``[[a,b],[c,d]]`` gives ``a,b],`` and ``c,d]]``, each two bytes too long."""
    text = orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY)
    rows = [row[:-2] for row in text.split(b"[")[2:]]
    rows.append(b"")  # the last line's newline
    return b"\n".join(rows)
