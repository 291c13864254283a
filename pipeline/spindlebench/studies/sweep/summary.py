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

import numpy as np
import pandas as pd

from spindlebench.core.names import ALL_RAW, SIX_DIFF, SIX_RAW

DIFF = SIX_DIFF
RAW = (ALL_RAW, SIX_RAW)
CASE = ["data", "replica", "noise", "fault", "train_experiment", "test_experiment"]
SLICES = ("noise", "fault", "test_season", "test_month", "test_speed_rpm", "test_programme",
          "test_cooling", "train_experiment")


def _stats(values: pd.Series) -> pd.Series:
    v = values.dropna()
    q1, median, q3 = (np.quantile(v, [0.25, 0.5, 0.75]) if len(v) else (np.nan,) * 3)
    return pd.Series({"n": len(v), "median_um": median, "q1_um": q1, "q3_um": q3,
                      "iqr_um": q3 - q1, "worst_um": v.max() if len(v) else np.nan,
                      "mean_um": v.mean() if len(v) else np.nan})


def ok_rows(results: pd.DataFrame) -> pd.DataFrame:
    return results[results["rmse_um"].notna()]


def by_method(results: pd.DataFrame) -> pd.DataFrame:
    """Median, IQR and worst case of the held-out RMSE per data, method and k."""
    keys = ["data", "method", "k"]
    table = (results.groupby(keys, dropna=False, sort=False)["rmse_um"].apply(_stats)
             .unstack().reset_index())
    failed = (results.assign(failed=results["rmse_um"].isna())
              .groupby(keys, dropna=False, sort=False)["failed"].sum().reset_index())
    true_median = (results.groupby(keys, dropna=False, sort=False)["rmse_true_um"].median()
                   .rename("median_vs_true_drift_um").reset_index())
    table = table.merge(failed, on=keys).merge(true_median, on=keys)
    table["n"] = table["n"].astype(int)
    return table


def by_condition(results: pd.DataFrame) -> pd.DataFrame:
    keys = ["data", "noise", "fault", "method", "k"]
    return (results.groupby(keys, dropna=False, sort=False)["rmse_um"].apply(_stats)
            .unstack().reset_index())


def by_season(results: pd.DataFrame) -> pd.DataFrame:
    keys = ["data", "method", "k", "test_season"]
    return (results.groupby(keys, dropna=False, sort=False)["rmse_um"].median()
            .rename("median_um").reset_index())


def stability(results: pd.DataFrame) -> pd.DataFrame:
    """Spread across k, across seasons and across held-out runs, per data and method."""
    rows = []
    data = ok_rows(results)
    for (kind, method), group in data.groupby(["data", "method"], sort=False):
        with_k = group[group["k"].notna()]
        if with_k["k"].nunique() > 1:
            # max and min as grouped reductions, not a Python function per case: the same
            # values, 50x faster (a lambda per case was half of a 1 000-run sweep's outputs)
            by_case = with_k.groupby(CASE)["rmse_um"]
            per_case = by_case.max() - by_case.min()
            medians_k = with_k.groupby("k")["rmse_um"].median()
            k_spread, k_median_range = per_case.median(), medians_k.max() - medians_k.min()
        else:
            k_spread = k_median_range = np.nan
        for k, at_k in group.groupby("k", dropna=False, sort=False):
            seasons = at_k.groupby("test_season")["rmse_um"].median()
            per_training = at_k.groupby(["replica", "noise", "fault", "train_experiment"])
            experiment_sd = per_training["rmse_um"].std().median()
            rows.append({"data": kind, "method": method, "k": k,
                         "k_spread_um": k_spread, "k_median_range_um": k_median_range,
                         "season_spread_um": seasons.max() - seasons.min()
                         if len(seasons) > 1 else np.nan,
                         "worst_season": seasons.idxmax() if len(seasons) else "",
                         "experiment_sd_um": experiment_sd})
    table = pd.DataFrame(rows)
    if len(table):
        table["k"] = table["k"].astype("Int64")
    return table


def paired(results: pd.DataFrame) -> pd.DataFrame:
    """The three groups side by side on identical cases (rows: case × k)."""
    groups = results[results["method"].isin([DIFF, *RAW])]
    return groups.pivot_table(index=[*CASE, "k"], columns="method", values="rmse_um",
                              aggfunc="first")


def verdict(results: pd.DataFrame, summary: pd.DataFrame, stable: pd.DataFrame) -> pd.DataFrame:
    """Per data kind and k: does ``six_diff`` beat both raw groups, on each criterion?"""
    rows = []
    wide = paired(results)
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
        try:
            sub = wide.xs((kind, k), level=("data", "k"), drop_level=False)
        except KeyError:
            sub = wide.iloc[0:0]
        for raw in raws:
            row[f"median_{raw}_um"] = at["median_um"].get(raw, np.nan)
            if raw in sub and DIFF in sub:
                both = sub[[DIFF, raw]].dropna()
                row[f"win_rate_vs_{raw}"] = float((both[DIFF] < both[raw]).mean()) \
                    if len(both) else np.nan
        row["lower"] = row["median_holds"]
        row["more_stable"] = all(row[f"{c}_holds"] for c in ("iqr", "worst", "season_spread",
                                                             "k_spread")
                                 if row[f"{c}_holds"] is not None)
        rows.append(row)
    return pd.DataFrame(rows)


def claim_by_slice(results: pd.DataFrame) -> pd.DataFrame:
    """Within each value of each axis, per k: median of ``six_diff`` against the better raw
    group (``versus = best-raw``) and against the same six sensors without differences
    (``versus = six_raw``, the paper's like-for-like comparison)."""
    rows = []
    data = ok_rows(results)
    data = data[(data["data"] == "measured") & data["method"].isin([DIFF, *RAW])]
    for axis in SLICES:
        if data[axis].nunique() < 2:
            continue
        if axis == "test_month" and data["test_month"].nunique() == data["test_season"].nunique():
            continue  # one month per season: the month slices repeat the season slices
        for (value, k), at in data.groupby([axis, "k"], sort=False):
            medians = at.groupby("method")["rmse_um"].median()
            if DIFF not in medians:
                continue
            raws = medians.drop(DIFF)
            if isinstance(value, float):
                value = f"{value:g}"
            for versus, reference in (("best-raw", raws.idxmin() if len(raws) else None),
                                      (SIX_RAW, SIX_RAW if SIX_RAW in raws else None)):
                if reference is None:
                    continue
                rows.append({"axis": axis, "value": value, "k": int(k), "versus": versus,
                             "diff_median_um": medians[DIFF], "reference": reference,
                             "reference_median_um": raws[reference],
                             "ratio": medians[DIFF] / raws[reference]
                             if raws[reference] > 0 else np.nan,
                             "holds": bool(medians[DIFF] < raws[reference])})
    return pd.DataFrame(rows)


def rank_by_slice(results: pd.DataFrame) -> pd.DataFrame:
    """Every method (not the oracle) ranked by median held-out RMSE within each slice (axis
    value) and k, on measured data; ``all`` is the whole study. Methods without k (ridge)
    take part at every k. Rank 1 is the lowest median."""
    data = ok_rows(results)
    data = data[(data["data"] == "measured") & (data["method"] != "oracle")]
    ks = sorted(int(k) for k in data["k"].dropna().unique())
    rows = []
    slices = [("all", "all", data)]
    for axis in SLICES:
        if data[axis].nunique() < 2:
            continue
        if axis == "test_month" and data["test_month"].nunique() == data["test_season"].nunique():
            continue
        slices += [(axis, f"{value:g}" if isinstance(value, float) else str(value), at)
                   for value, at in data.groupby(axis, sort=False)]
    for axis, value, at in slices:
        for k in ks or [None]:
            chosen = at[at["k"].isna() | (at["k"] == k)] if k is not None else at
            medians = chosen.groupby("method", sort=False)["rmse_um"].median().sort_values(
                kind="stable")
            for rank, (method, median) in enumerate(medians.items(), start=1):
                rows.append({"axis": axis, "value": value, "k": k, "rank": rank,
                             "method": method, "median_um": median,
                             "of": len(medians)})
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


def summarise(results: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """Every summary table, keyed by the file name it is written under."""
    summary = by_method(results)
    stable = stability(results)
    return {
        "by_method": summary,
        "by_condition": by_condition(results),
        "by_season": by_season(results),
        "stability": stable,
        "verdict": verdict(results, summary, stable),
        "claim_by_slice": claim_by_slice(results),
        "best": baselines_vs_paper(summary),
        "rank_by_slice": rank_by_slice(results),
    }
