"""The whole protocol on recordings: select on one experiment, fit, predict the others.

``evaluate`` is what ``spindlebench evaluate`` and the paper comparison call. Candidates are
the sensors (plus their pairwise differences), as rises relative to each experiment's first
sample; the target (thermal error, um) is used as recorded (canonical recordings zero it at the
first sample, like a displacement probe).

Missing values (the testbench's sensor dropout, a logger gap) are an error by default.
``missing="drop-rows"`` drops, with a ``SelectionWarning``, every sample where the target or a
sensor the step uses is missing, *before* rises and differences are computed, so the rise
reference is the first complete sample; nothing is ever filled in. The training recording is
checked on all candidate sensors; a test recording only on the sensors the fitted model reads
(a gap in an unselected sensor costs no test samples). The target is still used as recorded:
a gap at the very start leaves the drift accumulated by the first complete sample in it, which
the intercept absorbs when training but a test RMSE does not. A sensor missing in more than
half of the training samples is left out as a candidate (warned) rather than costing most of
the experiment; an experiment left with fewer than 2 complete samples is an error.
"""

from __future__ import annotations

import functools
import math
import os
import sys
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Union

import numpy as np

from spindlebench.core.names import DEFAULT_SIMILARITY, MISSING_MODES
from spindlebench.formats.recording import (
    MissingValueError,
    RecordingTable,
    default_sensors,
    read_table,
    recording_name,
)
from spindlebench.selection.differences import difference_names, pair_indices
from spindlebench.selection.dynamic import (
    check_drivers,
    driver_columns,
    is_dynamic,
    model_inputs,
    reads_rises,
)
from spindlebench.selection.errors import (
    SelectionError,
    SelectionOverflowError,
    SelectionWarning,
    column_list,
)
from spindlebench.selection.method_registry import METHOD_REGISTRY
from spindlebench.selection.pairs import ROW_WISE_ABOVE, PairCandidates
from spindlebench.selection.registry import (
    MethodChoice,
    fit_with,
    select_with,
    sensitive_points,
)
from spindlebench.selection.regression import (
    EstimatorFit,
    LinearFit,
    rises,
    rmse,
    rmse_each,
    rmse_rows,
)
from spindlebench.selection.select import Selection
from spindlebench.selection.similarity import constant_columns

if TYPE_CHECKING:  # pandas only where a DataFrame is given: the command line needs none
    import pandas as pd

RecordingLike = Union[str, os.PathLike[str], "pd.DataFrame", RecordingTable]


def _is_frame(value: object) -> bool:
    """Whether ``value`` is a DataFrame (none can be before pandas is imported)."""
    pandas = sys.modules.get("pandas")
    return pandas is not None and isinstance(value, pandas.DataFrame)
#: Choices inside clusters and regressors whose result depends on ``seed``.
SEEDED_PARTS = ("ga", "gbr", "mlp")


def seeded(choice: MethodChoice) -> bool:
    """Whether ``choice``'s result depends on the seed (a registry method marked ``seeded``,
    a seeded part, or a user's class, which may: say so)."""
    entry = METHOD_REGISTRY.get(choice.method)
    return ((entry is not None and entry.seeded) or choice.within in SEEDED_PARTS
            or choice.regressor in SEEDED_PARTS or is_dynamic(choice.regressor)
            or choice.user_method is not None
            or choice.user_regressor is not None)

#: ``CandidateSet.matrix`` builds at most this many candidates column by column.
FEW_CANDIDATES = 8
#: A sensor missing in more than this fraction of the training samples stops being a candidate.
SPARSE_SENSOR_FRACTION = 0.5
_DROP_HINT = "missing='drop-rows' (--missing drop-rows) drops incomplete samples"


class CheckedRecording:
    """A recording's columns as float arrays, each converted and checked at most once.

    Why: a study scores many methods and k on the same recordings; ``evaluate`` converting
    and checking every column of every recording again per call was most of a sweep's time.
    ``take(rows)`` is the same recording restricted to some samples (positions), sharing the
    conversions; its values are exactly ``frame.iloc[rows][column].to_numpy(dtype=float)``.
    ``frame`` is a DataFrame or a ``RecordingTable`` (``read_table``: already one float
    block).
    """

    def __init__(self, name: str, frame: pd.DataFrame | RecordingTable) -> None:
        self.name = name
        self.frame = frame
        self._rows: np.ndarray | None = None
        self._parent: CheckedRecording | None = None
        self._values: dict[str, np.ndarray] = {}
        self._nan: dict[str, np.ndarray] = {}
        self._any_nan: dict[str, bool] = {}
        self._rises: dict[tuple[str, ...], np.ndarray] = {}
        self._column_rises: dict[str, np.ndarray | None] = {}
        self._column_set: frozenset | None = None
        self._no_nan: bool | None = None
        self._finite: bool | None = None
        self._memo: dict[Any, Any] = {}
        self._length = len(frame)
        self._problems: dict[tuple[str, str], str | None] = {}
        self._block: np.ndarray | None = None
        self._positions: dict[str, int] = {}

    def __len__(self) -> int:
        return self._length

    @property
    def columns(self) -> pd.Index | tuple[str, ...]:
        return self.frame.columns

    @property
    def column_set(self) -> frozenset:
        """The column names as a set, made once (``resolve_sensors`` tests many names)."""
        if self._column_set is None:
            self._column_set = frozenset(self.frame.columns)
        return self._column_set

    def take(self, rows: np.ndarray) -> CheckedRecording:
        """The samples at positions ``rows`` (of this recording) only."""
        part = CheckedRecording(self.name, self.frame)
        part._rows, part._parent = np.asarray(rows), self
        part._length = len(part._rows)
        return part

    def values(self, column: str) -> np.ndarray:
        """The column as float64 (read-only use: shared by every caller)."""
        if column not in self._values:
            if self._parent is not None:
                self._values[column] = self._parent.values(column)[self._rows]
            elif self._float_block() is not None and column in self._positions:
                self._values[column] = self._float_block()[:, self._positions[column]]
            else:
                self._values[column] = self.frame[column].to_numpy(dtype=float)
        return self._values[column]

    def _float_block(self) -> np.ndarray | None:
        """All columns as one float64 array when pandas gives them so in common and each
        is named once (a float64 frame's own columns are then views of it; one conversion
        instead of one lookup per column).

        Asked of ``to_numpy``'s dtype, not of ``frame.dtypes`` (a Series pandas builds per
        call: most of the conversion's time, once per recording of every evaluation): it
        is float64 for float64 columns, and for ints or narrower floats beside them, whose
        values it converts as ``frame[column].to_numpy(dtype=float)`` converts each (and
        which hold no NaN or infinity, so ``problem`` finds the same on either); text,
        booleans and nullable columns give another dtype."""
        if self._block is None and not self._positions:
            frame = self.frame
            if isinstance(frame, RecordingTable):
                self._block = frame.values
                self._positions = {column: i for i, column in enumerate(frame.columns)}
            elif frame.columns.is_unique and (block := frame.to_numpy()).dtype == np.float64:
                self._block = block
                self._positions = {column: i for i, column in enumerate(frame.columns)}
            else:
                self._positions = {"": -1}  # looked: not one float block
        return self._block

    def is_nan(self, column: str) -> np.ndarray:
        """Where ``column`` is NaN (read-only use)."""
        if column not in self._nan:
            self._nan[column] = np.isnan(self.values(column))
        return self._nan[column]

    def complete(self, columns: tuple[str, ...]) -> bool:
        """Whether none of ``columns`` has a NaN (every model of a study asks it again of
        each test run): at once when the recording has none anywhere, else kept per column
        list."""
        return self._nan_free() or self.memo(
            ("complete", columns), lambda: not any(self.has_nan(column) for column in columns))

    def _nan_free(self) -> bool:
        """Whether no column has a NaN (one scan of the float block, made once; False when
        the recording is not one float block). A part is when its whole recording is."""
        if self._parent is not None:
            return self._parent._nan_free()
        if self._no_nan is None:
            block = self._float_block()
            self._no_nan = self.all_finite() or (
                block is not None and not bool(np.isnan(block).any()))
        return self._no_nan

    def all_finite(self) -> bool:
        """Whether every column is float64 and finite (one scan of the float block, made
        once; False when the recording is not one float block): then no column has a
        ``problem``. A part is when its whole recording is."""
        if self._parent is not None:
            return self._parent.all_finite()
        if self._finite is None:
            block = self._float_block()
            self._finite = block is not None and bool(np.isfinite(block).all())
        return self._finite

    def has_nan(self, column: str) -> bool:
        """Whether ``column`` has a NaN anywhere."""
        if column not in self._any_nan:
            self._any_nan[column] = bool(self.is_nan(column).any())
        return self._any_nan[column]

    def stack(self, columns: Sequence[str]) -> np.ndarray:
        """``columns`` side by side, (samples, len(columns))."""
        out = np.empty((len(self), len(columns)))
        for i, column in enumerate(columns):
            out[:, i] = self.values(column)
        return out

    def memo(self, key: Any, compute: Callable[[], Any]) -> Any:
        """``compute()`` the first time ``key`` is asked for, then kept (for values that
        depend on this recording and ``key`` only; read-only use)."""
        if key not in self._memo:
            self._memo[key] = compute()
        return self._memo[key]

    def rises(self, columns: Sequence[str]) -> np.ndarray:
        """``rises(self.stack(columns))``, made once per column list (read-only use: every
        method and k of a study reads the same sensors' rises of a test run again)."""
        key = tuple(columns)
        if key not in self._rises:
            self._rises[key] = rises(self.stack(columns))
        return self._rises[key]

    def column_rises(self, columns: Sequence[str]) -> list[np.ndarray]:
        """The columns of ``self.rises(columns)``, each made once per column (read-only use).

        Why: each of a study's many models reads the rises of a few sensors of every test
        run, a different few each; a rise is one subtraction per sample, so a column's is the
        same whatever list it is made in. A column whose reference (first) value is not
        finite while later ones are takes ``self.rises(columns)``, which raises its error."""
        out = []
        for column in columns:
            if column not in self._column_rises:
                values = self.values(column)
                bad = len(values) == 0 or (not math.isfinite(values[0])
                                            and bool(np.isfinite(values).any()))
                self._column_rises[column] = None if bad else values - values[0]
            rise = self._column_rises[column]
            if rise is None:
                return list(self.rises(columns).T)
            out.append(rise)
        return out

    def missing(self, columns: Sequence[str]) -> np.ndarray:
        """Where ``columns`` are missing (NaN), (samples, len(columns)); for checked columns."""
        out = np.empty((len(self), len(columns)), dtype=bool)
        for i, column in enumerate(columns):
            out[:, i] = self.is_nan(column)
        return out

    def problem(self, column: str, missing: str) -> str | None:
        """Why ``column`` cannot be used (one line without the recording's name), or None."""
        key = (column, missing)
        if key not in self._problems:
            block = self._float_block()
            values = block[:, self._positions[column]] if block is not None \
                and column in self._positions else None
            self._problems[key] = _column_problem(self.frame, column, missing, values)
        return self._problems[key]


def _column_problem(frame: pd.DataFrame | RecordingTable, column: str, missing: str,
                    values: np.ndarray | None = None) -> str | None:
    """Text, booleans and infinities never pass; NaN only with ``missing="drop-rows"``.
    ``values``: the column, known to be float64 (skips the frame lookup)."""
    if values is None and isinstance(frame, RecordingTable):
        values = frame[column]
    if values is None:
        import pandas as pd

        cells = frame[column]
        if isinstance(cells, pd.Series) and cells.dtype == np.float64:
            values = cells.to_numpy()
    if values is not None:  # the common case: only infinities and NaN to look for
        infinite = np.isinf(values)
        if infinite.any():
            first = int(np.flatnonzero(infinite)[0])
            return (f"{_where(frame, first)}, column '{column}': infinite value "
                    f"{str(values[first])!r}")
        nan = np.isnan(values)
        if missing == "error" and nan.any():
            first = int(np.flatnonzero(nan)[0])
            return (f"{_where(frame, first)}, column '{column}': missing value "
                    f"({int(nan.sum())} in this column); {_DROP_HINT}")
        return None
    import pandas as pd

    cells = frame[column]
    numeric = pd.to_numeric(cells, errors="coerce")
    values = numeric.to_numpy(dtype=float)
    nan = np.isnan(values)
    given = cells.notna().to_numpy(dtype=bool)
    if pd.api.types.is_bool_dtype(cells):
        return f"column '{column}': boolean values"
    bad = np.flatnonzero(np.isinf(values) | (nan & given))
    if bad.size:
        first = int(bad[0])
        what = "infinite value" if np.isinf(values[first]) else "non-numeric value"
        return (f"{_where(frame, first)}, column '{column}': {what} "
                f"{str(cells.iloc[first])!r}")
    if missing == "error" and nan.any():
        first = int(np.flatnonzero(nan)[0])
        return (f"{_where(frame, first)}, column '{column}': missing value "
                f"({int(nan.sum())} in this column); {_DROP_HINT}")
    return None


@dataclass(frozen=True)
class CandidateSet:
    """Raw sensors plus (optionally) their pairwise differences, as rises, any subset of columns."""

    sensors: tuple[str, ...]
    differences: bool

    @property
    def names(self) -> list[str]:
        """Candidate names: sensors, then ``A-B`` differences."""
        names = list(self.sensors)
        return names + difference_names(names) if self.differences else names

    def matrix(self, frame: pd.DataFrame | CheckedRecording,
               columns: Sequence[int] | None = None) -> np.ndarray:
        """Candidate values (rises) of ``frame`` (or of a checked recording); only
        ``columns`` if given.

        Only the sensors those candidates are made of are read: with ``missing="drop-rows"``
        a test recording is complete only in those, and an unused sensor's gap must not
        matter."""
        n = len(self.sensors)
        size = self.size
        if isinstance(frame, CheckedRecording) and (
                size if columns is None else len(columns)) <= FEW_CANDIDATES:
            # a model's few candidates, column by column: the same subtractions, without
            # the all-sensors block (most of the time of each of a study's many calls)
            needed, parts = _few_candidates(self, tuple(range(size)) if columns is None
                                            else tuple(int(column) for column in columns))
            rise = dict(zip(needed, frame.column_rises(needed), strict=True))
            out = np.empty((len(frame), len(parts)))
            for j, (a, b) in enumerate(parts):
                out[:, j] = rise[a] if b is None else rise[a] - rise[b]
            return out
        wanted = np.arange(size) if columns is None else np.asarray(columns, int)
        self._check_columns(wanted)
        needed = self.sensors_of(wanted)
        first, second = pair_indices(n)
        raw = np.full((len(frame), n), np.nan)
        raw[:, [self.sensors.index(s) for s in needed]] = frame.rises(needed) if isinstance(
            frame, CheckedRecording) else rises(frame.loc[:, needed].to_numpy(dtype=float))
        is_raw = wanted < n
        pair = wanted[~is_raw] - n  # index into the pair list
        out = np.empty((raw.shape[0], wanted.size))
        out[:, is_raw] = raw[:, wanted[is_raw]]
        out[:, ~is_raw] = raw[:, first[pair]] - raw[:, second[pair]]
        return out

    @property
    def size(self) -> int:
        """``len(self.names)``, without naming them."""
        n = len(self.sensors)
        return n + n * (n - 1) // 2 if self.differences else n

    def _check_columns(self, columns: np.ndarray) -> None:
        """Refuse candidate indices outside ``0..size - 1``."""
        if columns.size and (columns.min() < 0 or columns.max() >= self.size):
            raise SelectionError(f"candidate index out of range 0..{self.size - 1}")

    def sensors_of(self, columns: Sequence[int]) -> list[str]:
        """The raw sensors that candidates ``columns`` are made of, in sensor order."""
        n = len(self.sensors)
        first, second = pair_indices(n)
        used: set[int] = set()
        for column in columns:
            if column < n:
                used.add(int(column))
            else:
                used.update((int(first[column - n]), int(second[column - n])))
        return [self.sensors[i] for i in sorted(used)]


@functools.lru_cache(maxsize=4096)
def _few_candidates(candidates: CandidateSet, columns: tuple[int, ...]
                    ) -> tuple[list[str], list[tuple[str, str | None]]]:
    """The sensors that candidates ``columns`` are made of, and each candidate as (sensor,
    None) or the pair (A, B) of ``A-B``: worked out once per candidate set and columns (a
    study makes the same few candidates of every held-out run)."""
    candidates._check_columns(np.asarray(columns, int))
    n = len(candidates.sensors)
    first, second = pair_indices(n)
    sensors = candidates.sensors
    parts: list[tuple[str, str | None]] = [
        (sensors[column], None) if column < n
        else (sensors[first[column - n]], sensors[second[column - n]]) for column in columns]
    return candidates.sensors_of(columns), parts


@dataclass(frozen=True)
class Evaluation:
    """Result of ``evaluate``; ``to_dict()`` is the ``spindlebench evaluate --json`` shape."""

    train: str
    target: str
    sensors: list[str]
    candidates: list[str]
    selection: Selection
    fit: LinearFit | EstimatorFit
    predictions: dict[str, np.ndarray]
    measured: dict[str, np.ndarray]
    rmse_um: dict[str, float]
    #: Positions (0-based) of the samples of each recording the result used: all of them
    #: unless ``missing="drop-rows"`` dropped incomplete ones. ``predictions`` and ``measured``
    #: hold those samples only.
    train_rows: np.ndarray = field(default_factory=lambda: np.arange(0))
    test_rows: dict[str, np.ndarray] = field(default_factory=dict)
    #: The selection method, choice inside clusters and regressor (default: the paper's).
    method: MethodChoice = field(default_factory=MethodChoice)
    #: Seed of the seeded methods (fcm, kmeans, stability); recorded, used by those only.
    seed: int = 0

    @property
    def selected(self) -> list[str]:
        """Selected candidate names, one per cluster."""
        return [self.candidates[i] for i in self.selection.selected]

    @property
    def psi(self) -> list[float]:
        """psi (signed correlation with the error) of each selected candidate."""
        return [float(value) for value in self.selection.selected_psi]

    @property
    def clusters(self) -> list[list[str]]:
        """Candidate names of each cluster."""
        return [[self.candidates[i] for i in members] for members in self.selection.clusters]

    @property
    def coefficients(self) -> dict[str, float] | None:
        """Intercept, then one coefficient per selected candidate (um per K); None for a
        model that is not linear (``regression.EstimatorFit``)."""
        if self.fit.coefficients is None:
            return None
        out = {"intercept": float(self.fit.intercept)}
        out.update(zip(self.selected, map(float, self.fit.coefficients), strict=True))
        return out

    @property
    def mean_rmse_um(self) -> float:
        """Mean of the per-experiment RMSE."""
        return float(np.mean(list(self.rmse_um.values())))

    def to_dict(self) -> dict[str, Any]:
        """The JSON shape of ``spindlebench evaluate --json`` (without provenance)."""
        return {
            "selected": self.selected,
            "psi": self.psi,
            "eta": _finite_or_none(float(self.selection.eta)),
            "clusters": self.clusters,
            "coefficients": self.coefficients,
            "r2": _finite_or_none(self.fit.r2),
            "rmse_um": {name: float(value) for name, value in self.rmse_um.items()},
            "mean_rmse_um": self.mean_rmse_um,
            "method": {**self.method.to_dict(), "label": self.method.label, "seed": self.seed},
            **({"penalty": penalty} if (penalty := getattr(self.fit, "penalty", None))
               is not None else {}),
        }

    def summary(self) -> str:
        """A readable multi-line report."""
        lines = [
            f"train: {self.train}   target: {self.target}   "
            f"candidates: {len(self.candidates)} ({len(self.selection.dropped)} constant dropped)",
            f"method: {self.method.label}"
            + (f" (seed {self.seed})" if seeded(self.method) else ""),
            f"clusters: {len(self.selection.clusters)}"
            + (f" at eta = {self.selection.eta:.6f}" if math.isfinite(self.selection.eta)
               else ""),
        ]
        for number, (members, chosen, psi) in enumerate(
            zip(self.clusters, self.selected, self.psi, strict=True), start=1
        ):
            shown = ", ".join(members[:8]) + (f", ... ({len(members)})" if len(members) > 8 else "")
            lines.append(f"  {number}: keep {chosen} (psi = {psi:+.4f}) from [{shown}]")
        if is_dynamic(self.method.regressor):
            reads = ", ".join(driver_columns(self.method.regressor)[1:])
            if reads_rises(self.method.regressor):
                reads += f" and d({'), d('.join(self.selected)})"
            lines.append(f"model: {self.target} = {type(self.fit.estimator).__name__} of "
                         f"{reads} along time_s (dynamic: no coefficients)")
        elif self.coefficients is None:
            lines.append(f"model: {self.target} = {type(self.fit.estimator).__name__} of "
                         f"d({'), d('.join(self.selected)}) (not linear: no coefficients)")
        else:
            terms = " ".join(
                f"{value:+.4g}*d({name})" for name, value in list(self.coefficients.items())[1:]
            )
            lines.append(f"model: {self.target} = {self.fit.intercept:.4g} {terms}")
        lines.append(f"training R2: {self.fit.r2:.4f}")
        lines.append("RMSE on the other experiments (um):")
        width = max(len(name) for name in self.rmse_um)
        for name, value in self.rmse_um.items():
            lines.append(f"  {name:<{width}}  {value:8.3f}")
        lines.append(f"  {'mean':<{width}}  {self.mean_rmse_um:8.3f}")
        return "\n".join(lines)


@contextmanager
def _naming(name: str) -> Iterator[None]:
    """Put the recording's name in front of an error from the numerics below (an overflow,
    or too few distinguishable candidates in a two-row recording) that does not name one."""
    try:
        yield
    except SelectionError as exc:
        named = _named(exc, name)
        if named is exc:
            raise
        raise named from exc


def _named(exc: Exception, name: str) -> Exception:
    """``exc`` with the recording's name in front (``_naming``): a ``SelectionError`` that does
    not name one yet becomes a new one of its type (its cause ``exc``); any other as it is."""
    if not isinstance(exc, SelectionError) or str(exc).startswith("recording "):
        return exc
    named = type(exc)(f"recording {name}: {exc}")
    named.__cause__ = exc
    return named


def row_wise(candidates: CandidateSet, similarity: str, closure: str) -> bool:
    """Whether the selection runs row-wise (``selection.pairs``): sensors plus differences,
    more than ``ROW_WISE_ABOVE`` candidates, |Pearson r| and the fast closure. Smaller sets
    keep the matrix path (results unchanged to the last bit); the row-wise path gives the same
    clusters and psi, and eta to rounding."""
    return (candidates.differences and len(candidates.names) > ROW_WISE_ABOVE
            and similarity == DEFAULT_SIMILARITY and closure == "fast")


def _finite(matrix: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """``matrix`` (rises, differences), or an overflow error naming the first columns where
    subtracting two finite values gave inf (|values| near 1e308)."""
    if np.isfinite(matrix).all():  # the common case in one pass: nothing to name
        return matrix
    with np.errstate(over="ignore", invalid="ignore"):
        bad = np.flatnonzero(~np.isfinite(matrix).all(axis=0))
    if bad.size:
        raise SelectionOverflowError(
            f"values too large for rises and differences (overflow) in {column_list(bad, names)}"
        )
    return matrix


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _load(recording: RecordingLike, fallback: str,
          missing: str) -> tuple[str, pd.DataFrame | RecordingTable]:
    if isinstance(recording, RecordingTable) or _is_frame(recording):
        return recording_name(recording, fallback), recording
    try:
        return str(recording), read_table(
            Path(recording), allow_missing=missing == "drop-rows"
        )
    except MissingValueError as exc:
        raise SelectionError(f"{exc}; {_DROP_HINT}") from exc


def _where(frame: pd.DataFrame | RecordingTable, position: int) -> str:
    """``line N`` of the file a frame was read from, else ``row <index label>``."""
    if isinstance(frame, RecordingTable):
        return f"line {position + 2}"
    import pandas as pd

    index = frame.index
    if "path" in frame.attrs and isinstance(index, pd.RangeIndex) and index.start == 0 \
            and index.step == 1:
        return f"line {position + 2}"
    return f"row {index[position]}"


def _check_values(recording: CheckedRecording, columns: Sequence[str], missing: str) -> None:
    """Frames handed in directly skip ``read_recording``: check the columns used. NaN passes
    only with ``missing="drop-rows"``; text, booleans and infinities never do."""
    if len(recording) < 2:
        raise SelectionError(
            f"recording {recording.name}: has {len(recording)} row(s); an experiment needs at "
            "least 2"
        )
    if recording.all_finite():  # every column float64 and finite: nothing to refuse
        return
    for column in columns:
        problem = recording.problem(column, missing)
        if problem:
            raise SelectionError(f"recording {recording.name}, {problem}")


def _sparse_sensors(recording: CheckedRecording, sensors: list[str]) -> list[str]:
    """``sensors`` without those missing in more than ``SPARSE_SENSOR_FRACTION`` of the
    samples of ``recording`` (warned); an error if none is left."""
    name = recording.name
    if recording.complete(tuple(sensors)):  # the common case: nothing missing anywhere
        return sensors
    fractions = {s: float(np.isnan(recording.values(s)).mean()) for s in sensors}
    sparse = [s for s in sensors if fractions[s] > SPARSE_SENSOR_FRACTION]
    if not sparse:
        return sensors
    kept = [s for s in sensors if s not in sparse]
    shown = ", ".join(f"{s} ({fractions[s]:.0%})" for s in sparse)
    if not kept:
        raise SelectionError(
            f"recording {name}: every sensor is missing in more than half of the samples: {shown}"
        )
    warnings.warn(
        f"recording {name}: left out sensor(s) missing in more than half of the samples: "
        f"{shown}",
        SelectionWarning,
        stacklevel=4,
    )
    return kept


def _complete_rows(recording: CheckedRecording, columns: Sequence[str]) -> np.ndarray:
    """Positions of the samples where every one of ``columns`` is present (warned when some
    are not); an error if fewer than 2 are left."""
    name, frame = recording.name, recording.frame
    if recording.complete(tuple(columns)):
        return np.arange(len(recording))
    missing = recording.missing(list(columns))
    incomplete = missing.any(axis=1)
    rows = np.flatnonzero(~incomplete)
    if not incomplete.any():
        return rows
    counts = missing.sum(axis=0)
    shown = ", ".join(f"{c}: {int(n)}" for c, n in zip(columns, counts, strict=True) if n)
    if rows.size < 2:
        raise SelectionError(
            f"recording {name}: {rows.size} complete sample(s) after dropping the incomplete "
            f"ones ({shown}); an experiment needs at least 2"
        )
    warnings.warn(
        f"recording {name}: dropped {int(incomplete.sum())} of {len(frame)} samples with "
        f"missing values ({shown}); rises start at the first complete sample "
        f"({_where(frame, int(rows[0]))})",
        SelectionWarning,
        stacklevel=4,
    )
    return rows


def resolve_sensors(
    train: CheckedRecording,
    tests: Mapping[str, CheckedRecording],
    target: str,
    sensors: Sequence[str] | None,
) -> list[str]:
    """The sensor list, checked against every recording (each named as ``tests`` names it).

    Membership is tested on each recording's ``column_set``: a study asks this of the same
    recordings for every model, and a pandas ``Index`` lookup per column and recording was
    some 3 % of an evaluation."""
    for name, recording in [(train.name, train), *tests.items()]:
        if target not in recording.column_set:
            raise SelectionError(f"recording {name}: target column '{target}' not found")
    if sensors is not None:
        sensors = [str(sensor) for sensor in sensors]
        if not sensors:
            raise SelectionError("the sensor list is empty")
        repeated = sorted({s for s in sensors if sensors.count(s) > 1})
        if repeated:
            raise SelectionError(f"sensor(s) listed twice: {', '.join(repeated)}")
        if target in sensors:
            raise SelectionError(f"the target '{target}' is also listed as a sensor")
        for name, recording in [(train.name, train), *tests.items()]:
            columns = recording.column_set
            missing = [sensor for sensor in sensors if sensor not in columns]
            if missing:
                raise SelectionError(
                    f"recording {name}: sensor column(s) not found: {', '.join(missing)}"
                )
        return sensors
    chosen = default_sensors(train.frame, target)
    if not chosen:
        raise SelectionError(f"recording {train.name}: no sensor columns found; pass --sensors")
    for name, recording in tests.items():
        check_same_sensors(name, default_sensors(recording.frame, target), chosen, train.name)
    return chosen


def _resolved_sensors(train: CheckedRecording, tests: Mapping[str, CheckedRecording],
                      target: str, sensors: Sequence[str] | None) -> list[str]:
    """``resolve_sensors``, made once per training recording, test recordings, target and
    sensor list (a study asks it again of the same recordings for each of its models, some
    0.3 ms each time); a check that fails is not kept, so it raises again."""
    recordings = tuple(tests.values())
    listed = None if sensors is None else tuple(str(sensor) for sensor in sensors)
    # kept by the training recording: the memo holds the test recordings, so their ids
    # name them while it lives
    key = ("resolved sensors", tuple(map(id, recordings)), target, listed)
    resolved = train.memo(key, lambda: (recordings,
                                        resolve_sensors(train, tests, target, sensors)))[1]
    return list(resolved)


def check_same_sensors(name: str, theirs: Sequence[str], chosen: Sequence[str],
                       train_name: str) -> None:
    """A held-out recording must offer the training file's sensors, found by the same rule
    (in any order: they are read by name)."""
    if set(theirs) != set(chosen):
        missing = [s for s in chosen if s not in theirs]
        extra = [s for s in theirs if s not in chosen]
        raise SelectionError(
            f"recording {name}: sensor columns differ from the training file {train_name} "
            f"(missing: {missing or 'none'}; extra: {extra or 'none'}); pass --sensors"
        )


def _check_missing_mode(missing: str) -> None:
    if missing not in MISSING_MODES:
        raise SelectionError(f"missing: {missing!r} is not one of {', '.join(MISSING_MODES)}")


def evaluate(
    train: RecordingLike,
    tests: RecordingLike | Sequence[RecordingLike] | Mapping[str, RecordingLike],
    target: str,
    sensors: Sequence[str] | None = None,
    k: int = 2,
    differences: bool = False,
    similarity: str = DEFAULT_SIMILARITY,
    closure: str = "fast",
    missing: str = "error",
    method: str | MethodChoice = "closure",
    within: str = "psi",
    regressor: str = "ols",
    seed: int = 0,
) -> Evaluation:
    """Select ``k`` points on ``train``, fit the rise model, and score it on every test.

    Recordings are paths (read with ``read_table``), DataFrames or ``RecordingTable``s
    (``read_table``, ``read_table_with_roles``); ``tests`` is a list of
    them, a single one, or a mapping from display name to recording (default names: the
    paths). ``sensors`` None means
    ``default_sensors`` of the training file, and every test file must then have exactly the
    same sensor columns; with explicit ``sensors`` the files only need to contain them.
    ``missing`` is ``"error"`` or ``"drop-rows"`` (see the module docstring).
    ``method``, ``within`` and ``regressor`` choose the method (``method_registry.METHOD_REGISTRY``
    ...; the default is the paper's); ``method`` may also be a ``MethodChoice``. ``seed`` seeds
    the registry's seeded methods (fcm, kmeans, stability).
    Warnings (``SelectionWarning``): constant candidates dropped, ties in the cut, and with
    ``"drop-rows"`` incomplete samples dropped and sparse sensors left out.
    Errors (``SelectionError``, one line naming the file): missing target or sensor columns,
    differing sensor sets, missing (unless dropped) or non-finite values, fewer than 2 (complete)
    rows, k < 1 or k > candidates.
    """
    _check_missing_mode(missing)
    choice = method if isinstance(method, MethodChoice) else \
        MethodChoice(method, within, regressor)
    train_recording, test_recordings = load_recordings(train, tests, missing)
    return evaluate_checked(train_recording, test_recordings, target, sensors, k=k,
                            differences=differences, similarity=similarity, closure=closure,
                            missing=missing, method=choice, seed=seed)


def given_selection(matrix: np.ndarray | PairCandidates, y: np.ndarray, names: Sequence[str],
                    support: Sequence[str], where: str) -> Selection:
    """The ``Selection`` of candidates chosen elsewhere (``support``, by name): each its own
    cluster, psi against this ``y``, no similarity or cut."""
    from spindlebench.selection.similarity import correlation_with

    position = {name: i for i, name in enumerate(names)}
    unknown = [name for name in support if name not in position]
    if unknown:
        raise SelectionError(f"recording {where}: the given selection names candidate(s) "
                             f"{column_list(range(len(unknown)), unknown)} that it does not have")
    if not support:
        raise SelectionError(f"recording {where}: the given selection is empty")
    if isinstance(matrix, PairCandidates):
        matrix = matrix.columns(np.arange(matrix.n_candidates))
    selected = np.asarray([position[name] for name in support], dtype=np.intp)
    flat = constant_columns(matrix[:, selected])
    psi = np.full(matrix.shape[1], np.nan)
    psi[selected[~flat]] = correlation_with(matrix[:, selected[~flat]], y)
    empty = np.empty((0, 0))
    return Selection(kept=np.arange(matrix.shape[1]), dropped=np.arange(0), eta=float("nan"),
                     similarity_source=empty, closure_source=empty,
                     clusters=[np.array([i]) for i in selected], psi=psi, selected=selected)


def load_recordings(
    train: RecordingLike,
    tests: RecordingLike | Sequence[RecordingLike] | Mapping[str, RecordingLike],
    missing: str = "error",
) -> tuple[CheckedRecording, dict[str, CheckedRecording]]:
    """The training and test recordings of ``evaluate`` (read if paths), named as it names
    them, ready for any number of ``evaluate_checked`` calls."""
    if isinstance(tests, (str, os.PathLike, RecordingTable)) or _is_frame(tests):
        tests = [tests]  # one test recording; a string would otherwise be read per character
    train_name, train_frame = _load(train, "train", missing)
    items = tests.items() if isinstance(tests, Mapping) else enumerate(tests, start=1)
    test_frames: dict[str, CheckedRecording] = {}
    for key, recording in items:
        name, frame = _load(
            recording, f"test{key}" if isinstance(key, int) else str(key), missing
        )
        name = str(key) if isinstance(tests, Mapping) else name
        if name in test_frames:
            raise SelectionError(f"test recording {name} given twice")
        test_frames[name] = CheckedRecording(name, frame)
    if not test_frames:
        raise SelectionError("at least one test recording is needed")
    return CheckedRecording(train_name, train_frame), test_frames


def _stacked_candidates(train: CheckedRecording, tests: Mapping[str, CheckedRecording],
                        candidates: CandidateSet, columns: tuple[int, ...]
                        ) -> np.ndarray | None:
    """Candidates ``columns`` of every (whole) test recording, made for all at once: row i
    of the (recordings, samples, candidates) array is recording i's
    ``candidates.matrix(recording, columns)``, to the bit and in its layout.

    Why: a study's every model reads a few candidates of the same 23 held-out runs; made
    run by run that was a tenth of an evaluation. Here each candidate is one subtraction on
    the runs' rises stacked (the same subtraction per sample), and each run's block is a
    row-major (samples, candidates) part of one array, as ``matrix`` makes it. None (each
    run then made on its own, with its own error) for many candidates, recordings not
    equally long, a rise that cannot be made, or a value that is not finite."""
    recordings = tuple(tests.values())
    if len(columns) > FEW_CANDIDATES or len({len(r) for r in recordings}) != 1:
        return None
    needed, parts = _few_candidates(candidates, columns)
    # kept by the training recording, whose tests these are: the memo holds the recordings,
    # so their ids name them while it lives
    stacks = train.memo(("stacked test rises", tuple(map(id, recordings))),
                        lambda: (recordings, {}))[1]
    try:
        for sensor in needed:
            if sensor not in stacks:
                # np.array: np.stack's array of the equally long rises, a third faster
                stacks[sensor] = np.array([r.column_rises([sensor])[0] for r in recordings])
    except SelectionError:  # a rise that cannot be made: each run raises its own error
        return None
    out = np.empty((len(recordings), len(recordings[0]), len(parts)))
    with np.errstate(over="ignore", invalid="ignore"):  # warned by the run that overflows
        for j, (a, b) in enumerate(parts):
            out[:, :, j] = stacks[a] if b is None else stacks[a] - stacks[b]
    return out if np.isfinite(out).all() else None


def _check_recordings(train: CheckedRecording, tests: Mapping[str, CheckedRecording],
                      checked: tuple[str, ...], missing: str) -> None:
    """``_check_values`` of every recording, training first, each check made once per
    recording (one that passed is not repeated; one that failed raises again, in this
    order); that all of them passed is kept by the training recording, as the resolved
    sensors are (a study asks it again of the same 24 recordings for each of its models)."""
    recordings = tuple(tests.values())
    check = ("checked", checked, missing)

    def check_each() -> tuple[CheckedRecording, ...]:
        for recording in (train, *recordings):
            recording.memo(check, lambda recording=recording: _check_values(
                recording, checked, missing))
        return recordings

    train.memo(("checked tests", tuple(map(id, recordings)), checked, missing), check_each)


def _stacked_test_values(train: CheckedRecording, tests: Mapping[str, CheckedRecording],
                         column: str) -> np.ndarray:
    """Column ``column`` of every test recording stacked, (recordings, samples), for
    recordings equally long: made once per training recording, tests and column, kept as
    ``_stacked_candidates`` keeps its rises. Why: every model of a study scores its
    predictions against the same measured values, which ``rmse_each`` stacked again for
    each."""
    recordings = tuple(tests.values())
    return train.memo(("stacked test values", tuple(map(id, recordings)), column),
                      lambda: (recordings, np.array([r.values(column) for r in recordings])))[1]


def _stacked_predictions(fit: LinearFit | EstimatorFit,
                         shared: np.ndarray | None) -> np.ndarray | None:
    """Every run's prediction in one product, (runs, samples), where the runs' inputs are
    ``shared`` (stacked) and the model is linear: each run's row is its own product's bits
    (``LinearFit.predict_stacked``). None where a prediction is not finite (or there is no
    stack): the runs are then predicted one by one, so the run that fails raises its error
    in its turn."""
    if not isinstance(fit, LinearFit) or shared is None:
        return None
    stacked = fit.predict_stacked(shared)
    return stacked if np.isfinite(stacked).all() else None


def _score_tests(tests: Mapping[str, CheckedRecording], target: str, missing: str,
                 used: Sequence[str],
                 inputs: Callable[[CheckedRecording, CheckedRecording], np.ndarray],
                 fit: LinearFit | EstimatorFit,
                 batch: Callable[[], np.ndarray | None] | None = None,
                 measured_stack: Callable[[], np.ndarray] | None = None,
                 ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict[str, float],
                            dict[str, np.ndarray]]:
    """``evaluate_checked``'s predictions, measured values, RMSE and sample positions of every
    test recording (``inputs(recording, part used)``: the model's inputs; ``batch()``: those
    of every recording at once, stacked, or None, asked only when no sample is dropped;
    ``measured_stack()``: the measured values of every recording stacked, asked only when
    ``batch()`` gave a stack).

    Why in three passes (inputs of every run, then every prediction, then every RMSE in one
    reduction, ``rmse_each``) rather than run by run: a study scores each of its many
    models on the same 23 runs, and the per-run calls were half of its time. The values
    are those of the run-by-run way, and so are the errors, in its order: a run's failing
    inputs are raised only after the runs before it are predicted and scored (which raise
    first where they would), and a failing prediction only after the RMSE of those before.
    """
    test_rows: dict[str, np.ndarray] = {}
    measured: dict[str, np.ndarray] = {}
    values: dict[str, np.ndarray] = {}
    failure: Exception | None = None
    columns = tuple(used)
    whole = missing != "drop-rows" or all(recording.complete(columns)
                                          for recording in tests.values())
    shared = batch() if batch is not None and whole else None
    if shared is not None:  # whole runs, inputs stacked: each run's part of the loop below
        try:
            test_rows = {name: np.arange(len(recording)) for name, recording in tests.items()}
            measured = {name: recording.values(target) for name, recording in tests.items()}
            values = dict(zip(tests, shared, strict=True))
        except Exception:  # the loop raises it, for the run it fails on
            test_rows, measured, values = {}, {}, {}
    for i, (name, recording) in enumerate(tests.items()):
        if name in values:
            continue
        try:
            rows = np.arange(len(recording)) if whole else _complete_rows(recording, used)
            test_rows[name] = rows
            # a part only when samples were dropped: else its conversions serve again
            frame = recording.take(rows) if len(rows) < len(recording) else recording
            measured[name] = frame.values(target)
            values[name] = shared[i] if shared is not None else inputs(recording, frame)
        except Exception as exc:  # raised once the runs before it are scored
            failure = _named(exc, name)
            break
    stacked = _stacked_predictions(fit, shared) if failure is None else None
    predictions: dict[str, np.ndarray] = {} if stacked is None else \
        dict(zip(values, stacked, strict=True))
    scored: list[str] = [] if stacked is None else list(values)
    if stacked is None:  # run by run: the first that fails raises, after those before it
        if isinstance(fit, LinearFit):
            predictions = dict(zip(values, fit.predict_each(list(values.values())),
                                   strict=True))
        for name in values:
            try:
                if name not in predictions:
                    predictions[name] = fit.predict(values[name])
                if not np.isfinite(predictions[name]).all():
                    raise SelectionOverflowError("values too large to predict (overflow)")
            except Exception as exc:  # raised once the runs before it are scored
                failure = _named(exc, name)
                break
            scored.append(name)
    # every run whole and predicted in one product: its RMSE on the measured values stacked
    found = None if stacked is None or measured_stack is None else \
        rmse_rows(measured_stack(), stacked)
    try:
        if found is None:
            found = rmse_each([measured[n] for n in scored], [predictions[n] for n in scored])
    except SelectionError:  # the first run that fails, named
        for name in scored:
            with _naming(name):
                rmse(measured[name], predictions[name])
        raise
    if failure is not None:
        raise failure
    return predictions, measured, dict(zip(scored, found, strict=True)), test_rows


def evaluate_checked(
    train: CheckedRecording,
    tests: Mapping[str, CheckedRecording],
    target: str,
    sensors: Sequence[str] | None = None,
    k: int = 2,
    differences: bool = False,
    similarity: str = DEFAULT_SIMILARITY,
    closure: str = "fast",
    missing: str = "error",
    method: MethodChoice | None = None,
    seed: int = 0,
    support: Sequence[str] | None = None,
) -> Evaluation:
    """``evaluate`` on recordings from ``load_recordings``: the same result, messages and
    warnings, but each column of each recording is converted and checked once however many
    methods, k and sensor groups are evaluated on them (a study's one pass).

    ``support`` (candidate names) is a selection made elsewhere: no selection then, the model
    of ``method``'s regressor is fitted on those candidates (a joint selection of several
    targets, ``multi_target.evaluate_targets``, is scored per target this way)."""
    _check_missing_mode(missing)
    if not tests:
        raise SelectionError("at least one test recording is needed")
    choice = MethodChoice() if method is None else method
    train_name = train.name
    chosen = _resolved_sensors(train, tests, target, sensors)
    checked = [*chosen, target]
    dynamic = is_dynamic(choice.regressor)
    if dynamic:  # the regressor reads the speed programme too: present and finite everywhere
        for recording in [train, *tests.values()]:
            check_drivers(choice.regressor, recording.name, recording.columns)
        checked += [c for c in driver_columns(choice.regressor) if c not in checked]
    _check_recordings(train, tests, tuple(checked), missing)

    train_rows = np.arange(len(train))
    train_frame = train
    if missing == "drop-rows":
        chosen = _sparse_sensors(train, chosen)
        train_rows = _complete_rows(train, [*chosen, target, *(
            driver_columns(choice.regressor) if dynamic else ())])
        if len(train_rows) < len(train):  # else its conversions serve again (every k)
            train_frame = train.take(train_rows)
    candidates = CandidateSet(tuple(chosen), differences)
    names = candidates.names
    y_train = train_frame.values(target)
    if train_frame.memo(("constant target", target),
                        lambda: bool(constant_columns(y_train[:, None])[0])):
        raise SelectionError(f"recording {train_name}: target column {target!r} is constant "
                             f"({y_train[0]:g} in every sample); nothing to select or fit")

    def trained() -> tuple[Selection, LinearFit | EstimatorFit]:
        """The selection on the training recording and the model fitted on it."""
        if choice.is_paper and row_wise(candidates, similarity, closure):  # R too large
            matrix = PairCandidates(
                _finite(candidates.matrix(train_frame, range(len(chosen))), chosen))
        else:  # made once per recording and candidate set: every k selects from it
            matrix = train_frame.memo(("candidates", candidates),
                                      lambda: _finite(candidates.matrix(train_frame), names))
        points = None if support is not None else train_frame.memo(
            ("sensitive points", candidates, target, similarity, closure, choice.method,
             choice.within),
            lambda: sensitive_points(choice, matrix, y_train, similarity, names, closure))
        if support is not None:
            selection = given_selection(matrix, y_train, names, support, train_name)
        elif points is not None:  # the paper's method: its k-independent steps once
            selection = points.select(k)
        else:
            selection = select_with(choice, matrix, y_train, k, similarity, names, seed,
                                    closure)
        train_values = candidates.matrix(train_frame, selection.selected)
        if dynamic:  # the driver columns in front of the rises (``selection.dynamic``)
            train_values = model_inputs(choice.regressor, train_frame.values, train_values)
        return selection, fit_with(choice, train_values, y_train,
                                   names=[names[i] for i in selection.selected],
                                   random_state=seed)

    with _naming(train_name):
        # kept by the training recording: a study asks the same model of it again (a sweep's
        # measured conditions with one noise level train on the same recording, reused by
        # content: ``jobs._training_recording``); a user's method or regressor, which may
        # not give the same model twice, is trained at each call
        user = choice.user_method is not None or choice.user_regressor is not None
        selection, fit = trained() if user else train_frame.memo(
            ("model", candidates, target, similarity, closure, choice, k, seed,
             None if support is None else tuple(support)), trained)
    selected_names = [names[i] for i in selection.selected]
    used = [*candidates.sensors_of(selection.selected), target]
    if dynamic:
        used += list(driver_columns(choice.regressor))
    key = ("candidates", candidates, tuple(selection.selected))

    def inputs(recording: CheckedRecording, frame: CheckedRecording) -> np.ndarray:
        """The model's inputs on test ``frame`` (``recording``, or the part of it used)."""
        def candidate_values() -> np.ndarray:
            return _finite(candidates.matrix(frame, selection.selected), selected_names)

        # a whole recording's values of these candidates serve every model that reads them
        values = recording.memo(key, candidate_values) if frame is recording else \
            candidate_values()
        return model_inputs(choice.regressor, frame.values, values) if dynamic else values

    def batch() -> list[np.ndarray] | None:
        return None if dynamic else _stacked_candidates(train, tests, candidates,
                                                        tuple(selection.selected))

    def measured_stack() -> np.ndarray:
        return _stacked_test_values(train, tests, target)

    predictions, measured, errors, test_rows = _score_tests(tests, target, missing, used,
                                                            inputs, fit, batch, measured_stack)
    return Evaluation(
        train=train_name,
        target=target,
        sensors=chosen,
        candidates=names,
        selection=selection,
        fit=fit,
        predictions=predictions,
        measured=measured,
        rmse_um=errors,
        train_rows=train_rows,
        test_rows=test_rows,
        method=choice,
        seed=seed,
    )
