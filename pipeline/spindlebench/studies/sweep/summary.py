"""From the tidy results table to the numbers that answer the study's question.

The paper's claim has two halves, and each is measured, not assumed:

- *lower*: with the six sensors plus their differences (``six_diff``) the held-out RMSE is
  lower than with raw sensors (``all_raw``, ``six_raw``). Measured by the median RMSE per k, and
  by the paired win rate: on the same replica, condition, training and held-out run, how
  often ``six_diff`` beats each raw group.
- *more stable*: its error varies less: across held-out runs (interquartile range, worst
  case), across the number of clusters k (the spread max−min over k of the same case), and
  across seasons (max−min of the per-season medians).

``claim_by_slice`` repeats the *lower* test within every value of every study axis (noise
level, fault, held-out season, speed, programme, cooling, training run), which is where the
conditions under which the claim fails show up. ``rank_by_slice`` ranks every method (the
paper's groups, the other selection methods on them, the baselines) within the same slices.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from spindlebench.core.names import ALL_RAW, SIX_DIFF, SIX_RAW

DIFF = SIX_DIFF
RAW = (ALL_RAW, SIX_RAW)
CASE = ["data", "replica", "noise", "fault", "train_experiment", "test_experiment"]
SLICES = ("noise", "fault", "test_season", "test_month", "test_speed_rpm", "test_programme",
          "test_cooling", "train_experiment")
#: The code of k for the methods without one (``Scored.codes("k")``).
NO_K_KEY = -1


STATS = ("n", "median_um", "q1_um", "q3_um", "iqr_um", "worst_um", "mean_um")


def _stats(values: np.ndarray) -> tuple[float, ...]:
    """``STATS`` of one group's values (missing ones left out)."""
    v = values[~np.isnan(values)]
    if not len(v):
        return (0.0, *(np.nan,) * (len(STATS) - 1))
    q1, median, q3 = np.quantile(v, [0.25, 0.5, 0.75])
    return float(len(v)), median, q1, q3, q3 - q1, v.max(), v.mean()


def _stats_table(number: np.ndarray, values: np.ndarray, keys: pd.DataFrame) -> pd.DataFrame:
    """Each group's keys and ``STATS`` of its ``values`` (n as a float); ``number``: every
    row's group (``Scored.groups``).

    The groups' values come from one stable sort by group number and each is reduced by
    numpy: ``apply`` made pandas Series per group, a third of the summary's time."""
    order = np.argsort(number, kind="stable")
    starts = np.flatnonzero(np.diff(number[order])) + 1
    stats = pd.DataFrame([_stats(chunk) for chunk in np.split(values[order], starts)],
                         columns=list(STATS))
    return pd.concat([keys, stats], axis=1)


def by_method(results: pd.DataFrame, scored: Scored | None = None) -> pd.DataFrame:
    """Median, IQR and worst case of the held-out RMSE per data, method and k."""
    number, keys = (scored or Scored(results)).groups(["data", "method", "k"], by_levels=True)
    rmse = results["rmse_um"].to_numpy(dtype=float)
    table = _stats_table(number, rmse, keys)
    table["failed"] = np.bincount(number, weights=np.isnan(rmse)).astype(np.int64)
    table["median_vs_true_drift_um"] = (pd.Series(results["rmse_true_um"].to_numpy())
                                        .groupby(number).median().to_numpy())
    table["n"] = table["n"].astype(int)
    return table


def by_condition(results: pd.DataFrame, scored: Scored | None = None) -> pd.DataFrame:
    number, keys = (scored or Scored(results)).groups(["data", "noise", "fault", "method", "k"],
                                                      by_levels=True)
    return _stats_table(number, results["rmse_um"].to_numpy(dtype=float), keys)


def by_season(results: pd.DataFrame, scored: Scored | None = None) -> pd.DataFrame:
    number, keys = (scored or Scored(results)).groups(["data", "method", "k", "test_season"])
    keys["median_um"] = (pd.Series(results["rmse_um"].to_numpy()).groupby(number).median()
                         .to_numpy())
    return keys


class Scored:
    """A results table with its key columns as integer codes (each in the sorted order of
    its values), on every row and on the scored rows (``frame``, ``rmse``, a score), each
    column coded once for every table and figure computed from it.

    Grouping by the codes gives the groups in the order grouping by the columns does
    (sorted, or by first appearance with ``sort=False``) but hashes integers: factorising
    the text columns of a 1 000-run sweep's 380 000 rows again for every grouping was most
    of the summary's time. A missing value is code -1 (the key columns of a scored row have
    none; a failed evaluation's row has only its replica, condition and training run); k is
    ``NO_K_KEY`` for a method without one.
    """

    def __init__(self, results: pd.DataFrame) -> None:
        self.results = results
        self.ok = np.flatnonzero(results["rmse_um"].notna().to_numpy())
        self.frame = results.iloc[self.ok]
        self.rmse = self.frame["rmse_um"].to_numpy()
        self._all_codes: dict[str, np.ndarray] = {}
        self._codes: dict[str, np.ndarray] = {}
        self._labels: dict[str, pd.Index] = {}

    def all_codes(self, column: str) -> np.ndarray:
        """The codes of ``column`` on every row of the results, scored or not."""
        if column not in self._all_codes:
            values = self.results[column]
            if column == "k":
                self._all_codes[column] = values.fillna(NO_K_KEY).to_numpy(dtype=np.int64)
            else:
                self._all_codes[column], self._labels[column] = _factorized(values)
        return self._all_codes[column]

    def codes(self, column: str) -> np.ndarray:
        """The codes of ``column`` on the scored rows."""
        if column not in self._codes:
            self._codes[column] = self.all_codes(column)[self.ok]
        return self._codes[column]

    def label(self, column: str, code: int) -> Any:
        """The value a code stands for (k: the int, or None for a method without k; NaN
        for a missing value, as on the row of an evaluation that failed)."""
        if column == "k":
            return None if code == NO_K_KEY else int(code)
        return np.nan if code < 0 else self._labels[column][code]  # -1: missing

    def code(self, column: str, value: Any) -> int:
        """The code of ``value`` in ``column``, -1 if no row has it."""
        self.all_codes(column)
        labels = self._labels[column]
        return int(labels.get_loc(value)) if value in labels else -1

    def key(self, columns: Sequence[str], rows: np.ndarray | slice = slice(None),
            every_row: bool = False) -> tuple[np.ndarray, list[int]]:
        """The codes of ``columns`` in ``rows`` (of the scored rows, or of ``every_row``) as
        one integer per row, their place in the grid of all combinations (of that shape):
        ordered as the code tuples are.

        Grouping by it is one pass: pandas factorises each key of a grouping again, and those
        passes were half of what was left of the summary's time."""
        codes = [(self.all_codes(c) if every_row else self.codes(c))[rows] + 1
                 for c in columns]  # k's NO_K_KEY is -1
        shape = [int(c.max()) + 1 if len(c) else 1 for c in codes]
        return np.ravel_multi_index(codes, shape), shape

    def groups(self, columns: Sequence[str], by_levels: bool = False
               ) -> tuple[np.ndarray, pd.DataFrame]:
        """Every row's group by ``columns`` and each group's key values, the groups numbered
        as ``groupby(sort=False, dropna=False)`` orders them (as they first come) or, with
        ``by_levels``, as unstacking its result does (by each column's values in the order
        they first come, missing ones last)."""
        key, shape = self.key(columns, every_row=True)
        number, uniques = pd.factorize(key)
        codes = self.unkey(uniques, shape)
        if by_levels:
            ranks = []
            for column, at in zip(columns, codes, strict=True):
                come = [c for c in pd.unique(self.all_codes(column)) if c != -1]
                rank = np.full(max(shape) + 1, len(come), dtype=np.int64)  # missing: last
                rank[np.asarray(come, dtype=np.int64) + 1] = np.arange(len(come))
                ranks.append(rank[at + 1])
            order = np.lexsort(ranks[::-1])
            number = np.argsort(order)[number]
            codes = [at[order] for at in codes]
        keys = pd.DataFrame({column: [self.label(column, int(code)) for code in at]
                             for column, at in zip(columns, codes, strict=True)})
        if "k" in keys:
            keys["k"] = keys["k"].astype("Int64")
        return number, keys

    @staticmethod
    def unkey(key: np.ndarray, shape: Sequence[int]) -> list[np.ndarray]:
        """The codes of each column in ``key`` (``Scored.key``)."""
        return [codes - 1 for codes in np.unravel_index(key, shape)]

    def reduced(self, columns: Sequence[str], how: str | list[str],
                rows: np.ndarray | slice = slice(None), sort: bool = True,
                values: np.ndarray | None = None) -> pd.Series | pd.DataFrame:
        """``values`` (the RMSE) of ``rows`` grouped by ``columns`` and reduced by ``how``
        (``SeriesGroupBy.agg``), indexed by the columns' codes."""
        key, shape = self.key(columns, rows)
        reduced = pd.Series(self.rmse[rows] if values is None else values).groupby(
            key, sort=sort).agg(how)
        reduced.index = pd.MultiIndex.from_arrays(self.unkey(reduced.index.to_numpy(), shape))
        return reduced

    def values_by(self, columns: Sequence[str], rows: np.ndarray | slice = slice(None)
                  ) -> dict[tuple, np.ndarray]:
        """The RMSE of ``rows`` per combination of ``columns`` (keyed by their values, k
        None for a method without one), each in row order, sorted by the keys: one stable
        sort (a box plot's boxes; a mask per box compared every row again)."""
        key, shape = self.key(columns, rows)
        order = np.argsort(key, kind="stable")
        key, values = key[order], self.rmse[rows][order]
        starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]]) if len(key) else key
        codes = self.unkey(key[starts], shape)
        return {tuple(self.label(c, int(at[i])) for c, at in zip(columns, codes, strict=True)):
                chunk for i, chunk in enumerate(np.split(values, starts[1:]))}

    def slice_axes(self, rows: np.ndarray) -> list[str]:
        """The study axes the claim and the ranking are sliced by: those with more than one
        value in ``rows``, but not the month where each season has one month (its slices
        would repeat the season's)."""
        counts = {axis: np.count_nonzero(np.bincount(self.codes(axis)[rows]))
                  for axis in (*SLICES, "test_season")}  # values present (a sort took 5x)
        return [axis for axis in SLICES if counts[axis] > 1 and not (
            axis == "test_month" and counts["test_month"] == counts["test_season"])]

    def label_text(self, column: str, code: int) -> str:
        """A slice's value as the tables name it: a float in its shortest form."""
        value = self.label(column, code)
        return f"{value:g}" if isinstance(value, float) else str(value)


def _factorized(values: pd.Series) -> tuple[np.ndarray, pd.Index]:
    """``pd.factorize(values, sort=True)``: the same codes and labels, a text column's from
    its object array and, where its values come in long runs, from one value per run.

    Why: the results are the evaluation files one after another, so the replica, condition,
    training run and method change every few hundred rows; hashing every one of a 1 000-run
    sweep's 380 000 cells, a dozen columns, was half the summary's time (pandas' str path
    also marks the missing values first). A run's cells are one value (or one missing value:
    NaN ends a run, its code is -1 either way), so coding the first cell of each run and
    repeating its code gives each cell's code, and the runs' values are the column's."""
    if not isinstance(values.dtype, pd.StringDtype):
        return pd.factorize(values, sort=True)
    cells = values.to_numpy(dtype=object)
    starts = np.flatnonzero(np.r_[True, cells[1:] != cells[:-1]]) if len(cells) else None
    if starts is None or len(starts) > len(cells) // RUNS_WORTH_IT:
        codes, labels = pd.factorize(cells, sort=True)
    else:
        codes, labels = pd.factorize(cells[starts], sort=True)
        codes = np.repeat(codes, np.diff(np.r_[starts, len(cells)]))
    return codes, pd.Index(labels, dtype=values.dtype)


#: Coding a column by its runs pays where they average this many cells or more (a held-out
#: run's name changes on every row: its runs would only add the comparison).
RUNS_WORTH_IT = 4


def stability(results: pd.DataFrame, scored: Scored | None = None) -> pd.DataFrame:
    """Spread across k, across seasons and across held-out runs, per data and method.

    Every spread is one grouped reduction over the whole table, looked up per data, method
    and k (a grouping per method and k, by text columns, took five times as long on a
    1 000-run sweep)."""
    scored = scored or Scored(results)
    k = scored.codes("k")
    with_k = np.flatnonzero(k != NO_K_KEY)
    by_case = scored.reduced(["data", "method", *CASE[1:]], ["max", "min"], with_k)
    k_spread = (by_case["max"] - by_case["min"]).groupby(level=[0, 1]).median()
    medians_k = scored.reduced(["data", "method", "k"], "median", with_k)
    k_range = medians_k.groupby(level=[0, 1]).agg(["max", "min"])
    n_k = medians_k.groupby(level=[0, 1]).size()
    seasons: dict[tuple, dict[str, float]] = {}
    for (kind, method, at, season), median in scored.reduced(
            ["data", "method", "k", "test_season"], "median").items():
        seasons.setdefault((kind, method, at), {})[scored.label("test_season", season)] = median
    experiment_sd = (scored.reduced(["data", "method", "k", "replica", "noise", "fault",
                                     "train_experiment"], "std")
                     .groupby(level=[0, 1, 2]).median())
    ks: dict[tuple, list[int]] = {}  # per data and method, its k in the order they come
    for kind, method, at in scored.reduced(["data", "method", "k"], "size", sort=False).index:
        ks.setdefault((kind, method), []).append(at)
    rows = []
    for (kind, method), at in ((pair, at) for pair, all_k in ks.items() for at in all_k):
        if n_k.get((kind, method), 0) > 1:
            spread = k_spread[(kind, method)]
            median_range = k_range.loc[(kind, method), "max"] - k_range.loc[(kind, method), "min"]
        else:
            spread = median_range = np.nan
        by_season = seasons.get((kind, method, at), {})
        rows.append({"data": scored.label("data", kind), "method": scored.label("method", method),
                     "k": scored.label("k", at), "k_spread_um": spread,
                     "k_median_range_um": median_range,
                     "season_spread_um": max(by_season.values()) - min(by_season.values())
                     if len(by_season) > 1 else np.nan,
                     "worst_season": max(by_season, key=by_season.__getitem__)
                     if by_season else "",
                     "experiment_sd_um": experiment_sd.get((kind, method, at), np.nan)})
    table = pd.DataFrame(rows)
    if len(table):
        table["k"] = table["k"].astype("Int64")
    return table


def win_rates(scored: Scored) -> dict[str, pd.Series]:
    """Per raw group: on identical cases (replica, condition, training and held-out run,
    k), the share where ``six_diff`` scores lower, per data and k codes; only for the raw
    groups that, like ``six_diff``, have a score. Each group's score per case is one
    grouping (a table of the three side by side was half of the verdict's time)."""
    method = scored.codes("method")
    rows = {m: np.flatnonzero(method == scored.code("method", m)) for m in (DIFF, *RAW)}
    firsts = {m: scored.reduced([*CASE, "k"], "first", at) for m, at in rows.items() if len(at)}
    if DIFF not in firsts:
        return {}
    data_and_k = [0, len(CASE)]  # the levels of data and k in the case index
    rates = {}
    for raw in RAW:
        if raw in firsts:
            both = pd.concat([firsts[DIFF], firsts[raw]], axis=1, join="inner")
            rates[raw] = (both.iloc[:, 0] < both.iloc[:, 1]).groupby(level=data_and_k).mean()
    return rates


def verdict(results: pd.DataFrame, summary: pd.DataFrame, stable: pd.DataFrame,
            scored: Scored | None = None) -> pd.DataFrame:
    """Per data kind and k: does ``six_diff`` beat both raw groups, on each criterion?"""
    scored = scored or Scored(results)
    rows = []
    rates = win_rates(scored)
    for (kind, k), at in summary[summary["method"].isin([DIFF, *RAW])].groupby(
            ["data", "k"], sort=False):
        at = at.set_index("method")
        if DIFF not in at.index or not any(r in at.index for r in RAW):
            continue
        raws = [r for r in RAW if r in at.index]
        st = stable[(stable["data"] == kind) & (stable["k"] == k)].set_index("method")
        row: dict[str, object] = {"data": kind, "k": int(k)}
        for criterion, column, source in (("median", "median_um", at), ("iqr", "iqr_um", at),
                                          ("worst", "worst_um", at),
                                          ("season_spread", "season_spread_um", st),
                                          ("k_spread", "k_spread_um", st)):
            mine = source[column].get(DIFF, np.nan)
            best_raw = min((source[column].get(r, np.nan) for r in raws), default=np.nan)
            row[f"{criterion}_diff_um"] = mine
            row[f"{criterion}_best_raw_um"] = best_raw
            row[f"{criterion}_holds"] = bool(mine < best_raw) if np.isfinite(mine) and \
                np.isfinite(best_raw) else None
        for raw in raws:
            row[f"median_{raw}_um"] = at["median_um"].get(raw, np.nan)
            if raw in rates:
                row[f"win_rate_vs_{raw}"] = float(rates[raw].get(
                    (scored.code("data", kind), int(k)), np.nan))
        row["lower"] = row["median_holds"]
        row["more_stable"] = all(row[f"{c}_holds"] for c in ("iqr", "worst", "season_spread",
                                                             "k_spread")
                                 if row[f"{c}_holds"] is not None)
        rows.append(row)
    return pd.DataFrame(rows)


def claim_by_slice(results: pd.DataFrame, scored: Scored | None = None) -> pd.DataFrame:
    """Within each value of each axis, per k: median of ``six_diff`` against the better raw
    group (``versus = best-raw``) and against the same six sensors without differences
    (``versus = six_raw``, the paper's like-for-like comparison). The medians of each axis
    come from one grouping (by value, k and method), in the order the values come."""
    scored = scored or Scored(results)
    groups = [scored.code("method", m) for m in (DIFF, *RAW)]
    rows_at = np.flatnonzero((scored.codes("data") == scored.code("data", "measured"))
                             & np.isin(scored.codes("method"), groups))
    rows = []
    for axis in scored.slice_axes(rows_at):
        cells: dict[tuple, dict[str, float]] = {}
        for (value, k, method), median in scored.reduced(
                [axis, "k", "method"], "median", rows_at, sort=False).items():
            cells.setdefault((value, k), {})[scored.label("method", method)] = median
        for (value, k), medians in cells.items():
            if DIFF not in medians:
                continue
            raws = {m: medians[m] for m in sorted(medians) if m != DIFF}
            for versus, reference in (("best-raw", min(raws, key=raws.__getitem__)
                                       if raws else None),
                                      (SIX_RAW, SIX_RAW if SIX_RAW in raws else None)):
                if reference is None:
                    continue
                rows.append({"axis": axis, "value": scored.label_text(axis, value),
                             "k": scored.label("k", k), "versus": versus,
                             "diff_median_um": medians[DIFF], "reference": reference,
                             "reference_median_um": raws[reference],
                             "ratio": medians[DIFF] / raws[reference]
                             if raws[reference] > 0 else np.nan,
                             "holds": bool(medians[DIFF] < raws[reference])})
    return pd.DataFrame(rows)


def rank_by_slice(results: pd.DataFrame, scored: Scored | None = None) -> pd.DataFrame:
    """Every method (not the oracle) ranked by median held-out RMSE within each slice (axis
    value) and k, on measured data; ``all`` is the whole study. Methods without k (ridge)
    take part at every k. Rank 1 is the lowest median; equal medians rank in the order the
    methods first come in the slice.

    Each axis is one grouping by value, k and method (a method has a k on every row or on
    none), not a grouping per slice and k."""
    scored = scored or Scored(results)
    rows_at = np.flatnonzero((scored.codes("data") == scored.code("data", "measured"))
                             & (scored.codes("method") != scored.code("method", "oracle")))
    ks = sorted(int(k) for k in np.unique(scored.codes("k")[rows_at]) if k != NO_K_KEY)
    rows = []
    for axis in [None, *scored.slice_axes(rows_at)]:
        keys = ["k", "method"] if axis is None else [axis, "k", "method"]
        first = scored.reduced(keys, "min", rows_at, sort=False, values=rows_at)
        cells: dict[Any, dict[int, list[tuple[float, int, int]]]] = {}
        for key, median in scored.reduced(keys, "median", rows_at, sort=False).items():
            value, k, method = (None, *key) if axis is None else key
            cells.setdefault(value, {}).setdefault(k, []).append((median, first[key], method))
        for value, by_k in cells.items():
            for k in ks or [None]:
                chosen = sorted([*by_k.get(NO_K_KEY, []), *(by_k.get(k, []) if k else [])])
                for rank, (median, _, method) in enumerate(chosen, start=1):
                    rows.append({"axis": axis or "all",
                                 "value": "all" if axis is None
                                 else scored.label_text(axis, value),
                                 "k": k, "rank": rank, "method": scored.label("method", method),
                                 "median_um": median, "of": len(chosen)})
    table = pd.DataFrame(rows)
    if len(table):
        table["k"] = table["k"].astype("Int64")
    return table


def baselines_vs_paper(summary: pd.DataFrame) -> pd.DataFrame:
    """Per data kind: the method (not the oracle) with the lowest median, and the oracle's."""
    rows = []
    for kind, at in summary[summary["method"] != "oracle"].groupby("data", sort=False):
        best = at.loc[at["median_um"].idxmin()]
        oracle = summary[(summary["data"] == kind) & (summary["method"] == "oracle")]
        rows.append({"data": kind, "best_method": best["method"], "best_k": best["k"],
                     "best_median_um": best["median_um"],
                     "oracle_median_um": oracle["median_um"].iloc[0] if len(oracle) else np.nan})
    return pd.DataFrame(rows)


def summarise(results: pd.DataFrame, scored: Scored | None = None) -> dict[str, pd.DataFrame]:
    """Every summary table, keyed by the file name it is written under; ``scored``: the
    results' coded rows, when the caller shares them (with the box plots)."""
    scored = scored or Scored(results)
    summary = by_method(results, scored)
    stable = stability(results, scored)
    return {
        "by_method": summary,
        "by_condition": by_condition(results, scored),
        "by_season": by_season(results, scored),
        "stability": stable,
        "verdict": verdict(results, summary, stable, scored),
        "claim_by_slice": claim_by_slice(results, scored),
        "best": baselines_vs_paper(summary),
        "rank_by_slice": rank_by_slice(results, scored),
    }
