"""The sweep's evaluation jobs: one job per (replica, condition) covers its training runs.

Uses ``scenarios/studies/tiny_sweep.toml`` with ``rule = "each-season"`` (Jan and Jul at
4000 rpm train), so every (replica, condition) has two training runs sharing one job.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.studies.family.family_file import load_study
from spindlebench.studies.family.methods import score_all
from spindlebench.studies.running import jobs
from spindlebench.studies.running.executor import TaskRunner
from spindlebench.studies.running.jobs import evaluate_job, measured_frame
from spindlebench.studies.sweep.sweep_run import Sweep, evaluation_path

TINY = REPO / "scenarios" / "studies" / "tiny_sweep.toml"


@pytest.fixture(scope="module")
def seasons_study(tmp_path_factory):
    text = TINY.read_text(encoding="utf-8").replace('[training]\nmonth = "Jan"',
                                                    '[training]\nrule = "each-season"')
    assert "each-season" in text
    path = tmp_path_factory.mktemp("study") / "tiny_seasons.toml"
    path.write_text(text, encoding="utf-8")
    return path


def run(study_path, out):
    sweep = Sweep(load_study(study_path), out)
    return sweep, sweep.run(TaskRunner(workers=0, progress=False))


@pytest.fixture(scope="module")
def swept(seasons_study, tmp_path_factory):
    return run(seasons_study, tmp_path_factory.mktemp("sweep") / "seasons")


def rows_on_their_own(job, train):
    """A training run's rows as one job per training run made them: its own frames, measured
    (the training run without the fault) and checked for it alone."""
    train_frame = measured_frame(job, train, held_out=False)
    tests = {e.id: measured_frame(job, e) for e in job.experiments if e != train}
    rows = pd.DataFrame(score_all(list(job.specs), train_frame, tests, job.similarity))
    return rows.astype({"k": "Int64"})


def test_one_job_per_condition_gives_each_training_runs_own_rows(swept):
    sweep, outcome = swept
    assert len(sweep.trains) == 2
    # one task per replica holds its conditions' jobs
    assert outcome.stats.done == {"simulation": 8, "evaluation": 2}
    assert outcome.evaluated == 2 * 2 * len(sweep.conditions)
    assert {c.fault_name for c in sweep.conditions if c is not None} == {"none", "T1-stuck"}
    for condition in sweep.conditions:
        job = sweep.evaluation_task(2, condition, sweep.trains).args[0]
        merged = evaluate_job(job)
        assert list(merged) == [train.id for train in sweep.trains]
        for train in sweep.trains:
            alone = evaluate_job(sweep.evaluation_task(2, condition, [train]).args[0])
            frame = merged[train.id]
            assert frame.to_csv(index=False) == alone[train.id].to_csv(index=False)
            own = rows_on_their_own(job, train)
            columns = list(own.columns)
            assert frame[columns].to_csv(index=False) == own.to_csv(index=False)
            assert (frame["error"] == "").all()
            assert len(frame) == len(sweep.family[1:]) * len(sweep.specs)


def test_a_lost_training_run_file_redoes_only_that_run(swept, seasons_study, tmp_path):
    import shutil

    sweep, outcome = swept
    out = tmp_path / "copy"
    shutil.copytree(outcome.out_dir, out)
    condition = next(c for c in sweep.conditions if c is not None and c.fault is not None)
    lost = out / evaluation_path(1, condition, sweep.trains[1])
    kept = out / evaluation_path(1, condition, sweep.trains[0])
    before, kept_before = lost.read_bytes(), kept.stat().st_mtime_ns
    lost.unlink()
    _, again = run(seasons_study, out)
    assert again.stats.done == {"evaluation": 1} and again.evaluated == 1
    assert again.skipped["evaluation"] == 2 * 2 * len(sweep.conditions) - 1
    assert lost.read_bytes() == before and kept.stat().st_mtime_ns == kept_before
    pd.testing.assert_frame_equal(again.results, outcome.results)


def test_a_training_run_whose_evaluation_raises_costs_only_itself(swept, seasons_study,
                                                                  tmp_path, monkeypatch):
    import shutil

    sweep, outcome = swept
    out = tmp_path / "broken"
    shutil.copytree(outcome.out_dir, out)
    for path in out.glob("evals/r001/*/*.csv"):
        path.unlink()
    broken = sweep.trains[0]
    original = jobs._evaluate_training_run

    def breaking(job, train, *rest):
        if train == broken:
            raise RuntimeError("broken on purpose")
        return original(job, train, *rest)

    monkeypatch.setattr(jobs, "_evaluate_training_run", breaking)
    _, failing = run(seasons_study, out)
    assert failing.stats.done == {"evaluation": 1}  # replica 1's conditions in one task
    assert failing.evaluated == 2 * len(sweep.conditions)
    results = failing.results
    failed = results[results["error"] != ""]
    assert set(failed["train_experiment"]) == {broken.id} and set(failed["replica"]) == {1}
    assert (failed["error"] == "evaluation failed: RuntimeError: broken on purpose").all()
    assert len(failed) == len(sweep.conditions)  # one error row per (condition, run)
    for condition in sweep.conditions:
        assert (out / evaluation_path(1, condition, broken).replace(".csv", ".error.csv")
                ).is_file()
        assert (out / evaluation_path(1, condition, sweep.trains[1])).is_file()

    monkeypatch.setattr(jobs, "_evaluate_training_run", original)
    _, fixed = run(seasons_study, out)
    assert fixed.evaluated == len(sweep.conditions)
    assert not list(out.glob("evals/**/*.error.csv"))
    pd.testing.assert_frame_equal(fixed.results, outcome.results)


def _grown_frame(job, train, tests, rows):
    """How a training run's rows were framed before: from the row dicts, then column by
    column."""
    by_id = {e.id: e for e in tests}
    frame = pd.DataFrame(rows)
    frame.insert(0, "replica", job.replica)
    frame.insert(1, "data", "measured" if job.condition else "noise-free")
    frame.insert(2, "noise", job.condition.noise.name if job.condition else "noise-free")
    frame.insert(3, "fault", job.condition.fault_name if job.condition else "none")
    frame.insert(4, "train_experiment", train.id)
    tested = [by_id[name] for name in frame["test_experiment"]]
    for column in ("month", "season", "speed_rpm", "programme", "cooling"):
        frame[f"test_{column}"] = [getattr(e, column) for e in tested]
    frame["k"] = frame["k"].astype("Int64")
    return frame


@pytest.mark.parametrize("ks, rmse, error", [
    ([2, 3, None], [1.0, 2.5, 3.0], ""),
    ([None, None], [float("nan")] * 2, "training experiment failed: x"),
    ([2, 4], [float("nan"), 1.0], ""),
    ([2, None], [float("nan")] * 2, "simulation failed: y"),
])
def test_result_frame_is_the_grown_frame_to_the_byte(swept, tmp_path, ks, rmse, error):
    from spindlebench.studies.running.store import ResultStore

    sweep, _ = swept
    job = sweep.evaluation_task(1, sweep.conditions[0], sweep.trains).args[0]
    train, tests = sweep.trains[0], [e for e in sweep.family if e != sweep.trains[0]]
    rows = [{"method": "m", "k": k, "test_experiment": e.id, "rmse_um": r, "rmse_true_um": r,
             "selected": "" if error else "T1", "error": error}
            for k, r in zip(ks, rmse, strict=True) for e in tests]
    grown, made = _grown_frame(job, train, tests, rows), jobs._result_frame(job, train, tests,
                                                                            rows)
    pd.testing.assert_frame_equal(made, grown)
    store = ResultStore(tmp_path)
    store.write_frame("grown.csv", grown)
    store.write_frame("made.csv", made)
    assert (tmp_path / "made.csv").read_bytes() == (tmp_path / "grown.csv").read_bytes()


def test_measured_frames_carry_the_programme_for_identified_models(swept):
    """Issue 22: a sweep's measured frame holds the run's speed and ambient (from its truth),
    so a dynamic regressor (``selection.dynamic``) scores on the sweep's protocol."""
    from spindlebench.studies.family.methods import MethodSpec

    sweep, _ = swept
    condition = sweep.conditions[0]
    job = sweep.evaluation_task(1, condition, sweep.trains[:1]).args[0]
    train = sweep.trains[0]
    frame = measured_frame(job, train, held_out=False)
    truth = job.truths[train.id]
    assert (frame["spindle_speed_rpm"].to_numpy() == truth["spindle_speed_rpm"].to_numpy()).all()
    assert (frame["ambient_C"].to_numpy() == truth["ambient_C"].to_numpy()).all()
    tests = {e.id: measured_frame(job, e) for e in job.experiments if e != train}
    rows = pd.DataFrame(score_all([MethodSpec("six_raw:closure+tf1", 2)], frame, tests,
                                  job.similarity))
    assert len(rows) == len(tests) and rows["rmse_um"].notna().all(), rows


def test_measured_frame_is_the_same_from_a_truth_that_is_not_one_float_block(swept):
    """A truth frame of float64 columns is converted once (``_TruthColumns``); one with
    another column type takes pandas column by column: the same frame to the bit."""
    sweep, _ = swept
    for condition in sweep.conditions:
        job = sweep.evaluation_task(1, condition, sweep.trains[:1]).args[0]
        train = sweep.trains[0]
        mixed = {name: truth.assign(label="x") for name, truth in job.truths.items()}
        other = dataclasses.replace(job, truths=mixed)
        for held_out in (True, False):
            pd.testing.assert_frame_equal(measured_frame(job, train, held_out),
                                          measured_frame(other, train, held_out),
                                          check_exact=True)


def test_a_pickled_job_gives_the_same_truths_and_result_frames(swept):
    """A job reaches its worker pickled, with its truths as bare arrays
    (``EvaluationJob.__reduce__``): the same truth frames (values, dtypes, memory layout,
    columns) and the same result bytes; a truth that is not one float64 block goes as the
    frame it is."""
    import pickle

    import numpy as np

    sweep, _ = swept
    for condition in sweep.conditions:
        job = sweep.evaluation_task(1, condition, sweep.trains).args[0]
        truths = dict(job.truths)
        truths[next(iter(truths))] = truths[next(iter(truths))].assign(label="x")
        for sent in (job, dataclasses.replace(job, truths=truths)):
            shipped = pickle.loads(pickle.dumps(sent, protocol=pickle.HIGHEST_PROTOCOL))
            assert dataclasses.replace(shipped, truths={}) == \
                dataclasses.replace(sent, truths={})
            assert list(shipped.truths) == list(sent.truths)
            for name, truth in sent.truths.items():
                got = shipped.truths[name]
                pd.testing.assert_frame_equal(got, truth, check_exact=True)
                a, b = got.to_numpy(), truth.to_numpy()
                assert a.flags.f_contiguous == b.flags.f_contiguous
                if a.dtype == np.float64:  # the same bits, a NaN's included
                    assert np.array_equal(a.view(np.int64), b.view(np.int64))
            ours, theirs = evaluate_job(shipped), evaluate_job(sent)
            assert list(ours) == list(theirs)
            for train in ours:
                assert ours[train].to_csv(index=False) == theirs[train].to_csv(index=False)


def test_a_replica_task_stores_its_shared_truths_once(swept):
    """A replica's task holds one job per condition, all with the same truth frames: pickled
    together they store those truths once (``jobs._packed_frames``), not once per job, and
    each job unpickles to the same truths."""
    import pickle

    sweep, _ = swept
    task_jobs = tuple(sweep.evaluation_task(1, c, sweep.trains).args[0]
                      for c in sweep.conditions)
    assert len(task_jobs) >= 3
    one = len(pickle.dumps(task_jobs[0], protocol=pickle.HIGHEST_PROTOCOL))
    together = pickle.dumps(task_jobs, protocol=pickle.HIGHEST_PROTOCOL)
    truth_bytes = sum(t.to_numpy().nbytes for t in task_jobs[0].truths.values())
    assert truth_bytes > one / 2  # the truths are most of a job
    assert len(together) < one + truth_bytes / 2  # ... and are there once for all jobs
    for sent, got in zip(task_jobs, pickle.loads(together), strict=True):
        for name, truth in sent.truths.items():
            pd.testing.assert_frame_equal(got.truths[name], truth, check_exact=True)
    # a truth changed after a pickling goes as it is now: a value in place, a column set
    # anew, a column added, the columns renamed
    job = dataclasses.replace(task_jobs[0], truths={
        name: truth.copy() for name, truth in task_jobs[0].truths.items()})
    truth = next(iter(job.truths.values()))
    column = truth.columns[1]
    changes = [lambda: truth.iloc.__setitem__((0, 1), -1.0),
               lambda: truth.__setitem__(column, truth[column] + 1.0),
               lambda: truth.__setitem__("added", 2.0),
               lambda: setattr(truth, "columns", [f"{c}_renamed" for c in truth.columns])]
    for change in changes:
        pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL)
        change()
        got = pickle.loads(pickle.dumps(job, protocol=pickle.HIGHEST_PROTOCOL))
        pd.testing.assert_frame_equal(next(iter(got.truths.values())), truth, check_exact=True)


def test_measured_frame_is_the_frame_pandas_makes_of_its_values(swept):
    """``measured_frame`` hands pandas its block as it is (``jobs._block_frame``): the frame
    pandas' constructor makes of the same (samples, columns) values, to the memory layout
    (which the methods' arrays inherit); the noise-free one holds the truth's values."""
    import numpy as np

    sweep, _ = swept
    for condition in sweep.conditions:
        job = sweep.evaluation_task(1, condition, sweep.trains[:1]).args[0]
        for experiment in job.experiments[:3]:
            made = measured_frame(job, experiment)
            plain = pd.DataFrame(np.array(made.to_numpy()), columns=list(made.columns))
            pd.testing.assert_frame_equal(made, plain, check_exact=True)
            for frame in (made, plain):
                (block,) = frame._mgr.blocks
                assert block.values.flags.c_contiguous and block.dtype == np.float64
            assert made.to_numpy().flags.f_contiguous == plain.to_numpy().flags.f_contiguous
            assert isinstance(made.index, pd.RangeIndex) and made.index.equals(plain.index)
            if condition is None:
                truth = job.truths[experiment.id]
                for column, name in (("T1", "true_T1_C"), ("T20", "true_T20_C"),
                                     ("spindle_speed_rpm", "spindle_speed_rpm")):
                    assert np.array_equal(made[column].to_numpy(), truth[name].to_numpy())


def test_a_training_run_measured_alike_reuses_its_models_to_the_bit(swept, monkeypatch):
    """A fault condition measures each training run healthy, into the healthy condition's
    frame: in one task its job takes the recording the healthy job checked, with the models
    trained on it (``jobs._training_recording``), and gives the rows of models trained
    afresh (its job alone)."""
    sweep, _ = swept
    healthy = next(c for c in sweep.conditions if c is not None and c.fault is None)
    faulty = next(c for c in sweep.conditions
                  if c is not None and c.fault is not None and c.noise == healthy.noise)
    job, sibling = (sweep.evaluation_task(2, c, sweep.trains).args[0] for c in (faulty, healthy))
    fresh = evaluate_job(job)
    made = []
    original = jobs._training_recording

    def watched(frame, kept):
        recording = original(frame, kept)
        made.append((recording, dict(recording._memo)))  # its memo as the job found it
        return recording

    monkeypatch.setattr(jobs, "_training_recording", watched)
    _, reused = jobs.evaluate_jobs((sibling, job))
    first, second = made[:len(sweep.trains)], made[len(sweep.trains):]
    assert len(second) == len(sweep.trains)
    for (recording, _), (again, memo) in zip(first, second, strict=True):
        assert again is recording  # the healthy job's, with its models
        assert {key[0] for key in memo if isinstance(key, tuple)} >= {"model", "top-k fit"}
        assert "ridge fit" in memo
    for train in sweep.trains:
        pd.testing.assert_frame_equal(reused[train.id], fresh[train.id], check_exact=True)
        assert reused[train.id].to_csv(index=False) == fresh[train.id].to_csv(index=False)


def test_a_training_frame_differing_in_one_bit_is_a_recording_of_its_own(swept):
    sweep, _ = swept
    job = sweep.evaluation_task(2, sweep.conditions[0], sweep.trains).args[0]
    frame = measured_frame(job, sweep.trains[0], held_out=False)
    kept = {}
    recording = jobs._training_recording(frame, kept)
    assert jobs._training_recording(measured_frame(job, sweep.trains[0], held_out=False),
                                    kept) is recording
    changed = frame.copy()
    changed.iloc[5, 3] = float(np.nextafter(changed.iloc[5, 3], np.inf))
    assert jobs._training_recording(changed, kept) is not recording
    named = frame.copy()
    named.attrs["path"] = "somewhere.csv"  # its messages may name the file: not shared
    assert jobs._training_recording(named, kept) is not jobs._training_recording(named, kept)


def test_one_task_per_replica_gives_each_jobs_own_results_and_errors(swept):
    """``evaluate_jobs`` (a replica's conditions in one task, the sweep's) gives each job
    what ``evaluate_job`` gives it alone, whichever order the shared recordings are made in;
    a job that raises gives its one-line error and costs no other job."""
    sweep, _ = swept
    together = tuple(sweep.evaluation_task(2, condition, sweep.trains).args[0]
                     for condition in sweep.conditions)
    broken = dataclasses.replace(together[1], truths={})
    results = jobs.evaluate_jobs((together[0], broken, *together[2:]))
    assert results[1].startswith("KeyError: ")
    for job, result in zip(together, results, strict=True):
        if job is together[1]:
            continue
        alone = evaluate_job(job)
        assert list(result) == list(alone)
        for train_id, frame in alone.items():
            pd.testing.assert_frame_equal(result[train_id], frame, check_exact=True)
            assert result[train_id].to_csv(index=False) == frame.to_csv(index=False)
