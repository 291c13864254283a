"""The runner unpacks the FMU once per process (it used to unzip it for every simulation)
and removes the folder when the process ends: the main process, a worker process, and the
folders of processes killed before they could clean up."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
from conftest import QUICK
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.testbench import runner
from spindlebench.testbench.scenario import load_scenario


def _quick(tmp_path):
    path = tmp_path / "quick.toml"
    path.write_text(QUICK, encoding="utf-8")
    return load_scenario(path)


def test_one_extraction_per_process_gives_the_same_simulation(tmp_path):
    scenario = _quick(tmp_path)
    info = runner.inspect_fmu(DEFAULT_FMU)
    runner.forget_extracted(info)
    first = runner.co_simulate(scenario, DEFAULT_FMU)
    folder = runner.extracted_fmu(info)
    second = runner.co_simulate(scenario, DEFAULT_FMU)
    assert runner.extracted_fmu(info) == folder and folder.is_dir()
    assert folder.name.startswith(f"spindlebench-fmu-cache-{os.getpid()}-")
    runner.forget_extracted(info)  # a fresh unzip: the old way, once per simulation
    assert not folder.exists()
    fresh = runner.co_simulate(scenario, DEFAULT_FMU)
    for name, values in fresh.outputs.items():
        assert np.array_equal(first.outputs[name], values)
        assert np.array_equal(second.outputs[name], values)


SCRIPT = """
import concurrent.futures as cf, multiprocessing, sys
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.testbench import runner
from spindlebench.testbench.scenario import load_scenario

def simulate(path):
    runner.co_simulate(load_scenario(path), DEFAULT_FMU)
    return str(runner.extracted_fmu(runner.inspect_fmu(DEFAULT_FMU)))

if __name__ == "__main__":
    print(simulate(sys.argv[1]))
    context = multiprocessing.get_context("forkserver")
    with cf.ProcessPoolExecutor(1, mp_context=context) as pool:
        print(pool.submit(simulate, sys.argv[1]).result())
"""


def test_main_and_worker_processes_remove_their_folder_at_exit(tmp_path):
    _quick(tmp_path)
    script = tmp_path / "run.py"
    script.write_text(textwrap.dedent(SCRIPT), encoding="utf-8")
    # A short TMPDIR: the forkserver's socket is bound under it, and an AF_UNIX path has at
    # most 107 bytes (tmp_path under pytest-xdist, .../popen-gw0/<test>/, is too long).
    temp = Path(tempfile.mkdtemp(prefix="sb-cache-"))
    try:
        _run_and_check(tmp_path, script, temp)
    finally:
        shutil.rmtree(temp, ignore_errors=True)


def _run_and_check(tmp_path, script, temp):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    orphan = temp / f"spindlebench-fmu-cache-{dead}-abc"  # a process killed by SIGTERM
    (orphan / "binaries").mkdir(parents=True)
    done = subprocess.run([sys.executable, str(script), str(tmp_path / "quick.toml")],
                          capture_output=True, text=True, env={**os.environ, "TMPDIR": str(temp)},
                          timeout=300)
    assert done.returncode == 0, done.stderr
    main_folder, worker_folder = done.stdout.split()
    assert main_folder != worker_folder
    assert all(folder.startswith(str(temp)) for folder in (main_folder, worker_folder))
    assert list(temp.iterdir()) == []  # both removed at exit, and the orphan before
