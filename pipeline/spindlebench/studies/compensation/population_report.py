"""Across how many machines a compensation study's conclusion holds.

Each machine of a population runs the ordinary compensation study into its own folder. This
module reads what those runs wrote (``summary.csv``) and counts, per retraining rule, the
machines on which the paper's claim holds in the loop: the difference group ``six_diff``
leaves a smaller residual RMS over all days than the better raw group (``all_raw``,
``six_raw``), and on how many any compensation beats none.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from spindlebench.core import atomic
from spindlebench.core.names import ALL_RAW, SIX_DIFF, SIX_RAW
from spindlebench.studies.family.population import TABLE_FILE, Member, Population
from spindlebench.studies.family.population_summary import (
    on_machines,
    write_population_readme,
)

SUMMARY_FILE = "summary.csv"
RESULT_FILE = "population_compensation.csv"
DIFF_GROUP = SIX_DIFF
RAW_GROUPS = (ALL_RAW, SIX_RAW)
NONE = "uncompensated"
PART = "all days"


def collect(out: Path, members: list[Member]) -> pd.DataFrame:
    """One row per kept machine × retraining rule: the residual RMS of the difference group,
    of the better raw group, of the best model and of the uncompensated machine."""
    rows = []
    for member in members:
        path = out / member.name / SUMMARY_FILE
        if not member.kept or not path.is_file():
            continue
        table = pd.read_csv(path)
        table = table[table["part"] == PART]
        for rule, at in table.groupby("retrain", sort=False):
            rms = dict(zip(at["model"], at["rms_um"].astype(float), strict=True))
            raw = min(rms.get(g, np.nan) for g in RAW_GROUPS)
            models = {k: v for k, v in rms.items() if k != NONE}
            best = min(models, key=models.get) if models else ""
            diff = rms.get(DIFF_GROUP, np.nan)
            rows.append({"machine": member.name, "retrain": rule, "six_diff_rms_um": diff,
                         "best_raw_rms_um": raw, "gain_um": raw - diff,
                         "diff_helps": bool(diff < raw), "best_model": best,
                         "best_model_rms_um": models.get(best, np.nan),
                         "uncompensated_rms_um": rms.get(NONE, np.nan),
                         "compensation_helps": bool(models.get(best, np.inf)
                                                    < rms.get(NONE, np.nan))})
    return pd.DataFrame(rows, columns=["machine", "retrain", "six_diff_rms_um",
                                       "best_raw_rms_um", "gain_um", "diff_helps",
                                       "best_model", "best_model_rms_um",
                                       "uncompensated_rms_um", "compensation_helps"])


def compensation_population_report(out: Path, population: Population, members: list[Member],
                                   study_path: Path, fmu: Path) -> str:
    """Write ``population_compensation.csv``, ``README.md`` and ``provenance.json`` of a
    population compensation study into ``out``; return the README text."""
    kept = [m for m in members if m.kept]
    rows = collect(out, members)
    atomic.write_text(out / RESULT_FILE, rows.to_csv(index=False, lineterminator="\n"))
    lines = [f"# Population compensation study: {study_path.stem}", "",
             f"{population.describe()}: {len(kept)} kept of {len(members)} drawn (each "
             f"machine's file in `machines/`, its fingerprint in `{TABLE_FILE}`, its own "
             "compensation run and README beside this file; one row per machine and "
             f"retraining rule in `{RESULT_FILE}`).", "",
             "## Does the difference group help in the loop, machine by machine?", "",
             f"*differences help*: `{DIFF_GROUP}` leaves a smaller residual RMS over all days "
             f"than the better raw group ({', '.join(f'`{g}`' for g in RAW_GROUPS)}). Gain: "
             f"the better raw group's RMS minus `{DIFF_GROUP}`'s (positive: the differences "
             "help). *compensation helps*: the best model's residual RMS is below the "
             "uncompensated machine's drift RMS.", "",
             "| retrain | machines | differences help | median gain (µm) | gain IQR (µm) | "
             "compensation helps | median residual, best model (µm) | median uncompensated "
             "(µm) |", "|---|---|---|---|---|---|---|---|"]
    for rule, at in rows.groupby("retrain", sort=False):
        q1, median, q3 = np.nanquantile(at["gain_um"].to_numpy(dtype=float), [0.25, 0.5, 0.75])
        lines.append(f"| {rule} | {len(at)} | "
                     f"{on_machines(int(at['diff_helps'].sum()), len(at))} | {median:.2f} | "
                     f"{q1:.2f} to {q3:.2f} | "
                     f"{on_machines(int(at['compensation_helps'].sum()), len(at))} | "
                     f"{np.nanmedian(at['best_model_rms_um']):.2f} | "
                     f"{np.nanmedian(at['uncompensated_rms_um']):.2f} |")
    if rows.empty:
        lines = [*lines[:-2], "No machine's compensation run wrote a summary: nothing can be "
                 "said."]
    else:
        best = rows["best_model"].value_counts()
        lines += ["", "Lowest residual per machine: " + ", ".join(
            f"`{name}` on {count}" for name, count in best.items()) + "."]
    missing = sorted({m.name for m in kept} - set(rows["machine"]))
    if missing:
        lines += ["", f"No summary (see their folders): {', '.join(missing)}."]
    return write_population_readme(out, lines, population, members, study_path, fmu)
