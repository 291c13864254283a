"""An evaluation's result frame (``jobs._result_frame``), made from its columns as they are,
is the frame the plain pandas construction makes: the same values, dtypes, column order and
CSV text, for scored rows, failed rows (NaN scores, an error), methods without a k, no rows,
and the noise-free pseudo-condition (issue 26)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.studies.family.experiments import conditions, experiments
from spindlebench.studies.family.family_file import load_study
from spindlebench.studies.running import jobs

TINY = REPO / "scenarios" / "studies" / "tiny_sweep.toml"


@dataclasses.dataclass
class _Job:
    """The two fields of a job that ``_result_frame`` reads."""

    replica: int
    condition: object


def plain_pandas_frame(job, train, tests, rows) -> pd.DataFrame:
    """The result frame as it was built before issue 26: a list per column, ``pd.array``
    with the text and ``Int64`` dtypes, ``pd.DataFrame`` of the dict."""
    by_id = {e.id: e for e in tests}
    tested = [by_id[row["test_experiment"]] for row in rows]
    n = len(rows)
    condition = job.condition

    def text(values):
        return pd.array(values, dtype=pd.Series(["text"]).dtype)

    def floats(values):
        return np.array(values, dtype=np.float64)

    return pd.DataFrame({
        "replica": np.full(n, job.replica, dtype=np.int64),
        "data": text(["measured" if condition else jobs.NOISE_FREE] * n),
        "noise": text([condition.noise.name if condition else jobs.NOISE_FREE] * n),
        "fault": text([condition.fault_name if condition else "none"] * n),
        "train_experiment": text([train.id] * n),
        "method": text([row["method"] for row in rows]),
        "k": pd.array([row["k"] for row in rows], dtype="Int64"),
        "test_experiment": text([row["test_experiment"] for row in rows]),
        "rmse_um": floats([row["rmse_um"] for row in rows]),
        "rmse_true_um": floats([row["rmse_true_um"] for row in rows]),
        "selected": text([row["selected"] for row in rows]),
        "error": text([row["error"] for row in rows]),
        "test_month": text([e.month for e in tested]),
        "test_season": text([e.season for e in tested]),
        "test_speed_rpm": floats([e.speed_rpm for e in tested]),
        "test_programme": text([e.programme for e in tested]),
        "test_cooling": text([e.cooling for e in tested]),
    }, copy=False)


@pytest.fixture(scope="module")
def study():
    return load_study(TINY)


def mixed_rows(tests) -> list[dict]:
    """Scored rows (with k and without), a failed method (NaN, error) and a failed
    simulation, across every held-out run, in an order that is not the runs' order."""
    rows = []
    for spec_k, name in ((2, "six_diff"), (None, "ridge_all"), (4, "all_raw")):
        for i, test in enumerate(reversed(tests)):
            failed = name == "all_raw" and i % 2 == 0
            rows.append({"method": name, "k": spec_k, "test_experiment": test.id,
                         "rmse_um": np.nan if failed else 1.5 + i / 7,
                         "rmse_true_um": np.nan if failed else 0.1 * i,
                         "selected": "" if failed else "T1;T16",
                         "error": "simulation failed: boom, 'x'" if failed else ""})
    return rows


def assert_same_frame(made: pd.DataFrame, expected: pd.DataFrame) -> None:
    pd.testing.assert_frame_equal(made, expected, check_exact=True)
    assert list(made.columns) == list(expected.columns)
    assert list(made.dtypes) == list(expected.dtypes)
    assert made.to_csv(index=False) == expected.to_csv(index=False)
    assert made.isna().equals(expected.isna())


@pytest.mark.parametrize("which", ["measured", "noise-free"])
def test_result_frame_is_the_plain_pandas_frame(study, which):
    family = experiments(study)
    condition = conditions(study)[-1] if which == "measured" else None
    job, train, tests = _Job(7, condition), family[0], family[1:]
    rows = mixed_rows(tests)
    made = jobs._result_frame(job, train, tests, rows)
    assert len(made) == len(rows) and made["k"].isna().sum() == len(tests)
    assert made["rmse_um"].isna().any() and (made["error"] != "").any()
    assert_same_frame(made, plain_pandas_frame(job, train, tests, rows))


def test_result_frame_of_no_rows_is_the_plain_pandas_frame(study):
    family = experiments(study)
    job = _Job(1, conditions(study)[0])
    assert_same_frame(jobs._result_frame(job, family[0], family[1:], []),
                      plain_pandas_frame(job, family[0], family[1:], []))


def test_result_frames_concatenate_as_the_plain_pandas_frames(study):
    """The sweep's results table concatenates the frames: the same table either way."""
    family = experiments(study)
    frames = {made: [] for made in (jobs._result_frame, plain_pandas_frame)}
    for replica, condition in enumerate([*conditions(study), None]):
        for train in family[:2]:
            tests = [e for e in family if e != train]
            for make, made in frames.items():
                made.append(make(_Job(replica, condition), train, tests, mixed_rows(tests)))
    made, expected = (pd.concat(f, ignore_index=True) for f in frames.values())
    assert_same_frame(made, expected)
