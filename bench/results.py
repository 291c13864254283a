"""Machine-readable bench results: ``record(script, rows, goals)`` writes
``bench/results/<script>.json``.

Every bench script prints its table for a reader and, at the end of its ``main``, hands the
same numbers to ``record`` so that docs and the lead can quote a figure with the machine, the
load and the date it was measured on (a number in CPU seconds without its load and machine is
not comparable across runs on this shared machine), and with the speed of a CPU second at the
script's start and end (``speed_probe_ms``). The file is written atomically
(``spindlebench.core.atomic``): a benchmark interrupted half-way leaves the previous result.
"""

from __future__ import annotations

import datetime
import json
import os
import subprocess
import time
from pathlib import Path
from typing import Any

from spindlebench.core import atomic

#: Where the results go: ``bench/results/<script>.json`` beside the scripts.
RESULTS_DIR = Path(__file__).resolve().parent / "results"


#: The fixed work ``speed_probe_ms`` times: this many integer additions in a Python loop.
PROBE_ADDITIONS = 1_000_000
#: ``speed_probe_ms`` keeps the fastest of this many timings (a slower one is interference).
PROBE_REPEATS = 3


def speed_probe_ms() -> float:
    """CPU milliseconds of a fixed pure-Python workload (``PROBE_ADDITIONS`` additions), the
    fastest of ``PROBE_REPEATS``: how much work a CPU second did when a figure was measured.

    Why: CPU seconds are not a fixed amount of work on this shared virtual machine. On
    2026-12-03 the same 3 million additions took 0.26 to 0.71 CPU-s within minutes at a load
    average near 0, their CPU time equal to their wall time (none stolen: presumably a
    neighbour on the host slows the core itself, which neither the load average nor
    ``/proc/stat``'s steal time shows); the probe itself moved from 41 to 81 ms in three
    processes started one after another. The machine's host changes between sessions as
    well (the CPU model in ``machine`` names it): the 1 008-experiment sweep's simulations
    cost 1.8x their CPU of a run three hours earlier on another CPU model (34.9 against
    19.5 CPU-s). So the probe marks a slow phase rather than correcting a figure; ratios
    measured in one run move far less (that sweep's over its simulations: 2.29x against
    2.14x)."""
    best = float("inf")
    for _ in range(PROBE_REPEATS):
        start, total = time.process_time(), 0
        for number in range(PROBE_ADDITIONS):
            total += number
        best = min(best, time.process_time() - start)
    return 1000.0 * best


#: The probe when the bench script imported this module (at its start).
PROBE_AT_START_MS = speed_probe_ms()


def cpu_model() -> str:
    """The CPU's model name from ``/proc/cpuinfo`` (``"unknown"`` where there is none)."""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def git_commit() -> str | None:
    """The checkout's commit (with ``+dirty`` when files differ from it, the results folder
    aside: a script writing its rows after each one must not mark its own file), or None."""
    here = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"],
                                capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain",
                                "--untracked-files=no", "--", ":/", ":(exclude,top)bench/results"],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return commit + ("+dirty" if dirty else "")


def machine() -> dict[str, Any]:
    """What the numbers were measured on: cores and CPU model."""
    return {"nproc": os.cpu_count(), "cpu_model": cpu_model()}


def record(script: str, rows: list[dict], goals: dict | None = None,
           folder: Path = RESULTS_DIR, name: str | None = None) -> Path:
    """Write ``<folder>/<script>.json`` with the machine, load average, speed probe (at the
    script's start and now), UTC date, git commit, the goals and the rows; return its path.
    ``script`` is the bench script's stem (``bench_startup``); ``name``, when given, the
    file's stem instead, for a second kind of run of the same script (``bench_dask
    --compare`` writes ``bench_dask_compare.json``)."""
    document = {
        "script": script,
        "date_utc": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "machine": machine(),
        "load_average": list(os.getloadavg()),
        "speed_probe_ms": {"start": PROBE_AT_START_MS, "end": speed_probe_ms(),
                           "additions": PROBE_ADDITIONS},
        "git_commit": git_commit(),
        "goals": goals or {},
        "rows": rows,
    }
    path = folder / f"{name or script}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, json.dumps(document, indent=2, sort_keys=True, default=float) + "\n")
    return path
