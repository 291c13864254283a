"""Compiled CSV text of a float64 array: every value as Python's ``repr`` writes it.

A sweep writes a thousand recordings of ~27 000 float64 values in its one coordinating
process; ``repr`` of each (CPython's ``dtoa``, ~350 ns a value here) was ~10 ms per
recording, most of that process's CPU while its workers simulate. This kernel makes the same
text, the shortest decimal that reads back to the same float (on ties of length the closest
to it), with the Ryu algorithm (Ulf Adams, "Ryū: fast float-to-string conversion", PLDI
2018: the digits and decimal exponent from one 128-bit product with a table of powers of 5,
no big numbers), and lays them out as ``repr`` does: positional for a decimal exponent from
-4 to 15 (``0.0001``, ``120.0``, ``9999999999999998.0``), else ``d.ddde±XX`` (``1e-05``,
``1e+16``, ``5e-324``), ``-0.0``, ``inf`` and ``-inf``; a NaN is an empty field, as pandas
writes it. Tests hold it equal to ``repr`` on awkward values and millions of random bit
patterns.

Numba compiles it once and caches the machine code on disk (``selection.prim_kernel`` does
the same); it is imported only by a process that writes many recordings and asks for it
(``table_csv.write_table(..., compiled=True)``: a study's ``ResultStore``), since loading
the cached code costs ~0.7 s of CPU, the time ``repr`` takes for ~70 recordings.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_U = np.uint64
_MASK32 = _U(0xFFFFFFFF)
#: Bits of the table entries (Ryu's DOUBLE_POW5_INV_BITCOUNT and DOUBLE_POW5_BITCOUNT).
_POW5_INV_BITS = 125
_POW5_BITS = 125
#: Widest text of one value, "-2.2250738585072014e-308", and its separator.
MAX_CELL_BYTES = 25


def _split(value: int) -> tuple[int, int]:
    return value & 0xFFFFFFFFFFFFFFFF, value >> 64


def _tables() -> tuple[np.ndarray, np.ndarray]:
    """Ryu's tables as (low, high) 64-bit halves: 5^i scaled to 125 bits (``_POW5``), and
    2^(bits(5^i) - 1 + 125) / 5^i rounded up (``_POW5_INV``), exact from Python's integers."""
    pow5 = np.array([_split(5 ** i >> (5 ** i).bit_length() - _POW5_BITS)
                     if (5 ** i).bit_length() >= _POW5_BITS
                     else _split(5 ** i << _POW5_BITS - (5 ** i).bit_length())
                     for i in range(326)], dtype=np.uint64)
    inverse = np.array([_split((1 << (5 ** i).bit_length() - 1 + _POW5_INV_BITS) // 5 ** i + 1)
                        for i in range(342)], dtype=np.uint64)
    return pow5, inverse


#: Read by the compiled functions as constants frozen into their code: passed as arguments,
#: each call counted references to them (a quarter of the time per value).
_POW5, _POW5_INV = _tables()


@njit(cache=True, nogil=True)
def _mul_shift(m, low, high, shift):  # pragma: no cover (compiled)
    """(m * (high·2^64 + low)) >> shift for m < 2^55 and 64 <= shift < 128, by 32-bit
    pieces (no 128-bit integers here)."""
    m_lo, m_hi = m & _MASK32, m >> _U(32)
    # m * low: only its high word is needed
    b00 = m_lo * (low & _MASK32)
    mid = m_hi * (low & _MASK32) + (b00 >> _U(32))
    mid2 = m_lo * (low >> _U(32)) + (mid & _MASK32)
    high0 = m_hi * (low >> _U(32)) + (mid >> _U(32)) + (mid2 >> _U(32))
    # m * high: both words
    c00 = m_lo * (high & _MASK32)
    cmid = m_hi * (high & _MASK32) + (c00 >> _U(32))
    cmid2 = m_lo * (high >> _U(32)) + (cmid & _MASK32)
    high1 = m_hi * (high >> _U(32)) + (cmid >> _U(32)) + (cmid2 >> _U(32))
    low1 = (cmid2 << _U(32)) | (c00 & _MASK32)
    total = high0 + low1
    if total < high0:
        high1 += _U(1)
    dist = _U(shift - 64)
    if dist == _U(0):
        return total
    return (high1 << (_U(64) - dist)) | (total >> dist)


@njit(cache=True, nogil=True)
def _pow5_factor(value):  # pragma: no cover (compiled)
    count = 0
    while value % _U(5) == _U(0):
        value //= _U(5)
        count += 1
    return count


@njit(cache=True, nogil=True)
def _pow5_bits(e):  # pragma: no cover (compiled)
    return ((e * 1217359) >> 19) + 1


@njit(cache=True, nogil=True)
def _shortest(mantissa, exponent):  # pragma: no cover (compiled)
    """Ryu's d2d: (digits, decimal exponent) of the shortest round trip of the positive
    finite double with IEEE fields ``mantissa``, ``exponent``."""
    if exponent == 0:
        e2 = 1 - 1023 - 52 - 2
        m2 = mantissa
    else:
        e2 = exponent - 1023 - 52 - 2
        m2 = mantissa | (_U(1) << _U(52))
    accept_bounds = (m2 & _U(1)) == _U(0)
    mv = _U(4) * m2
    mm_shift = _U(1) if (mantissa != _U(0) or exponent <= 1) else _U(0)
    vm_trailing_zeros = False
    vr_trailing_zeros = False
    if e2 >= 0:
        q = ((e2 * 78913) >> 18) - (1 if e2 > 3 else 0)
        e10 = q
        k = _POW5_INV_BITS + _pow5_bits(q) - 1
        i = -e2 + q + k
        low, high = _POW5_INV[q, 0], _POW5_INV[q, 1]
        vr = _mul_shift(mv, low, high, i)
        vp = _mul_shift(mv + _U(2), low, high, i)
        vm = _mul_shift(mv - _U(1) - mm_shift, low, high, i)
        if q <= 21:
            if mv % _U(5) == _U(0):
                vr_trailing_zeros = _pow5_factor(mv) >= q
            elif accept_bounds:
                vm_trailing_zeros = _pow5_factor(mv - _U(1) - mm_shift) >= q
            elif _pow5_factor(mv + _U(2)) >= q:
                vp -= _U(1)
    else:
        q = (((-e2) * 732923) >> 20) - (1 if -e2 > 1 else 0)
        e10 = q + e2
        i = -e2 - q
        k = _pow5_bits(i) - _POW5_BITS
        j = q - k
        low, high = _POW5[i, 0], _POW5[i, 1]
        vr = _mul_shift(mv, low, high, j)
        vp = _mul_shift(mv + _U(2), low, high, j)
        vm = _mul_shift(mv - _U(1) - mm_shift, low, high, j)
        if q <= 1:
            vr_trailing_zeros = True
            if accept_bounds:
                vm_trailing_zeros = mm_shift == _U(1)
            else:
                vp -= _U(1)
        elif q < 63:
            vr_trailing_zeros = (mv & ((_U(1) << _U(q)) - _U(1))) == _U(0)
    removed = 0
    last_removed = _U(0)
    if vm_trailing_zeros or vr_trailing_zeros:
        while vp // _U(10) > vm // _U(10):
            vm_trailing_zeros &= vm % _U(10) == _U(0)
            vr_trailing_zeros &= last_removed == _U(0)
            last_removed = vr % _U(10)
            vr //= _U(10)
            vp //= _U(10)
            vm //= _U(10)
            removed += 1
        if vm_trailing_zeros:
            while vm % _U(10) == _U(0):
                vr_trailing_zeros &= last_removed == _U(0)
                last_removed = vr % _U(10)
                vr //= _U(10)
                vp //= _U(10)
                vm //= _U(10)
                removed += 1
        if vr_trailing_zeros and last_removed == _U(5) and vr % _U(2) == _U(0):
            last_removed = _U(4)  # exactly halfway: round to even
        up = (vr == vm and (not accept_bounds or not vm_trailing_zeros)) or last_removed >= _U(5)
    else:
        round_up = False
        while vp // _U(10) > vm // _U(10):
            round_up = vr % _U(10) >= _U(5)
            vr //= _U(10)
            vp //= _U(10)
            vm //= _U(10)
            removed += 1
        up = vr == vm or round_up
    return vr + (_U(1) if up else _U(0)), e10 + removed


@njit(cache=True, nogil=True)
def _put_float(out, at, bits):  # pragma: no cover (compiled)
    """Write ``repr`` of the double with IEEE bits ``bits`` (NaN: nothing) at ``out[at:]``;
    return the end."""
    exponent = int((bits >> _U(52)) & _U(0x7FF))
    mantissa = bits & ((_U(1) << _U(52)) - _U(1))
    if exponent == 0x7FF and mantissa != _U(0):
        return at
    if bits >> _U(63):
        out[at] = 45  # "-"
        at += 1
    if exponent == 0x7FF:  # inf
        out[at], out[at + 1], out[at + 2] = 105, 110, 102
        return at + 3
    if exponent == 0 and mantissa == _U(0):
        out[at], out[at + 1], out[at + 2] = 48, 46, 48  # "0.0"
        return at + 3
    digits, e10 = _shortest(mantissa, exponent)
    count = 1
    scale = _U(10)
    while count < 20 and digits >= scale:
        count += 1
        scale *= _U(10)
    point = count + e10  # the decimal point after ``point`` digits
    if -4 < point <= 16:
        if point <= 0:
            out[at], out[at + 1] = 48, 46  # "0."
            at += 2
            for _ in range(-point):
                out[at] = 48
                at += 1
            _put_digits(out, at, digits, count)
            return at + count
        if point >= count:
            _put_digits(out, at, digits, count)
            at += count
            for _ in range(point - count):
                out[at] = 48
                at += 1
            out[at], out[at + 1] = 46, 48  # ".0"
            return at + 2
        _put_digits(out, at, digits, count)  # then the fraction moved one place right
        for place in range(at + count, at + point, -1):
            out[place] = out[place - 1]
        out[at + point] = 46
        return at + count + 1
    _put_digits(out, at + 1, digits, count)  # d.ddd: the first digit moved before the point
    out[at] = out[at + 1]
    at += 1
    if count > 1:
        out[at] = 46
        at += count
    out[at] = 101  # "e"
    power = point - 1
    out[at + 1] = 43 if power >= 0 else 45
    power = abs(power)
    width = 3 if power >= 100 else 2
    _put_digits(out, at + 2, _U(power), width)
    return at + 2 + width


@njit(cache=True, nogil=True)
def _put_digits(out, at, value, count):  # pragma: no cover (compiled)
    """Write the ``count`` last decimal digits of ``value`` (zero-padded) at ``out[at:]``, two
    at a time (half the divisions)."""
    place = count
    while place >= 2:
        pair = value % _U(100)
        value //= _U(100)
        place -= 2
        out[at + place] = 48 + int(pair // _U(10))
        out[at + place + 1] = 48 + int(pair % _U(10))
    if place:
        out[at] = 48 + int(value % _U(10))


@njit(cache=True, nogil=True)
def _csv_rows(bits):  # pragma: no cover (compiled)
    out = np.empty(bits.shape[0] * bits.shape[1] * MAX_CELL_BYTES, dtype=np.uint8)
    at = 0
    for row in range(bits.shape[0]):
        for column in range(bits.shape[1]):
            if column:
                out[at] = 44  # ","
                at += 1
            at = _put_float(out, at, bits[row, column])
        out[at] = 10  # "\n"
        at += 1
    return out[:at]


def csv_rows(values: np.ndarray) -> bytes:
    """The CSV lines of a 2-D float64 array (each row's values joined by commas, each line
    ending in a newline), every value as its ``repr`` and a NaN as an empty field."""
    bits = np.ascontiguousarray(values, dtype=np.float64).view(np.uint64)
    return _csv_rows(bits).tobytes()
