"""The season sweep end to end on the real FMU: results, resume, failures, Dask, CLI.

Uses ``scenarios/studies/tiny_sweep.toml``: 4 experiments of 40 simulated minutes at a
2-minute step, 2 replicas, 2 fault states plus the noise-free truth.
"""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import REPO
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.recording import read_recording
from spindlebench.studies.family.family_file import load_study
from spindlebench.studies.family.methods import method_specs
from spindlebench.studies.running.executor import TaskRunner
from spindlebench.studies.running.jobs import measured_frame
from spindlebench.studies.running.simulations import failure_path, recording_path
from spindlebench.studies.sweep.sweep_run import RESULT_COLUMNS, Sweep, run_sweep, write_outputs

#: Every test here runs the tiny sweep or reuses the module's run of it.
pytestmark = pytest.mark.slow

TINY = REPO / "scenarios" / "studies" / "tiny_sweep.toml"
NUMBERS = ["rmse_um", "rmse_true_um"]


def runner() -> TaskRunner:
    return TaskRunner(workers=0, progress=False)


def sweep_into(out: Path, sweep_class: type[Sweep] = Sweep):
    sweep = sweep_class(load_study(TINY), out)
    outcome = sweep.run(runner())
    write_outputs(sweep, outcome, runner())
    return sweep, outcome


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """One uninterrupted in-process run of the tiny study."""
    out = tmp_path_factory.mktemp("sweep") / "reference"
    return sweep_into(out)


def ordered(results: pd.DataFrame) -> pd.DataFrame:
    keys = ["replica", "data", "noise", "fault", "train_experiment", "method", "k",
            "test_experiment"]
    return results.sort_values(keys).reset_index(drop=True)


def test_results_table_has_one_row_per_replica_condition_method_k_and_test(reference):
    sweep, outcome = reference
    study = sweep.study
    results = outcome.results
    n_tests = len(sweep.family) - 1
    n_conditions = len(study.noise) * len(study.faults) + 1  # + the noise-free truth
    n_specs = len(method_specs(study.methods))
    assert len(results) == study.replicas * n_conditions * n_specs * n_tests
    assert list(results.columns) == list(RESULT_COLUMNS)
    assert (results["error"] == "").all()
    assert np.isfinite(results[NUMBERS].to_numpy()).all() and (results["rmse_um"] > 0).all()
    assert set(results["data"]) == {"measured", "noise-free"}
    assert not results.duplicated(["replica", "noise", "fault", "method", "k",
                                   "test_experiment"]).any()
    # The oracle (OLS on all 20 sensors, fitted on the held-out run itself) is a floor.
    case = ["replica", "data", "noise", "fault", "test_experiment"]
    oracle = results[results["method"] == "oracle"].set_index(case)["rmse_um"]
    others = results[results["method"] != "oracle"].join(oracle.rename("floor"), on=case)
    assert (others["rmse_um"] >= others["floor"] - 1e-9).all()
    # The stuck T1 only harms models that read T1; on the others the fault changes nothing.
    measured = results[results["data"] == "measured"].set_index(
        ["replica", "method", "k", "test_experiment", "fault"])["rmse_um"].unstack("fault")
    uses_t1 = results[(results["data"] == "measured") & (results["fault"] == "none")].set_index(
        ["replica", "method", "k", "test_experiment"])["selected"].str.contains(r"\bT1\b|all ")
    untouched = measured[~uses_t1.reindex(measured.index)]  # ridge reads all sensors
    assert np.allclose(untouched["none"], untouched["T1-stuck"])
    assert not np.allclose(measured["none"], measured["T1-stuck"])
    # Files a reader needs, with provenance.
    out = outcome.out_dir
    for name in ("results.csv", "README.md", "provenance.json", "summary/by_method.csv",
                 "summary/verdict.csv",
                 "plots/rmse_by_method.png"):
        assert (out / name).is_file(), name
    record = json.loads((out / "provenance.json").read_text())
    assert record["study"]["sha256"] == study.sha256
    assert len(record["fmu"]["sha256"]) == 64 and record["package_versions"]["fmpy"]
    assert set(record["seeds"]) == {"r1", "r2"}
    readme = (out / "README.md").read_text()
    assert "Does the paper's claim hold?" in readme and "![by_method]" in readme
    assert "runs of 40 min sampled" in readme and "bound" not in readme.split("Methods:")[0]
    assert "**On measured data the paper's claim" in readme
    assert "On the noise-free truth (perfect instruments)" in readme
    assert pd.read_csv(out / "results.csv").shape == results.shape


def test_conditions_remeasure_exactly_what_the_runner_recorded(reference):
    """The first noise level without faults reproduces the stored recording bit for bit."""
    sweep, _ = reference
    healthy = next(c for c in sweep.conditions if c is not None and c.fault is None)
    job = sweep.evaluation_task(2, healthy, sweep.trains).args[0]
    columns = [f"T{i}" for i in range(1, 21)] + ["drift_um"]
    for experiment in sweep.family:
        stored = read_recording(sweep.store.path(recording_path(2, experiment)))
        again = measured_frame(job, experiment)
        assert np.array_equal(stored[columns].to_numpy(), again[columns].to_numpy())


class InterruptedSweep(Sweep):
    """Stops like a Ctrl-C after three simulations have been written."""

    def _record_simulation(self, outcome, waiting):
        written = list(self.store.root.glob("runs/*/*.csv"))
        if len(written) == 3:
            raise KeyboardInterrupt
        return super()._record_simulation(outcome, waiting)


def test_interrupted_sweep_resumes_without_redoing_finished_work(tmp_path, reference):
    out = tmp_path / "resumed"
    with pytest.raises(KeyboardInterrupt):
        sweep_into(out, InterruptedSweep)
    assert len(list(out.glob("runs/*/*.csv"))) == 3
    assert not list(out.glob("**/.*.part"))  # atomic writes: no half files left behind

    sweep, outcome = sweep_into(out)
    assert outcome.resumed
    total = len(sweep.family) * sweep.study.replicas
    assert outcome.stats.total("simulation") == total - 3
    assert outcome.skipped["simulation"] == 3

    _, again = sweep_into(out)
    assert again.stats.total() == 0
    assert again.skipped == {"simulation": total, "evaluation": 6}
    reference_results = ordered(reference[1].results)
    for results in (outcome.results, again.results):
        pd.testing.assert_frame_equal(ordered(results), reference_results)

    # Losing one recording costs exactly that simulation and its replica's evaluations (one
    # task for the replica's conditions).
    lost = sweep.family[2]
    (out / recording_path(1, lost)).unlink()
    _, repaired = sweep_into(out)
    assert repaired.stats.done == {"simulation": 1, "evaluation": 1}
    assert repaired.evaluated == len(sweep.conditions) * len(sweep.trains) == 3


class BrokenExperiment(Sweep):
    """Gives one experiment of replica 1 a parameter the FMU does not have."""

    broken_index = 2  # Jul at 2000 rpm, a held-out run (index 1 is the training run)

    def simulation_task(self, replica, experiment):
        task = super().simulation_task(replica, experiment)
        if replica == 1 and experiment == self.family[self.broken_index]:
            scenario = dataclasses.replace(task.args[0], parameters={"no_such_parameter": 1.0})
            task = dataclasses.replace(task, args=(scenario, *task.args[1:]))
        return task


class BrokenTraining(BrokenExperiment):
    broken_index = 1


def test_a_failed_simulation_is_recorded_and_the_sweep_goes_on(tmp_path, reference):
    out = tmp_path / "failing"
    sweep, outcome = sweep_into(out, BrokenExperiment)
    broken = sweep.family[BrokenExperiment.broken_index]
    assert broken not in sweep.trains
    assert outcome.stats.failed == {"simulation": 1}
    assert outcome.stats.done["simulation"] == len(sweep.family) * 2 - 1
    error = json.loads((out / failure_path(1, broken)).read_text())["error"]
    assert "no_such_parameter" in error and error.startswith("SpindlebenchError")
    results = outcome.results
    failed = results[results["error"] != ""]
    assert set(failed["test_experiment"]) == {broken.id} and set(failed["replica"]) == {1}
    assert failed["rmse_um"].isna().all()
    assert failed["error"].str.startswith("simulation failed: SpindlebenchError").all()
    assert results[results["error"] == ""]["rmse_um"].notna().all()
    assert len(results) == len(reference[1].results)
    assert "no_such_parameter" in (out / "README.md").read_text()

    # Resuming retries the failed simulation only; then nothing is missing any more.
    _, fixed = sweep_into(out)
    assert fixed.stats.done == {"simulation": 1, "evaluation": 1}  # the replica's 3 jobs
    assert fixed.evaluated == 3
    assert not (out / failure_path(1, broken)).exists()
    pd.testing.assert_frame_equal(ordered(fixed.results), ordered(reference[1].results))


def test_a_failed_training_run_fails_its_replica_only(tmp_path):
    _, outcome = sweep_into(tmp_path / "no-training", BrokenTraining)
    results = outcome.results
    replica_1 = results[results["replica"] == 1]
    assert replica_1["error"].str.startswith("training experiment failed: ").all()
    assert results[results["replica"] == 2]["rmse_um"].notna().all()


class BrokenEvaluation(Sweep):
    """Hands one evaluation a job without its data, so the whole evaluation raises."""

    def evaluation_task(self, replica, condition, trains):
        task = super().evaluation_task(replica, condition, trains)
        if replica == 2 and condition is None:
            task = dataclasses.replace(task, args=(dataclasses.replace(task.args[0], truths={}),))
        return task


def test_a_failed_evaluation_is_reported_and_retried(tmp_path, reference):
    out = tmp_path / "bad-evaluation"
    _, outcome = sweep_into(out, BrokenEvaluation)
    # the job fails inside its replica's task, which reports it per job: the task is done
    assert not outcome.stats.failed and outcome.stats.done["evaluation"] == 2
    failed = outcome.results[outcome.results["error"] != ""]
    assert len(failed) == 1 and failed["error"].iloc[0].startswith("evaluation failed: KeyError")
    assert failed["replica"].iloc[0] == 2 and failed["data"].iloc[0] == "noise-free"
    _, fixed = sweep_into(out)
    assert fixed.stats.done == {"evaluation": 1}
    pd.testing.assert_frame_equal(ordered(fixed.results), ordered(reference[1].results))


def test_dask_local_cluster_gives_the_same_numbers(tmp_path, reference):
    import distributed  # here, not at collection: only this test needs it

    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  protocol="tcp://", dashboard_address=None) as cluster:
        outcome = run_sweep(TINY, tmp_path / "dask", dask_address=cluster.scheduler_address,
                            progress=False)
    assert outcome.stats.done == {"simulation": 8, "evaluation": 2}  # a task per replica
    pd.testing.assert_frame_equal(ordered(outcome.results), ordered(reference[1].results))
    assert "Dask cluster at tcp://" in (tmp_path / "dask" / "provenance.json").read_text()


def test_a_folder_of_another_study_is_not_resumed(tmp_path, reference):
    out = tmp_path / "other"
    shutil.copytree(reference[1].out_dir, out)
    changed = tmp_path / "tiny_changed.toml"
    changed.write_text(TINY.read_text().replace("seed = 7", "seed = 8"))
    with pytest.raises(SpindlebenchError) as refused:
        run_sweep(changed, out, workers=0, progress=False)
    assert str(refused.value) == (
        f"{out}: holds results of a different study (study file key 'study.seed': 7 → 8); "
        "use a new output folder to run this study")


def test_a_comment_or_reordered_key_does_not_block_resuming(tmp_path, reference):
    out = tmp_path / "edited"
    shutil.copytree(reference[1].out_dir, out)
    edited = tmp_path / "tiny_edited.toml"
    text = TINY.read_text().replace("seed = 7\nreplicas = 2", "replicas = 2   # two days\nseed = 7")
    edited.write_text("# a note the user added\n" + text.replace(
        "[study]", '[study]\ndescription = "prose does not change a number"')
        .replace("speeds_rpm = [2000, 4000]", "speeds_rpm = [2000.0, 4000]"))
    assert edited.read_bytes() != TINY.read_bytes()
    outcome = run_sweep(edited, out, workers=0, progress=False)
    assert outcome.resumed and outcome.stats.total("simulation") == 0
    assert outcome.stats.total("evaluation") == 0
    provenance = json.loads((out / "provenance.json").read_text())
    original = json.loads((reference[1].out_dir / "provenance.json").read_text())
    assert provenance["study_content_sha256"] == original["study_content_sha256"]
    assert provenance["study"]["sha256"] != original["study"]["sha256"]  # the raw file hash


def test_a_state_file_without_the_pinned_content_is_refused(tmp_path, reference):
    """A state.json that pins no study content (an unreleased early format) is not adopted:
    one line, and the folder is left as it was."""
    from spindlebench.core.provenance import sha256_file

    out = tmp_path / "old"
    shutil.copytree(reference[1].out_dir, out)
    fmu = load_study(TINY).fmu
    old_state = {"inputs": {"study_sha256": sha256_file(TINY), "fmu_sha256": sha256_file(fmu)}}
    (out / "state.json").write_text(json.dumps(old_state))
    with pytest.raises(SpindlebenchError) as refused:
        run_sweep(TINY, out, workers=0, progress=False)
    assert str(refused.value) == (f"{out / 'state.json'}: not a study state file; choose "
                                  "another output folder")
    assert json.loads((out / "state.json").read_text()) == old_state


def test_command_line(tmp_path, capsys, reference):
    out = tmp_path / "cli"
    shutil.copytree(reference[1].out_dir, out)
    assert cli.main(["sweep", str(TINY), "-o", str(out), "--workers", "0",
                     "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert "resumed: ran 0 simulation(s) and 0 evaluation(s)" in printed
    assert "skipped 8 done simulation(s), 6 done evaluation(s)" in printed
    # "in all" is the whole command's wall time, so it holds the runner's own seconds
    wall = re.search(r"evaluation\(s\) in (\d+\.\d) s \(skipped.* (\d+\.\d) s in all",
                     printed)
    assert wall and float(wall[2]) >= float(wall[1])
    bad = tmp_path / "bad.toml"
    bad.write_text(TINY.read_text().replace("replicas = 2", "replicas = -1"))
    assert cli.main(["sweep", str(bad), "-o", str(tmp_path / "x"), "--no-progress"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"error: {bad}: key 'study.replicas': must be in [1, 10000], got -1"]
    assert not (tmp_path / "x").exists()


class EveryExperimentBroken(Sweep):
    """Every simulation gets a parameter the FMU does not have (a run-time failure)."""

    def simulation_task(self, replica, experiment):
        task = super().simulation_task(replica, experiment)
        scenario = dataclasses.replace(task.args[0], parameters={"no_such_parameter": 1.0})
        return dataclasses.replace(task, args=(scenario, *task.args[1:]))


def test_when_every_simulation_fails_the_sweep_says_so_in_one_line(tmp_path):
    out = tmp_path / "all-failed"
    with pytest.raises(SpindlebenchError) as info:
        sweep_into(out, EveryExperimentBroken)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("sweep: all 8 simulations failed; first: SpindlebenchError: ")
    assert "no_such_parameter" in message
    assert message.endswith(f"see {out / 'runs' / 'r001'}/Jan-2000rpm-constant-off.error.json")
    results = pd.read_csv(out / "results.csv")
    assert len(results) and results["rmse_um"].isna().all()
    assert results["error"].str.startswith("training experiment failed: ").all()
    readme = (out / "README.md").read_text(encoding="utf-8")
    assert "all 8 simulations failed" in readme and "no_such_parameter" in readme
    assert not (out / "summary").exists()


class EveryEvaluationBroken(Sweep):
    def evaluation_task(self, replica, condition, trains):
        task = super().evaluation_task(replica, condition, trains)
        return dataclasses.replace(task, args=(dataclasses.replace(task.args[0], truths={}),))


def test_when_every_evaluation_fails_the_sweep_says_so_in_one_line(tmp_path, reference):
    out = tmp_path / "no-evaluation"
    shutil.copytree(reference[1].out_dir / "runs", out / "runs")
    shutil.copy(reference[1].out_dir / "state.json", out / "state.json")
    with pytest.raises(SpindlebenchError, match=r"^sweep: no evaluation produced an RMSE "
                                                r"\(6 result rows, 0 of 8 simulations failed\); "
                                                r"first: evaluation failed: KeyError"):
        sweep_into(out, EveryEvaluationBroken)
    assert "no evaluation produced an RMSE" in (out / "README.md").read_text(encoding="utf-8")
