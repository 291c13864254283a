"""The sweep README's generated sentences: the headline agrees with the per-k verdicts."""

from __future__ import annotations

import pandas as pd
from spindlebench.studies.sweep.sweep_report import duration_text, overall


def verdict(*rows: tuple[str, int, bool, bool]) -> pd.DataFrame:
    return pd.DataFrame([{"data": d, "k": k, "lower": lo, "more_stable": st}
                         for d, k, lo, st in rows])


def test_headline_names_measured_data_and_reports_the_noise_free_verdict_too():
    text = overall(verdict(("measured", 2, False, False), ("measured", 3, False, True),
                           ("noise-free", 2, False, False), ("noise-free", 3, True, False)))
    assert text == (
        "**On measured data the paper's claim does not hold in this synthetic world**: at no "
        "k tested (2, 3) do the differences give a lower median held-out error than the "
        "better raw group. On the noise-free truth (perfect instruments) it holds only in "
        "part: differences are lower but not more stable on all criteria at k = 3; not lower "
        "at k = 2.")


def test_headline_without_noise_free_rows_and_when_the_claim_holds():
    text = overall(verdict(("measured", 2, True, True), ("measured", 4, True, True)))
    assert text.startswith("**On measured data the paper's claim holds in this synthetic "
                           "world**: at every k tested (2, 4)")
    assert "noise-free" not in text
    mixed = overall(verdict(("measured", 2, True, True), ("measured", 3, False, True),
                            ("noise-free", 2, True, True)))
    assert mixed == ("**On measured data the paper's claim holds only in part**: differences "
                     "are lower and more stable at k = 2; not lower at k = 3. On the "
                     "noise-free truth (perfect instruments) it holds: at every k tested (2) "
                     "the six sensors plus their differences give a lower median held-out "
                     "error and a smaller spread than either raw group.")


def test_durations_read_at_a_glance():
    assert duration_text(2400.0) == "40 min"
    assert duration_text(6 * 3600.0) == "6 h"
    assert duration_text(5400.0) == "1.5 h"
    assert duration_text(6000.0) == "1.67 h"
