"""Across how many machines a placement study's conclusion holds.

Each machine of a population runs the ordinary placement study into its own folder. This module
reads what those runs wrote (``placements.csv``) and counts, per search method and budget m,
the machines on which the paper's claim holds for placement: the method given the nodes *and*
their pairwise differences finds a placement with a lower mean held-out RMSE than the same
method given the nodes alone (*differences help*).
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

PLACEMENTS_FILE = "placements.csv"
RESULT_FILE = "population_placements.csv"
SCORE = "test_mean_rmse_um"


def collect(out: Path, members: list[Member]) -> pd.DataFrame:
    """One row per kept machine × method × m: the nodes-only and the with-differences score
    (NaN where a machine's run wrote no placement: it counts as 'not shown', never 'holds')."""
    rows = []
    for member in members:
        if not member.kept:
            continue
        path = out / member.name / PLACEMENTS_FILE
        if not path.is_file():
            continue
        table = pd.read_csv(path)
        for (method, m), at in table.groupby(["method", "m"], sort=True):
            score = {bool(d): float(v) for d, v in zip(at["differences"], at[SCORE],
                                                        strict=True)}
            nodes, diff = score.get(False, np.nan), score.get(True, np.nan)
            rows.append({"machine": member.name, "method": method, "m": int(m),
                         "nodes_rmse_um": nodes, "diff_rmse_um": diff,
                         "gain_um": nodes - diff, "diff_helps": bool(diff < nodes)})
    return pd.DataFrame(rows, columns=["machine", "method", "m", "nodes_rmse_um",
                                       "diff_rmse_um", "gain_um", "diff_helps"])


def placement_population_report(out: Path, population: Population, members: list[Member],
                                study_path: Path, fmu: Path) -> str:
    """Write ``population_placements.csv``, ``README.md`` and ``provenance.json`` of a
    population placement study into ``out``; return the README text."""
    kept = [m for m in members if m.kept]
    rows = collect(out, members)
    atomic.write_text(out / RESULT_FILE, rows.to_csv(index=False, lineterminator="\n"))
    lines = [f"# Population placement study: {study_path.stem}", "",
             f"{population.describe()}: {len(kept)} kept of {len(members)} drawn (each "
             f"machine's file in `machines/`, its fingerprint in `{TABLE_FILE}`, its own "
             "placement study and README beside this file; one row per machine, method and "
             f"budget in `{RESULT_FILE}`).", "",
             "## Do the differences help, machine by machine?", "",
             "*differences help*: the method searching the nodes and their pairwise "
             "differences finds a placement with a lower mean RMSE on the test days than the "
             "same method searching the nodes alone. Gain: nodes-only RMSE minus "
             "with-differences RMSE (positive: the differences help).", "",
             "| method | m | machines | differences help | median gain (µm) | gain IQR (µm) |",
             "|---|---|---|---|---|---|"]
    shown = rows.dropna(subset=["gain_um"])
    for (method, m), at in shown.groupby(["method", "m"], sort=True):
        gains = at["gain_um"].to_numpy(dtype=float)
        q1, median, q3 = np.quantile(gains, [0.25, 0.5, 0.75])
        lines.append(f"| {method} | {m} | {len(at)} | "
                     f"{on_machines(int(at['diff_helps'].sum()), len(at))} | {median:.2f} | "
                     f"{q1:.2f} to {q3:.2f} |")
    if shown.empty:
        lines = [*lines[:-2], "No machine's placement study wrote a comparable pair: nothing "
                 "can be said."]
    else:
        helps = shown.groupby("machine")["diff_helps"].all()
        lines += ["", f"Differences help at every method and budget on "
                  f"{on_machines(int(helps.sum()), len(helps))}."]
    missing = sorted({m.name for m in kept} - set(rows["machine"]))
    if missing:
        lines += ["", f"No placements (see their folders): {', '.join(missing)}."]
    return write_population_readme(out, lines, population, members, study_path, fmu)
