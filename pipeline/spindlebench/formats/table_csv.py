"""Recordings and result tables as CSV: the bytes of ``frame.to_csv(path, index=False,
lineterminator="\\n")``, written about twice as fast for the column types the project makes.

A sweep writes a thousand recordings and one result file per training run and condition
(over a thousand) in its one coordinating process, then ``results.csv`` with every row;
pandas' writer was most of that time. A frame of floats only (a recording) is written row by
row (its values by ``float_text``), any other frame column by column. Each column becomes its text
as pandas makes it (float: the shortest round trip, ``repr``; integer, nullable integer and
bool: ``str``; text as it is; missing: an empty field), a cell holding the delimiter or the
quote is quoted as the ``csv`` module's ``QUOTE_MINIMAL`` (which pandas uses) quotes it (in
``"``, inner ``"`` doubled), and the rows are the cells joined by commas. Any other column
type, a line break in a cell, or a frame pandas writes in a special way (one column, no
rows, names that are not unique strings) is written by pandas itself.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import orjson

from spindlebench.formats.float_text import csv_rows, float_cells

if TYPE_CHECKING:  # imported where a frame is written: reading recordings needs no pandas
    import pandas as pd


def floats_only(frame: pd.DataFrame) -> bool:
    """Whether ``write_table`` writes ``frame`` row by row, every value as its ``repr`` (NaN
    an empty field): all float64, more than one column, names that need no quoting."""
    names = list(map(str, frame.columns.tolist()))  # tolist: not one boxed name at a time
    joined = "\0".join(names)  # one scan of all names for a character that needs quoting
    return frame.shape[1] > 1 and set(frame.dtypes.tolist()) == _FLOAT64 \
        and all(names) and not any(mark in joined for mark in ',"\r\n')


#: The dtypes of a frame of floats only (a set: one comparison for a recording's ~150 columns).
_FLOAT64 = {np.dtype(np.float64)}


def write_table(path: str | os.PathLike[str], frame: pd.DataFrame) -> bytes | None:
    """``frame.to_csv(path, index=False, lineterminator="\\n")``, the same bytes (tested);
    returns them (None where pandas wrote the frame itself), so a caller that records the
    file's hash takes it from memory instead of reading the file back."""
    data = table_bytes(frame)
    if data is None:
        frame.to_csv(path, index=False, lineterminator="\n")
        return None
    Path(path).write_bytes(data)
    return data


def table_bytes(frame: pd.DataFrame) -> bytes | None:
    """The bytes ``write_table`` writes, or None where pandas is left to write the frame."""
    if floats_only(frame):
        header = ",".join(map(str, frame.columns.tolist()))
        return f"{header}\n".encode() + csv_rows(frame.to_numpy())
    columns = _column_texts(frame)
    if columns is None:
        return None
    lines = [",".join(columns[0]), *map(",".join, zip(*columns[1:], strict=True))]
    return ("\n".join(lines) + "\n").encode("utf-8")


def _column_texts(frame: pd.DataFrame) -> list[list[str]] | None:
    """The header's names, then each column's cells, as written; None where pandas is left
    to write the frame.

    Only text (the names, text columns) is looked at for line breaks and quoted: a number's
    text has neither a comma, a quote nor a line break (``results.csv``'s five number
    columns, 1.9 million cells, were joined just to be searched). A column to quote is
    quoted once per distinct cell (a sweep's ``selected`` column holds a few hundred sets of
    sensors over its 380 000 rows)."""
    names = frame.columns.tolist()
    if frame.shape[1] < 2 or not len(frame) or \
            not all(isinstance(name, str) for name in names) or len(set(names)) < len(names):
        return None
    texts = [names]
    free_text = [True]  # whether the cells may need quoting (numbers' never do)
    for _, column in frame.items():
        cells = _cells(column)
        if cells is None:
            return None
        texts.append(cells)
        free_text.append(not _numeric(column.dtype))
    for number, cells in enumerate(texts):
        if not free_text[number]:
            continue
        try:
            joined = "\0".join(cells)
        except TypeError:  # a text column's missing cells, left for this join to find
            cells = texts[number] = [cell if isinstance(cell, str) else "" for cell in cells]
            joined = "\0".join(cells)
        if "\n" in joined or "\r" in joined:
            return None
        if "," in joined or '"' in joined:
            quoted = {cell: _quoted(cell) for cell in set(cells)}
            texts[number] = list(map(quoted.__getitem__, cells))
    return texts


def _quoted(cell: str) -> str:
    return '"' + cell.replace('"', '""') + '"' if "," in cell or '"' in cell else cell


def _numeric(dtype: object) -> bool:
    """Whether ``_cells`` writes a column of ``dtype`` as numbers (or True/False) only."""
    import pandas as pd

    return dtype in (np.float64, np.int64, np.bool_) or isinstance(dtype, pd.Int64Dtype)


def _cells(column: pd.Series) -> list[str] | None:
    import pandas as pd

    dtype = column.dtype
    if dtype == np.float64:
        return float_cells(column.to_numpy())
    if dtype == np.int64:
        return _integer_cells(column.to_numpy())
    if dtype == np.bool_:
        return list(map(str, column.to_numpy().tolist()))
    if isinstance(dtype, pd.StringDtype):  # every cell a str or missing (blanked later:
        return column.to_numpy(dtype=object).tolist()  # looking for them took 3x as long)
    if isinstance(dtype, pd.Int64Dtype):  # every cell an int or missing
        values = column.array
        return _blank(_integer_cells(values.to_numpy(dtype=np.int64, na_value=0)),
                      values.isna())
    if pd.api.types.is_object_dtype(dtype):
        missing = column.isna().to_numpy()
        values = column.to_numpy(dtype=object, na_value="").tolist()
        if not all(type(value) is str or gap for value, gap in
                   zip(values, missing.tolist(), strict=True)):
            return None
        return _blank(list(map(str, values)), missing)
    return None


def _integer_cells(values: np.ndarray) -> list[str]:
    """Each int64 as ``str`` writes it: orjson's text of the array (the same decimal
    digits and sign), cut at its commas, in a fifth of the time of ``str`` on each."""
    if not values.size:
        return []
    return orjson.dumps(values, option=orjson.OPT_SERIALIZE_NUMPY)[1:-1].decode().split(",")


def _blank(cells: list[str], missing: np.ndarray) -> list[str]:
    for index in np.flatnonzero(missing).tolist():
        cells[index] = ""
    return cells
