"""Issue 25: a sweep on a real Dask cluster (a scheduler and workers, each its own process,
started in another folder), with a worker killed mid-sweep; and addresses that cannot work.

The LocalCluster test in ``test_sweep_run.py`` runs its worker inside the test process, so
it shares the test's folder and cannot lose a worker: neither fault can show there.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import REPO

DASK = Path(sys.executable).parent / "dask"
TINY = Path("scenarios") / "studies" / "tiny_sweep.toml"  # relative: run from REPO
#: What differs between two correct runs on different executors: provenance.json and the
#: README (which quotes it) name the executor (in-process vs the cluster's address), and
#: manifest.json holds provenance.json's hash.
EXECUTOR_NAMED = ("provenance.json", "README.md", "manifest.json")


def spindlebench(*args: str, cwd: Path = REPO) -> subprocess.CompletedProcess | subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "spindlebench", *args], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=_env())


def _env() -> dict[str, str]:
    """This checkout's package on the path of every process (the workers import it)."""
    path = os.pathsep.join(filter(None, [str(REPO / "pipeline"), os.environ.get("PYTHONPATH")]))
    return {**os.environ, "PYTHONPATH": path}


def one_error_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("error: ") and "Traceback" not in stderr
    return lines[0]


@pytest.fixture
def cluster(tmp_path):
    """``dask scheduler`` and two single-threaded ``dask worker`` processes (no nanny: a
    killed worker stays dead), started in a folder that holds no study."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    address_file = elsewhere / "scheduler.json"
    quiet = {"cwd": elsewhere, "env": _env(), "stdout": subprocess.DEVNULL,
             "stderr": subprocess.DEVNULL}
    processes = [subprocess.Popen([str(DASK), "scheduler", "--scheduler-file",
                                   str(address_file), "--port", "0", "--dashboard-address",
                                   ":0", "--no-show"], **quiet)]
    try:
        deadline = time.monotonic() + 180
        while not address_file.is_file():
            assert processes[0].poll() is None and time.monotonic() < deadline
            time.sleep(0.1)
        workers = [subprocess.Popen([str(DASK), "worker", "--scheduler-file",
                                     str(address_file), "--nthreads", "1", "--no-nanny",
                                     "--no-dashboard"], **quiet) for _ in range(2)]
        processes += workers
        address = json.loads(address_file.read_text(encoding="utf-8"))["address"]
        import distributed  # here, not at collection

        with distributed.Client(address, timeout="120s") as client:
            client.wait_for_workers(2, timeout=180)
        yield address, workers, processes[0]
    finally:
        for process in processes:
            process.kill()
            process.wait()


def files_of(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != ".lock" and p.name not in EXECUTOR_NAMED}


@pytest.mark.slow
def test_a_worker_killed_mid_sweep_loses_no_result_and_a_relative_study_path_works(
        tmp_path, cluster):
    address, workers, scheduler = cluster
    reference = tmp_path / "reference"
    run = spindlebench("sweep", str(TINY), "-o", str(reference), "--workers", "0",
                       "--no-progress")
    _, stderr = run.communicate(timeout=900)
    assert run.returncode == 0, stderr
    out = tmp_path / "dask"
    child = spindlebench("sweep", str(TINY), "-o", str(out), "--dask-address", address,
                         "--no-progress")
    deadline = time.monotonic() + 600
    while not [p for p in out.glob("runs/*/*.csv") if p.with_suffix(".json").is_file()]:
        assert child.poll() is None and time.monotonic() < deadline, child.communicate()
        time.sleep(0.05)
    os.kill(workers[0].pid, signal.SIGKILL)  # mid-sweep: 7 of 8 simulations still to come
    _, stderr = child.communicate(timeout=900)
    assert child.returncode == 0, stderr
    assert not list(out.rglob("*.error.*"))  # before: FileNotFoundError on every run
    assert files_of(out) == files_of(reference)
    assert address in (out / "provenance.json").read_text(encoding="utf-8")
    # the scheduler saw sealed tasks only (executor.SealedCall): it never unpickled a study
    # task, which imported the study's modules (SciPy, pandas) into it
    loaded = Path(f"/proc/{scheduler.pid}/maps").read_text(encoding="utf-8")
    assert f"{os.sep}scipy{os.sep}" not in loaded and f"{os.sep}pandas{os.sep}" not in loaded


@pytest.mark.slow
@pytest.mark.parametrize("address", ["tls://127.0.0.1:9", "inproc://scheduler",
                                     "tcp://127.0.0.1:9"])
def test_an_address_that_cannot_work_is_one_line_and_nothing_else(tmp_path, address):
    """tls:// without a TLS set-up printed the line, then waited 20 s and dumped the client's
    ``__del__`` traceback at exit."""
    child = spindlebench("sweep", str(TINY), "-o", str(tmp_path / "out"), "--dask-address",
                         address, "--no-progress")
    _, stderr = child.communicate(timeout=300)
    assert child.returncode == 2
    assert address in one_error_line(stderr)
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_a_study_cluster_forks_its_workers_preloaded_and_single_threaded_in_blas(tmp_path):
    """``dask worker --preload-nanny spindlebench.studies.running.dask_plugin`` (the study
    cluster of docs/speed.md): both workers are forked from one forkserver that has imported
    the study's task modules, so they hold them before any task; each runs one BLAS thread
    and no profiler before a study connects; and a study's task runs there, sealed."""
    from spindlebench.studies.running.dask_plugin import FORKSERVER_PRELOAD
    from spindlebench.studies.running.executor import TASK_MODULES, call_isolated, dask_executor
    from spindlebench.studies.sweep.sweep_run import condition_id

    address_file = tmp_path / "scheduler.json"
    quiet = {"cwd": tmp_path, "env": _env(), "stdout": subprocess.DEVNULL,
             "stderr": subprocess.DEVNULL}
    processes = [subprocess.Popen([str(DASK), "scheduler", "--scheduler-file",
                                   str(address_file), "--port", "0", "--no-dashboard"],
                                  **quiet)]
    try:
        deadline = time.monotonic() + 180
        while not address_file.is_file():
            assert processes[0].poll() is None and time.monotonic() < deadline
            time.sleep(0.1)
        processes.append(subprocess.Popen(
            [str(DASK), "worker", "--scheduler-file", str(address_file), "--nworkers", "2",
             "--nthreads", "1", "--no-dashboard", "--memory-limit", "0", "--preload-nanny",
             "spindlebench.studies.running.dask_plugin"], **quiet))
        address = json.loads(address_file.read_text(encoding="utf-8"))["address"]
        import distributed  # here, not at collection

        def state(dask_worker):  # nested: pickled by value, run in each worker
            import psutil
            import threadpoolctl

            return {"parent": os.getppid(),
                    "parent_command": " ".join(psutil.Process(os.getppid()).cmdline()),
                    "loaded": sorted(set(TASK_MODULES) & set(sys.modules)),
                    "blas_threads": {pool["num_threads"]
                                     for pool in threadpoolctl.threadpool_info()},
                    "profiling": "profile" in dask_worker.periodic_callbacks}

        with distributed.Client(address, timeout="120s") as client:
            client.wait_for_workers(2, timeout=180)
            workers = list(client.run(state).values())
        with dask_executor(address) as executor:
            done = executor.submit(call_isolated, condition_id, (None,)).result()
    finally:
        for process in reversed(processes):
            process.terminate()
            process.wait(timeout=60)
    assert len(workers) == 2 and len({worker["parent"] for worker in workers}) == 1
    forkserver = workers[0]["parent_command"]
    assert "multiprocessing.forkserver" in forkserver
    assert str(list(FORKSERVER_PRELOAD)) in forkserver
    for worker in workers:
        assert worker["loaded"] == sorted(TASK_MODULES)  # before any task: preloaded
        assert worker["blas_threads"] == {1} and not worker["profiling"]
    assert done[:2] == ("noise-free", None)
