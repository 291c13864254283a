"""Indented JSON text: exactly ``json.dumps(data, indent=2, ensure_ascii=False, ...)``, faster.

A sweep writes a ~14 kB sidecar beside each of its thousand recordings in its one
coordinating process. With ``indent`` the standard library cannot use its C encoder and
encodes in Python (~0.9 ms a sidecar, 1.5 million calls in a 1 008-experiment sweep).
orjson (a pinned dependency, see ``float_text``) writes the same text with ``OPT_INDENT_2``
(the same layout, ``": "`` after a key, ``{}`` and ``[]`` for empty ones, the same string
escapes with ``ensure_ascii=False``) for the values it and ``json`` treat alike; the
differences are the floats of decimal exponents -5 to -9 (``1e-05``, ``1e-07``: orjson writes
``0.00001``, ``1e-7``; ``float_text.orjson_writes_repr`` says which), which are handed to it
as their ``repr`` (``orjson.Fragment``),
and everything orjson would write otherwise or refuse: NaN and the infinities, integers
beyond 64 bits, keys that are not strings, subclasses (an ``IntEnum``, ``numpy.float64``),
enums, UUIDs, dataclasses, dates. Any of those, or anything else unknown, takes the
standard library's path, which writes (or refuses) it as it always did. Tests hold the text
equal to ``json.dumps`` on sidecars and on awkward and random values.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import orjson

from spindlebench.formats.float_text import orjson_writes_repr

#: orjson's integer range (64 bits, signed or unsigned); ``json`` has none.
_INT_FROM, _INT_BELOW = -(1 << 63), 1 << 64


class _UnsureError(Exception):
    """A value whose text orjson might not write as ``json`` does."""


def indented_json(data: Any, *, allow_nan: bool = True,
                  default: Callable[[Any], Any] | None = None) -> str:
    """``json.dumps(data, indent=2, ensure_ascii=False, allow_nan=allow_nan,
    default=default)``, the same text (and the same errors)."""
    try:
        return orjson.dumps(_plain(data), option=orjson.OPT_INDENT_2).decode("utf-8")
    except (_UnsureError, RecursionError, orjson.JSONEncodeError):
        return json.dumps(data, indent=2, ensure_ascii=False, allow_nan=allow_nan,
                          default=default)


def _plain(value: Any) -> Any:
    """``value`` as orjson should see it (tuples as lists, odd floats as their ``repr``), or
    ``_UnsureError`` for anything whose text could differ from ``json``'s."""
    kind = type(value)
    if kind is str or kind is bool or value is None:
        return value
    if kind is float:
        if orjson_writes_repr(value):
            return value
        if value != value or value in (float("inf"), float("-inf")):
            raise _UnsureError  # json writes NaN/Infinity, or refuses with allow_nan=False
        return orjson.Fragment(repr(value).encode())
    if kind is int:
        if _INT_FROM <= value < _INT_BELOW:
            return value
        raise _UnsureError
    if kind is dict:
        out = {}
        for key, item in value.items():
            if type(key) is not str:
                raise _UnsureError  # json writes 1, 1.5, True, None keys as text; orjson refuses
            out[key] = _plain(item)
        return out
    if kind is list or kind is tuple:
        return [_plain(item) for item in value]
    raise _UnsureError
