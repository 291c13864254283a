"""Across how many machines a study's conclusion holds.

Each machine of a population is an ordinary study run with its own results folder and README.
This module reads what those runs wrote (a sweep's ``summary/verdict.csv``) and counts, per
data kind and number of clusters k, the machines on which the paper's claim holds: the six
sensors plus their differences give a lower median held-out RMSE than the better raw group
(*lower*), and a smaller spread on every criterion (*more stable*). A conclusion that holds on
31 of 50 machines is a property of the machine type; one that holds on 50 of 50 may be one of
the method; the numbers say which.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from spindlebench.core import atomic
from spindlebench.studies.family.population import TABLE_FILE, Member, Population
from spindlebench.studies.family.population_summary import (
    on_machines,
    write_population_readme,
)

VERDICT_FILE = Path("summary") / "verdict.csv"
RESULT_FILE = "population_verdict.csv"
FINGERPRINT_KEYS = ("median_best_raw_psi", "median_best_diff_psi", "median_overshoot",
                    "median_early_fraction", "median_t63_ratio")


def collect_verdicts(out: Path, members: list[Member]) -> pd.DataFrame:
    """One row per kept machine × data kind × k (machines whose run wrote no verdict are
    rows with NaN, so they count as 'not shown', never as 'holds')."""
    rows = []
    for member in members:
        if not member.kept:
            continue
        path = out / member.name / VERDICT_FILE
        if not path.is_file():
            rows.append({"machine": member.name, "data": None, "k": None})
            continue
        verdict = pd.read_csv(path)
        for _, row in verdict.iterrows():
            best_raw = float(row["median_best_raw_um"])
            rows.append({"machine": member.name, "data": row["data"], "k": int(row["k"]),
                         "lower": bool(row["lower"]), "more_stable": bool(row["more_stable"]),
                         "median_diff_um": float(row["median_diff_um"]),
                         "median_best_raw_um": float(best_raw),
                         "gain_um": float(best_raw - row["median_diff_um"])})
    return pd.DataFrame(rows)


def fractions(verdicts: pd.DataFrame, n_machines: int) -> pd.DataFrame:
    """Per data kind and k: on how many machines each half of the claim holds."""
    rows = []
    shown = verdicts.dropna(subset=["data"])
    for (data, k), at in shown.groupby(["data", "k"], sort=True):
        gains = at["gain_um"].to_numpy(dtype=float)
        q1, median, q3 = np.nanquantile(gains, [0.25, 0.5, 0.75])
        rows.append({"data": data, "k": int(k), "machines": n_machines,
                     "lower": int(at["lower"].sum()),
                     "lower_and_more_stable": int((at["lower"] & at["more_stable"]).sum()),
                     "median_gain_um": median, "gain_q1_um": q1, "gain_q3_um": q3})
    return pd.DataFrame(rows)


def sweep_population_report(out: Path, population: Population, members: list[Member],
                            study_path: Path, fmu: Path) -> str:
    """Write ``population_verdict.csv``, ``README.md`` and ``provenance.json`` of a population
    sweep into ``out``; return the README text."""
    kept = [m for m in members if m.kept]
    verdicts = collect_verdicts(out, members)
    counts = fractions(verdicts, len(kept))
    atomic.write_text(out / RESULT_FILE, verdicts.to_csv(index=False, lineterminator="\n"))
    lines = [f"# Population sweep: {study_path.stem}", "",
             f"{population.describe()}: {len(kept)} kept of {len(members)} drawn "
             f"(each machine's file in `machines/`, its fingerprint in `{TABLE_FILE}`, its own "
             "results folder and README beside this file).", "",
             "## Does the paper's claim hold, machine by machine?", "",
             "*lower*: `six_diff` has a lower median held-out RMSE than the better raw group "
             "(`all_raw`, `six_raw`); *lower and more stable*: also a smaller spread on every "
             "criterion of the sweep's README. Gain: the better raw group's median minus "
             "`six_diff`'s (positive: the differences help).", ""]
    if counts.empty:
        lines.append("No machine's sweep wrote a verdict: nothing can be said.")
    for _, row in counts.iterrows():
        total = int(row["machines"])
        lines.append(
            f"- {row['data']}, k = {row['k']}: *lower* on {on_machines(int(row['lower']), total)}, "
            f"*lower and more stable* on {on_machines(int(row['lower_and_more_stable']), total)}; "
            f"median gain {row['median_gain_um']:.2f} µm (IQR {row['gain_q1_um']:.2f} to "
            f"{row['gain_q3_um']:.2f} µm).")
    missing = verdicts[verdicts["data"].isna()]["machine"].tolist() if not verdicts.empty \
        else []
    if missing:
        lines += ["", f"No verdict (see their folders): {', '.join(missing)}."]
    lines += ["", "## The machines' fingerprints (median over the paper's five runs)", "",
              "| statistic | min | median | max |", "|---|---|---|---|"]
    for key in FINGERPRINT_KEYS:
        values = np.array([m.fingerprint.get(key.removeprefix("median_"), np.nan)
                           for m in kept], dtype=float)
        if values.size and np.isfinite(values).any():
            lines.append(f"| {key.removeprefix('median_')} | {np.nanmin(values):.3f} | "
                         f"{np.nanmedian(values):.3f} | {np.nanmax(values):.3f} |")
    return write_population_readme(out, lines, population, members, study_path, fmu)
