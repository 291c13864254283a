"""The unit of a recording's time column, made explicit: one home for the rule.

Every command works in seconds (``time_s``). A user's logger writes minutes (``Zeit [min]``),
hours (``time (h)``), a sample counter or a date and time; read as seconds, a 6 h run became
0-0.10 h in ``plot`` and ``fingerprint`` without a word. The unit comes from ``--time-unit``,
else from the column's name; a name without a unit means seconds, unless the column counts
0, 1, 2, … (a sample index: refused until ``--time-unit`` says what one step is). A column
of dates/times is read as seconds elapsed since its first row.
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Sequence

import numpy as np

from spindlebench.core.errors import SpindlebenchError

#: Seconds per unit of a time column.
TIME_UNITS = {"ms": 1e-3, "s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}
#: How units are spelt in column names.
_ALIASES = {"ms": "ms", "s": "s", "sec": "s", "secs": "s", "second": "s", "seconds": "s",
            "min": "min", "mins": "min", "minute": "min", "minutes": "min",
            "h": "h", "hr": "h", "hrs": "h", "hour": "h", "hours": "h",
            "d": "d", "day": "d", "days": "d"}
_UNIT = "|".join(sorted(_ALIASES, key=len, reverse=True))
#: A unit in brackets or parentheses anywhere, or a ``_unit`` / `` unit`` suffix.
_IN_NAME = re.compile(rf"[\[(]\s*({_UNIT})\s*[\])]|[_ ]({_UNIT})$", re.IGNORECASE)


def unit_from_name(name: str) -> str | None:
    """The time unit a column's name states (``Zeit [min]`` -> ``min``), or None."""
    found = _IN_NAME.search(name.strip())
    if not found:
        return None
    return _ALIASES[(found.group(1) or found.group(2)).lower()]


def time_axis_seconds(values: np.ndarray, name: str, given: str | None,
                      where: str) -> tuple[np.ndarray, str | None]:
    """The time column in seconds and a note saying how it was read (None: plain seconds).

    Refused in one line: a ``--time-unit`` that contradicts the unit in the name, and a
    unit-less column that counts samples (0, 1, 2, …) when no unit is given."""
    stated = unit_from_name(name)
    if given is not None and given not in TIME_UNITS:
        raise SpindlebenchError(f"--time-unit {given}: not one of {', '.join(TIME_UNITS)}")
    if given is not None and stated is not None and given != stated:
        raise SpindlebenchError(f"recording {where}: --time-unit {given} contradicts the unit "
                                f"in the time column's name {name!r} ({stated}); drop one")
    unit = given or stated
    if unit is None and looks_like_sample_index(values):
        raise SpindlebenchError(
            f"recording {where}: time column {name!r} counts 0, 1, 2, … without a unit in its "
            "name: a sample index, not a time; give --time-unit (s, min, …: what one step "
            "is) or name the real time column with --time-column")
    if unit is None or unit == "s":
        return values, None
    how = "--time-unit" if given else "its name"
    return values * TIME_UNITS[unit], f"{name!r} in {unit} ({how}), read as seconds"


def looks_like_sample_index(values: np.ndarray) -> bool:
    """Whether a time column is a counter: at least 3 whole numbers rising by exactly 1,
    starting at 0 or 1."""
    values = np.asarray(values, dtype=float)
    if values.size < 3 or not np.isfinite(values).all() or values[0] not in (0.0, 1.0):
        return False
    return bool(np.all(np.diff(values) == 1.0))


def parse_datetimes(cells: Sequence[str], name: str, where: str) -> np.ndarray | None:
    """Seconds since the first row of a column of ISO dates/times (``2024-03-01 08:00:00``,
    ``2024-03-01T08:00``), or None when the first cell is not one (a numeric column).
    A later cell that is not a date/time is one line naming its line."""
    def parse(text: str) -> dt.datetime:
        moment = dt.datetime.fromisoformat(text.strip())
        return moment if moment.tzinfo is None else moment.astimezone(dt.UTC)

    if not cells:
        return None
    try:
        float(cells[0].strip().replace(",", "."))
        return None  # a number (20240301 would read as a date)
    except ValueError:
        pass
    try:
        first = parse(cells[0])
    except ValueError:
        return None
    aware = first.tzinfo is not None
    seconds = np.empty(len(cells))
    for row, text in enumerate(cells):
        try:
            moment = parse(text)
            if (moment.tzinfo is not None) != aware:
                raise ValueError
        except ValueError:
            raise SpindlebenchError(
                f"recording {where}, line {row + 2}, column {name!r}: {text.strip()[:40]!r} is "
                "not a date/time like the first row's (YYYY-MM-DD hh:mm:ss)") from None
        seconds[row] = (moment - first).total_seconds()
    return seconds
