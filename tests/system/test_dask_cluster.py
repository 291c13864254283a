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
