"""Reading study files: TOML tables whose every key is checked, with one-line errors.

A study file is read through :class:`Table`, which remembers the file and the dotted key of
every value, so a wrong value is reported as ``study.toml: key 'axes.months': ...`` and an
unknown key (usually a typo) is never silently ignored.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

from spindlebench.errors import SpindlebenchError

T = TypeVar("T")

_MISSING: Any = object()

_TYPE_NAMES = {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
               list: "a list", dict: "a table"}


def load_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file; a missing file or a syntax error becomes a one-line error."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SpindlebenchError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SpindlebenchError(f"{path}: cannot read ({exc})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpindlebenchError(f"{path}: invalid TOML: {exc}") from None


class Table:
    """A TOML table that hands out checked values and rejects keys nobody asked for."""

    def __init__(self, data: dict[str, Any], source: str | Path, prefix: str = "") -> None:
        self.data = data
        self.source = str(source)
        self.prefix = prefix
        self._used: set[str] = set()

    def key(self, name: str) -> str:
        """The dotted key of ``name`` inside this table, as the user wrote it."""
        return f"{self.prefix}.{name}" if self.prefix else name

    def error(self, name: str, message: str) -> SpindlebenchError:
        """A one-line error about key ``name`` of this table."""
        return SpindlebenchError(f"{self.source}: key '{self.key(name)}': {message}")

    def has(self, name: str) -> bool:
        return name in self.data

    def get(self, name: str, kind: type[T], default: Any = _MISSING,
            check: Callable[[T], str | None] | None = None) -> T:
        """The value of ``name`` as ``kind``; ``check`` returns a complaint or None."""
        self._used.add(name)
        if name not in self.data:
            if default is _MISSING:
                raise self.error(name, "missing (required)")
            return default
        value = _coerce(self.data[name], kind)
        if value is _MISSING:
            raise self.error(name, f"must be {_TYPE_NAMES.get(kind, kind.__name__)}, "
                                   f"got {_describe(self.data[name])}")
        if not _finite(value):
            raise self.error(name, f"must be a finite number, got {value!r}")
        if check is not None and (complaint := check(value)) is not None:
            raise self.error(name, complaint)
        return value

    def get_list(self, name: str, kind: type[T], default: Any = _MISSING,
                 check: Callable[[T], str | None] | None = None,
                 allow_empty: bool = False) -> list[T]:
        """A list whose items are all ``kind`` (each checked); duplicates are rejected."""
        self._used.add(name)
        if name not in self.data:
            if default is _MISSING:
                raise self.error(name, "missing (required)")
            return list(default)
        raw = self.data[name]
        if not isinstance(raw, list):
            raise self.error(name, f"must be a list, got {_describe(raw)}")
        if not raw and not allow_empty:
            raise self.error(name, "must not be empty")
        items: list[T] = []
        for index, item in enumerate(raw):
            value = _coerce(item, kind)
            if value is _MISSING:
                raise self.error(name, f"item {index + 1} must be "
                                       f"{_TYPE_NAMES.get(kind, kind.__name__)}, "
                                       f"got {_describe(item)}")
            if not _finite(value):
                raise self.error(name, f"item {index + 1} must be a finite number, "
                                       f"got {value!r}")
            if check is not None and (complaint := check(value)) is not None:
                raise self.error(name, f"item {index + 1} ({item!r}): {complaint}")
            if value in items:
                raise self.error(name, f"item {item!r} appears twice")
            items.append(value)
        return items

    def table(self, name: str, required: bool = True) -> Table:
        """A sub-table (empty if optional and absent)."""
        self._used.add(name)
        if name not in self.data:
            if required:
                raise self.error(name, "missing table (required)")
            return Table({}, self.source, self.key(name))
        raw = self.data[name]
        if not isinstance(raw, dict):
            raise self.error(name, f"must be a table, got {_describe(raw)}")
        return Table(raw, self.source, self.key(name))

    def raw(self, name: str, default: Any = _MISSING) -> Any:
        """An unchecked value (for fragments that another module validates)."""
        self._used.add(name)
        if name not in self.data:
            if default is _MISSING:
                raise self.error(name, "missing (required)")
            return default
        return self.data[name]

    def names(self) -> Iterator[str]:
        return iter(self.data)

    def unused(self) -> list[str]:
        """Keys no reader has asked for yet."""
        return [name for name in self.data if name not in self._used]

    def finish(self) -> None:
        """Reject keys that no reader asked for: they are typos or unsupported options."""
        unknown = [name for name in self.data if name not in self._used]
        if unknown:
            raise self.error(unknown[0], "unknown key" + _suggest(unknown[0], self._used))


def _coerce(value: Any, kind: type) -> Any:
    """``value`` as ``kind`` if it is one (ints count as floats; bools never as numbers)."""
    if isinstance(value, bool) and kind is not bool:
        return _MISSING
    if kind is float and isinstance(value, int | float):
        return float(value)
    if isinstance(value, kind):
        return value
    return _MISSING


def _finite(value: Any) -> bool:
    """False for a NaN or infinite float: TOML allows them, no study value means them, and
    they slip past range checks (every comparison with NaN is false)."""
    return not isinstance(value, float) or math.isfinite(value)


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"


def _suggest(name: str, known: set[str]) -> str:
    import difflib

    close = difflib.get_close_matches(name, sorted(known), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def positive(value: float) -> str | None:
    return None if value > 0 else "must be > 0"


def non_negative(value: float) -> str | None:
    return None if value >= 0 else "must be >= 0"
