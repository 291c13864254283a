"""List-valued command-line flags: ``--sensors T1 T6,T8`` and ``--tests exp2, exp3`` alike."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from spindlebench.core.errors import SpindlebenchError


def split_list_flag(flag: str, values: str | Sequence[str] | None, what: str = "item",
                    error: type[SpindlebenchError] = SpindlebenchError) -> list[str] | None:
    """The names in a list flag's words, split at spaces and commas; None stays None.

    Both separators are accepted because users type either. A comma at either end of a word
    is a separator (``exp2, exp3`` unquoted); an empty item between two commas (``2,,3``) is
    an error, since it is usually a value left out.
    """
    if values is None:
        return None
    items = [values] if isinstance(values, str) else list(values)
    names: list[str] = []
    for item in items:
        text = item.strip()
        if len(items) > 1:
            text = text.strip(",").strip()
        pieces = [piece.strip() for piece in text.split(",")]
        if not all(pieces):
            raise error(f"{flag}: empty {what} in {' '.join(items)!r}")
        names.extend(pieces)
    return names


def expand_folders(paths: Sequence[str | Path], suffix: str, what: str) -> list[Path]:
    """File arguments as given, a folder as its ``*<suffix>`` files in name order; a folder
    without any is one line (``DIR: folder holds no .csv recording``)."""
    files: list[Path] = []
    for argument in paths:
        path = Path(argument)
        if path.is_dir():
            found = sorted(path.glob(f"*{suffix}"))
            if not found:
                raise SpindlebenchError(f"{path}: folder holds no {suffix} {what}")
            files.extend(found)
        else:
            files.append(path)
    return files
