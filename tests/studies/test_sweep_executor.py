"""The study task runner: failure isolation, crash quarantine, follow-ups, Dask backend."""

from __future__ import annotations

import concurrent.futures as cf
import os
import time

import distributed
import pytest
from conftest import REPO
from spindlebench.core.errors import SpindlebenchError
from spindlebench.studies.running.executor import Task, TaskRunner, call_isolated, one_line_error


def square(x: int) -> int:
    if x == 3:
        raise ValueError("three is\nnot allowed")
    return x * x


def crash_on(x: int, bad: int) -> int:
    if x == bad:
        os._exit(1)  # a segfault in native FMU code looks like this to the pool
    return x + 100


def run(runner: TaskRunner, tasks, follow=None):
    outcomes = []

    def on_outcome(outcome):
        outcomes.append(outcome)
        return follow(outcome) if follow else ()

    stats = runner.run(tasks, on_outcome)
    return stats, {o.task.key: o for o in outcomes}


@pytest.mark.parametrize("workers", [0, 2])
def test_a_failing_task_is_recorded_and_the_rest_complete(workers):
    tasks = [Task(f"t{i}", square, (i,)) for i in range(6)]
    stats, outcomes = run(TaskRunner(workers=workers, progress=False), tasks)
    assert stats.done == {"task": 5} and stats.failed == {"task": 1}
    assert outcomes["t3"].error == "ValueError: three is not allowed"
    assert "Traceback" in outcomes["t3"].detail
    assert [outcomes[f"t{i}"].value for i in (0, 1, 2, 4, 5)] == [0, 1, 4, 16, 25]


class SlowToUnpickle:
    """An argument whose unpickling burns ``seconds`` of CPU in the worker, before the task
    function (and its CPU clock) starts."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds

    def __reduce__(self):
        return burn_then_make, (self.seconds,)


def burn_then_make(seconds: float) -> SlowToUnpickle:
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass
    return SlowToUnpickle(seconds)


def seconds_of(slow: SlowToUnpickle) -> float:
    return slow.seconds


@pytest.mark.parametrize("workers", [0, 1])
def test_worker_cpu_outside_the_tasks_is_counted_apart(workers):
    """Unpickling a task's arguments happens in the worker before ``call_isolated`` starts
    its clock: that CPU (and the worker's imports) is in ``outside_cpu_s``, not in the
    tasks' ``cpu_s``; in-process the study process's own CPU holds it, so it is 0 there."""
    tasks = [Task(f"s{i}", seconds_of, (SlowToUnpickle(0.2),)) for i in range(3)]
    stats, outcomes = run(TaskRunner(workers=workers, progress=False), tasks)
    assert all(o.value == 0.2 for o in outcomes.values())
    assert stats.cpu_s["task"] < 0.2
    if workers:
        assert stats.outside_cpu_s >= 3 * 0.2
        assert all(o.outside_cpu_s >= 0.2 for o in outcomes.values())
    else:
        assert stats.outside_cpu_s == 0.0


def test_workers_are_forked_with_their_tasks_modules_and_its_cpu_is_counted():
    """The forkserver imports the tasks' modules once (the sweep's: 2.3 CPU-s) and the
    workers are forked with them, instead of each importing them itself; that CPU is the
    forkserver's and is counted in ``outside_cpu_s`` too."""
    from multiprocessing import forkserver

    from spindlebench.studies.sweep.sweep_run import condition_id

    forkserver._forkserver._stop()  # a fresh one, started with this run's preload
    tasks = [Task("c", condition_id, (None,))]
    stats, outcomes = run(TaskRunner(workers=1, progress=False), tasks)
    assert outcomes["c"].value == "noise-free"
    worker = outcomes["c"].outside_cpu_s  # the worker's start-up, before its task
    assert stats.outside_cpu_s - worker > worker  # the forkserver's imports outweigh it


def test_a_study_clusters_workers_are_forked_with_the_modules_the_local_pool_preloads():
    """The local pool preloads its tasks' modules (``TaskRunner._opener``); a study cluster's
    forkserver, started before any task is known, preloads ``TASK_MODULES``
    (``dask_plugin.FORKSERVER_PRELOAD``): they must be the modules of a study's tasks."""
    from spindlebench.studies.running import jobs
    from spindlebench.studies.running.dask_plugin import FORKSERVER_PRELOAD
    from spindlebench.studies.running.executor import TASK_MODULES

    assert {jobs.simulate_job.__module__, jobs.evaluate_job.__module__} == set(TASK_MODULES)
    assert FORKSERVER_PRELOAD[0] == "__main__"
    assert set(TASK_MODULES) < set(FORKSERVER_PRELOAD)


def test_the_study_process_start_up_is_frozen_out_of_the_collector():
    """A full collection of the study process rescans its 140 000 start-up objects (0.1
    CPU-s each): a run freezes them (``freeze_start_up``)."""
    import gc

    run(TaskRunner(workers=0, progress=False), [Task("t", square, (2,))])
    assert gc.get_freeze_count() > 10_000


def test_follow_up_tasks_run_after_their_trigger():
    def follow(outcome):
        if outcome.task.kind == "first" and outcome.ok:
            return [Task(f"second-{outcome.task.key}", square, (outcome.value,), kind="second")]
        return ()

    tasks = [Task(f"{i}", square, (i,), kind="first") for i in (1, 2, 3)]
    stats, outcomes = run(TaskRunner(workers=2, progress=False), tasks, follow)
    assert stats.done == {"first": 2, "second": 2} and stats.failed == {"first": 1}
    assert outcomes["second-2"].value == 16


def test_a_crashing_worker_is_pinned_on_its_task_and_the_others_survive():
    tasks = [Task(f"c{i}", crash_on, (i, 4)) for i in range(8)]
    stats, outcomes = run(TaskRunner(workers=2, progress=False), tasks)
    assert stats.failed == {"task": 1}
    assert "worker process died" in outcomes["c4"].error
    assert {k: o.value for k, o in outcomes.items() if o.ok} == {
        f"c{i}": i + 100 for i in range(8) if i != 4}


def test_dask_local_cluster_runs_the_same_tasks():
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  protocol="tcp://", dashboard_address=None) as cluster:
        runner = TaskRunner(dask_address=cluster.scheduler_address, progress=False)
        assert runner.describe().startswith("Dask cluster at tcp://")
        stats, outcomes = run(runner, [Task(f"t{i}", square, (i,)) for i in range(5)])
    assert stats.done == {"task": 4} and stats.failed == {"task": 1}
    assert outcomes["t4"].value == 16
    assert outcomes["t3"].error.startswith("ValueError")


def test_unreachable_dask_scheduler_is_one_clear_line():
    runner = TaskRunner(dask_address="tcp://127.0.0.1:9", progress=False, connect_timeout_s=1)
    with pytest.raises(SpindlebenchError, match=r"--dask-address tcp://127.0.0.1:9: cannot "
                                                r"connect to a Dask scheduler"):
        runner.run([Task("t", square, (1,))])


@pytest.mark.parametrize("address", ["foo", "tcp://host", "http://host:8786", "tcp://a b:1"])
def test_malformed_dask_address_is_refused_before_connecting(address):
    with pytest.raises(SpindlebenchError, match="expected a scheduler address like tcp://"):
        TaskRunner(dask_address=address)


def test_one_line_error_is_short_and_single_line():
    message = one_line_error(RuntimeError("a\nb " + "x" * 500))
    assert "\n" not in message and len(message) < 330 and message.startswith("RuntimeError: a b")


@pytest.mark.parametrize("name", ["../../escape/tiny-sweep", "a/b", "", "..", "tiny sweep"])
@pytest.mark.parametrize("command", ["sweep", "place"])
def test_a_study_name_that_is_no_folder_name_is_refused_without_o(tmp_path, monkeypatch,
                                                                  capsys, name, command):
    from spindlebench.commands import main as cli

    repo = REPO
    tiny = repo / "scenarios" / "studies" / ("tiny_sweep.toml" if command == "sweep"
                                            else "tiny_placement.toml")
    study = tmp_path / "work" / "study.toml"
    study.parent.mkdir()
    text = tiny.read_text(encoding="utf-8")
    study.write_text(text.replace(f'name = "tiny-{"sweep" if command == "sweep" else "placement"}"',
                                  f'name = "{name}"'), encoding="utf-8")
    monkeypatch.chdir(study.parent)
    assert cli.main([command, str(study), "--workers", "0", "--no-progress"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        f"error: {study}: key 'study.name': {name!r} cannot name a folder under results/ (use "
        "only letters, digits, '.', '_' and '-'), or give -o/--out"]
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["study.toml", "work"]


@pytest.mark.parametrize("command", ["sweep", "place"])
def test_an_unreachable_scheduler_fails_before_the_results_folder_is_made(tmp_path, monkeypatch,
                                                                         capsys, command):
    import functools

    from spindlebench.commands import main as cli
    from spindlebench.studies.placement import placement_run as place
    from spindlebench.studies.sweep import sweep_run as sweep

    for module in (sweep, place):  # a short connect timeout keeps the test fast
        monkeypatch.setattr(module, "TaskRunner", functools.partial(TaskRunner,
                                                                    connect_timeout_s=1))
    studies = REPO / "scenarios" / "studies"
    study = studies / ("tiny_sweep.toml" if command == "sweep" else "tiny_placement.toml")
    out = tmp_path / "out"
    assert cli.main([command, str(study), "-o", str(out), "--dask-address",
                     "tcp://127.0.0.1:9", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --dask-address tcp://127.0.0.1:9: "
                                               "cannot connect to a Dask scheduler")
    assert not out.exists()


def test_dask_workers_get_one_blas_thread_like_the_local_pool():
    """``dask_executor`` registers ``OneBlasThread``: in a real worker process the BLAS
    variables are 1 and every loaded BLAS/OpenMP library runs one thread, also where the
    nanny does not set the variables (Dask's ``pre-spawn-environ`` emptied here, as for a
    worker started without a nanny; with it, a worker here runs OpenBLAS on 2 threads)."""
    import dask
    import threadpoolctl
    from spindlebench.studies.running.executor import dask_executor

    with (dask.config.set({"distributed.nanny.pre-spawn-environ": {}}),
          distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                   protocol="tcp://", dashboard_address=None) as cluster,
          dask_executor(cluster.scheduler_address) as executor):
        variables = {name: executor.submit(os.getenv, name).result()
                     for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
        pools = executor.submit(threadpoolctl.threadpool_info).result()
        worker_pid = executor.submit(os.getpid).result()
    assert worker_pid != os.getpid()
    assert variables == dict.fromkeys(variables, "1")
    blas = [pool for pool in pools if pool["user_api"] == "blas"]
    assert blas and all(pool["num_threads"] == 1 for pool in pools)


def test_dask_workers_and_nannies_are_quieted():
    """``dask_executor`` stops each worker's statistical profiler and slows its event-loop
    tick and system monitor (``dask_plugin.QUIET``), and the nanny's too: an idle cluster
    otherwise wakes every 10-20 ms."""
    from distributed import get_worker
    from spindlebench.studies.running.executor import dask_executor

    def periods():
        callbacks = get_worker().periodic_callbacks
        return ("profile" in callbacks, callbacks["tick"].callback_time,
                callbacks["monitor"].callback_time)

    with (distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                   protocol="tcp://", dashboard_address=None) as cluster,
          dask_executor(cluster.scheduler_address) as executor):
        profiling, tick_ms, monitor_ms = executor.submit(periods).result()
        nanny = next(iter(cluster.workers.values()))
        nanny_tick_ms = nanny.periodic_callbacks["tick"].callback_time
    assert not profiling
    assert (tick_ms, monitor_ms, nanny_tick_ms) == (1000, 5000, 1000)


def test_dask_tasks_are_not_hashed_into_shared_keys():
    """``dask_executor`` submits impure tasks: Dask's default hashes every argument (a whole
    evaluation job's truths) in the coordinator to make a key shared by identical calls, so
    two identical calls ran once. Here two identical calls run twice."""
    import time

    from spindlebench.studies.running.executor import dask_executor

    with (distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                   protocol="tcp://", dashboard_address=None) as cluster,
          dask_executor(cluster.scheduler_address) as executor):
        first = executor.submit(time.perf_counter_ns).result()
        second = executor.submit(time.perf_counter_ns).result()
    assert second > first


def test_the_scheduler_is_handed_sealed_tasks_and_the_workers_hold_sealed_values():
    """A study task reaches the scheduler as ``pickle.loads(BYTES)`` (``SealedCall``): the
    scheduler unpickles what it is given, and unpickling a study's task made it import the
    study's modules and rebuild every evaluation job's data. The worker still runs the call,
    its exceptions come back as data, and it holds the value as bytes (``sealed_value``:
    Dask measured every recording frame's columns), which the client's future unpickles."""
    import pickle

    from distributed.diagnostics.plugin import SchedulerPlugin
    from spindlebench.studies.running.executor import dask_executor

    class Seen(SchedulerPlugin):
        """Each finished task's spec and the type of the value its worker holds (read as it
        finishes: the scheduler forgets a task once its client has the value)."""

        def __init__(self, scheduler):
            self.scheduler, self.tasks = scheduler, []

        def transition(self, key, start, finish, *args, **kwargs):
            if finish == "memory":
                task = self.scheduler.tasks[key]
                self.tasks.append((task.run_spec, task.type))

    with (distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                   protocol="tcp://", dashboard_address=None) as cluster,
          dask_executor(cluster.scheduler_address) as executor):
        seen = Seen(cluster.scheduler)
        cluster.scheduler.add_plugin(seen)
        future = executor.submit(call_isolated, square, (2,))
        failed = executor.submit(call_isolated, square, (3,))
        assert future.result()[:2] == (4, None)
        assert failed.result()[1].startswith("ValueError")
    assert len(seen.tasks) == 2
    for spec, held in seen.tasks:
        assert spec.func is pickle.loads
        assert [type(arg) for arg in spec.args] == [bytes]
        assert held == "bytes"


def test_cancelling_a_sealed_task_s_future_cancels_the_task_it_stands_for(tmp_path):
    """``SealedExecutor``'s futures stand for the inner executor's (a Dask client's, which
    passes a cancel on to the scheduler): a task cancelled while it waits is never run."""
    from spindlebench.studies.running.executor import SealedExecutor

    ran = tmp_path / "ran"  # a task runs a copy of what it was given: a file tells
    with cf.ThreadPoolExecutor(max_workers=1) as pool:
        executor = SealedExecutor(pool)
        first = executor.submit(time.sleep, 1.0)  # holds the one thread for a second
        second = executor.submit(ran.touch)
        assert second.cancel()
        assert first.result() is None
    assert not ran.exists()  # the pool ran the first task only


def test_a_script_that_runs_at_its_top_level_is_told_to_guard_it(tmp_path):
    """Each local worker imports the main script: one that starts its run at the top level,
    without ``if __name__ == "__main__":``, started it again in every worker, which died
    with a traceback, and the run said only "worker process died". Now the script stops
    before the pool starts, in one line naming its file and line (``main_guard``); where its
    source is not a ``.py`` file to read, each worker says the same in one line, no
    traceback; with the guard the same script runs its task."""
    import subprocess
    import sys

    body = ("import os\n"
            "from spindlebench.studies.running.executor import Task, TaskRunner\n"
            "{guard}"
            "{indent}stats = TaskRunner(workers=1, progress=False).run([Task('t', os.getpid)])\n"
            "{indent}print('done', stats.total('task'))\n")
    env = {**os.environ, "PYTHONPATH": str(REPO / "pipeline")}

    def python(*args):
        return subprocess.run([sys.executable, *map(str, args)], capture_output=True,
                              text=True, env=env, cwd=tmp_path, timeout=120, check=False)

    def run(name, guarded):
        script = tmp_path / name
        script.write_text(body.format(guard="if __name__ == '__main__':\n" if guarded else "",
                                      indent="    " if guarded else ""), encoding="utf-8")
        return script, python(script)

    script, done = run("guarded.py", guarded=True)
    assert done.returncode == 0 and "done 1" in done.stdout, done.stderr
    script.write_text(script.read_text().replace("if __name__ == '__main__':",
                                                 "if len(sys.argv) and '__main__' == __name__:")
                      .replace("import os\n", "import os\nimport sys\n"))
    done = python(script)  # a guard written another way
    assert done.returncode == 0 and "done 1" in done.stdout, done.stderr
    script, done = run("unguarded.py", guarded=False)
    assert done.returncode != 0 and "done" not in done.stdout
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith(f"spindlebench.core.errors.SpindlebenchError: {script}:3: starts a "
                           "run with worker processes at the script's top level"), done.stderr
    assert '`if __name__ == "__main__":`' in last
    assert "worker process died" not in done.stderr
    package = tmp_path / "package"  # a package's __main__ is never imported again
    package.mkdir()
    (package / "__init__.py").write_text("", encoding="utf-8")
    (package / "__main__.py").write_text((tmp_path / "unguarded.py").read_text())
    done = python("-m", "package")
    assert done.returncode == 0 and "done 1" in done.stdout, done.stderr
    script, done = run("unguarded_script", guarded=False)  # not .py: the workers tell
    errors = [line for line in done.stderr.splitlines() if line.startswith("error: ")]
    assert errors and "Traceback" not in done.stderr, done.stderr
    assert errors[0].startswith(f"error: {script}: starts a run with worker processes")
