"""The one checked-TOML reader: scenarios, studies, climate tables and paper configs.

Every value is read through :class:`Table`, which remembers the file and the dotted key, so any
problem is one line of one shape, ``FILE: key 'a.b': what is wrong``, and a key no reader asked
for (usually a typo) is refused with a "did you mean" hint instead of being silently ignored.
The rules live here once: booleans never count as numbers, NaN and infinity are refused (TOML
allows them, no input means them, and they slip past every range check), and a range is
reported as ``must be in [lo, hi] unit, got v``.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any, TypeVar

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_input

T = TypeVar("T")

#: Marks a key without a default (required).
REQUIRED: Any = object()

_TYPE_NAMES = {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
               list: "a list", dict: "a table"}


def load_toml(path: str | Path, what: str = "") -> dict[str, Any]:
    """Parse a TOML file; a missing, unreadable or malformed file is a one-line error.

    ``what`` names the kind of file for the not-found message (``"scenario"`` → ``scenario
    file not found``).
    """
    path = Path(path)
    kind = f"{what} file" if what else "file"
    check_input(path, f"{kind} (.toml)")
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise SpindlebenchError(f"{path}: {kind} not found") from None
    except IsADirectoryError:
        raise SpindlebenchError(f"{path}: is a directory, expected a {kind} (.toml)") from None
    except UnicodeDecodeError as exc:
        raise SpindlebenchError(f"{path}: not valid TOML: not UTF-8 text (byte "
                                f"{exc.start})") from None
    except OSError as exc:
        raise SpindlebenchError(f"{path}: cannot read ({exc})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpindlebenchError(f"{path}: not valid TOML: {exc}") from None
    except RecursionError:  # arrays or inline tables nested thousands deep
        raise SpindlebenchError(f"{path}: not valid TOML here: arrays or tables nested too "
                                "deeply") from None


def with_key_paths(table: Mapping[str, Any], values: Mapping[str, Any]) -> dict[str, Any]:
    """``table`` with each dotted key path of ``values`` set (``"speed.rpm"`` is ``rpm`` of
    the ``[speed]`` table, made if missing); a table value merges into the table already
    there, key by key, as TOML's ``[a]`` then ``[a.b]`` would. ``table`` is not changed.

    >>> with_key_paths({"speed": {"kind": "constant"}}, {"speed.rpm": 2000.0, "seed": 3})
    {'speed': {'kind': 'constant', 'rpm': 2000.0}, 'seed': 3}
    """
    merged: dict[str, Any] = dict(table)
    for path, value in values.items():
        head, _, rest = path.partition(".")
        if rest:
            value = {rest: value}
        if isinstance(value, Mapping) and isinstance(merged.get(head), Mapping):
            value = with_key_paths(merged[head], {k: v for k, v in value.items()})
        elif isinstance(value, Mapping):
            value = with_key_paths({}, value)
        merged[head] = value
    return merged


def range_problem(value: float, minimum: float | None = None, maximum: float | None = None,
                  unit: str = "", positive: bool = False) -> str | None:
    """The one range message (None when ``value`` is in range)."""
    unit = f" {unit}" if unit else ""
    low_ok = (minimum is None or value >= minimum) and (not positive or value > 0)
    high_ok = maximum is None or value <= maximum
    if low_ok and high_ok:
        return None
    if positive and (minimum is None or minimum <= 0):
        bounds = f"in (0, {maximum:g}]" if maximum is not None else "> 0"
    elif minimum is not None and maximum is not None:
        bounds = f"in [{minimum:g}, {maximum:g}]"
    elif minimum is not None:
        bounds = f">= {minimum:g}"
    else:
        bounds = f"<= {maximum:g}"
    return f"must be {bounds}{unit}, got {value:g}"


def in_range(minimum: float | None = None, maximum: float | None = None, unit: str = "",
             positive: bool = False) -> Callable[[float], str | None]:
    """A ``check`` for :meth:`Table.get` / :meth:`Table.get_list` with the one range message."""
    return lambda value: range_problem(value, minimum, maximum, unit, positive)


def positive(value: float) -> str | None:
    return range_problem(value, positive=True)


def non_negative(value: float) -> str | None:
    return range_problem(value, minimum=0.0)


def did_you_mean(name: str, known: Iterator[str] | list[str] | set[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``known``, or ``""``."""
    close = difflib.get_close_matches(name, sorted(str(k) for k in known), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


class Table:
    """A TOML table that hands out checked values and rejects keys nobody asked for."""

    def __init__(self, data: Mapping[str, Any], source: str | Path, prefix: str = "") -> None:
        self.data = data
        self.source = str(source)
        self.prefix = prefix
        self._used: set[str] = set()

    # ----------------------------------------------------------------- naming and errors

    def key(self, name: str) -> str:
        """The dotted key of ``name`` inside this table, as the user wrote it."""
        return f"{self.prefix}.{name}" if self.prefix else name

    def error(self, name: str, message: str) -> SpindlebenchError:
        """A one-line error about key ``name`` of this table."""
        return SpindlebenchError(f"{self.source}: key '{self.key(name)}': {message}")

    def has(self, name: str) -> bool:
        return name in self.data

    def names(self) -> Iterator[str]:
        return iter(self.data)

    def unused(self) -> list[str]:
        """Keys no reader has asked for yet."""
        return [name for name in self.data if name not in self._used]

    def finish(self) -> None:
        """Reject keys that no reader asked for: they are typos or unsupported options."""
        unknown = self.unused()
        if unknown:
            allowed = ", ".join(sorted(self._used)) or "none"
            raise self.error(unknown[0], f"unknown key{did_you_mean(unknown[0], self._used)}; "
                                         f"allowed here: {allowed}")

    # ----------------------------------------------------------------- values

    def raw(self, name: str, default: Any = REQUIRED) -> Any:
        """An unchecked value (for fragments that another module validates)."""
        self._used.add(name)
        if name in self.data:
            return self.data[name]
        if default is REQUIRED:
            near = difflib.get_close_matches(name, self.unused(), n=1)
            hint = f"; is '{self.key(near[0])}' a misspelling of it?" if near else ""
            raise self.error(name, f"missing (required){hint}")
        return default

    def get(self, name: str, kind: type[T], default: Any = REQUIRED,
            check: Callable[[T], str | None] | None = None) -> T:
        """The value of ``name`` as ``kind``; ``check`` returns a complaint or None. A default
        is returned as is, unchecked."""
        if name not in self.data:
            return self.raw(name, default)
        value = self.raw(name)
        return self._checked(name, value, kind, check, "")

    def get_list(self, name: str, kind: type[T], default: Any = REQUIRED,
                 check: Callable[[T], str | None] | None = None,
                 allow_empty: bool = False) -> list[T]:
        """A list whose items are all ``kind`` (each checked); duplicates are rejected."""
        if name not in self.data:
            return list(self.raw(name, default))
        raw = self.raw(name)
        if not isinstance(raw, list):
            raise self.error(name, f"must be a list, got {_describe(raw)}")
        if not raw and not allow_empty:
            raise self.error(name, "must not be empty")
        items: list[T] = []
        for index, item in enumerate(raw):
            value = self._checked(name, item, kind, None, f"item {index + 1} ")
            if check is not None and (complaint := check(value)) is not None:
                raise self.error(name, f"item {index + 1} ({item!r}): {complaint}")
            if value in items:
                raise self.error(name, f"item {item!r} appears twice")
            items.append(value)
        return items

    def _checked(self, name: str, value: Any, kind: type[T],
                 check: Callable[[T], str | None] | None, what: str) -> T:
        coerced = _coerce(value, kind)
        if coerced is REQUIRED:
            raise self.error(name, f"{what}must be {_TYPE_NAMES.get(kind, kind.__name__)}, "
                                   f"got {_describe(value)}")
        if isinstance(coerced, float) and not math.isfinite(coerced):
            raise self.error(name, f"{what}must be a finite number, got {coerced!r}")
        if check is not None and (complaint := check(coerced)) is not None:
            raise self.error(name, complaint)
        return coerced

    def number(self, name: str, default: Any = REQUIRED, *, minimum: float | None = None,
               maximum: float | None = None, positive: bool = False, unit: str = "") -> float:
        """A finite number (ints count), within the given bounds."""
        return self.get(name, float, default, check=in_range(minimum, maximum, unit, positive))

    def integer(self, name: str, default: Any = REQUIRED, *, minimum: int | None = None,
                maximum: int | None = None) -> int:
        """An integer (not a boolean), within the given bounds."""
        return self.get(name, int, default, check=in_range(minimum, maximum))

    def string(self, name: str, default: Any = REQUIRED, *, choices: tuple[str, ...] = ()) -> str:
        """A string, one of ``choices`` when given."""
        return self.get(name, str, default, check=lambda v: one_of(v, choices))

    def table(self, name: str, required: bool = True) -> Table:
        """A sub-table (empty if optional and absent)."""
        if name not in self.data and not required:
            self._used.add(name)
            return Table({}, self.source, self.key(name))
        raw = self.raw(name)
        if not isinstance(raw, Mapping):
            raise self.error(name, f"must be a table, got {_describe(raw)}")
        return Table(raw, self.source, self.key(name))

    def tables(self, name: str, default: Any = REQUIRED) -> list[Table]:
        """An array of tables (``[[name]]``), each read through its own ``Table``."""
        value = self.raw(name, default)
        if not isinstance(value, list) or not all(isinstance(v, Mapping) for v in value):
            raise self.error(name, "must be an array of tables ([[...]] or [{...}, ...])")
        return [Table(v, self.source, f"{self.key(name)}[{i}]") for i, v in enumerate(value)]


def one_of(value: str, choices: tuple[str, ...] | list[str]) -> str | None:
    """The one "not a choice" message (None when ``value`` is one, or there are no choices)."""
    if not choices or value in choices:
        return None
    return f"must be one of {', '.join(choices)}; got {value!r}{did_you_mean(value, choices)}"


def _coerce(value: Any, kind: type) -> Any:
    """``value`` as ``kind`` if it is one (ints count as floats; bools never as numbers)."""
    if isinstance(value, bool) and kind is not bool:
        return REQUIRED
    if kind is float and isinstance(value, int | float):
        return float(value)
    if isinstance(value, kind):
        return value
    return REQUIRED


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"
