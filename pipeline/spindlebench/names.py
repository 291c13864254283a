"""The shared vocabulary: sensor names, the paper's six, group and similarity names, units.

One home for every name that more than one layer (modelica/, testbench/, selection/, studies/,
paper_study/) uses, so a rename is one edit. This module imports nothing from the package, so
every layer may import it without importing another layer.
"""

from __future__ import annotations

#: The paper's twenty temperature sensors (Xu et al. 2023, Fig. 4), in the paper's order.
SENSORS: tuple[str, ...] = tuple(f"T{i}" for i in range(1, 21))
#: The paper's six-sensor subset (spindle front, headstock, motor, ambient, X motor, Y motor).
PAPER_SIX: tuple[str, ...] = ("T1", "T6", "T8", "T10", "T13", "T16")

#: The paper's three candidate groups: reference group 1 (all raw sensors), reference group 2
#: (the six raw sensors) and the reconstructed group (the six plus their pairwise differences).
#: Used in every table, file name and report (paper study and season sweep alike).
ALL_RAW, SIX_RAW, SIX_DIFF = "all_raw", "six_raw", "six_diff"
GROUPS: tuple[str, ...] = (ALL_RAW, SIX_RAW, SIX_DIFF)
#: Human-readable group labels for figure legends.
GROUP_LABELS: dict[str, str] = {
    ALL_RAW: "all raw",
    SIX_RAW: "six raw",
    SIX_DIFF: "six + differences",
}

#: The two readings of the paper's eq. 1 (see ``selection.similarity``); the first is the default.
SIMILARITIES: tuple[str, ...] = ("abs-pearson", "literal")
DEFAULT_SIMILARITY = SIMILARITIES[0]

#: Degrees Celsius to kelvin.
KELVIN_OFFSET = 273.15
