"""Benchmark: what translating the machine model costs a command, with and without the
translated-model cache (``spindlebench.model.ode_cache``).

Each process that needs the machine's equations (``calibrate``, ``observe``, the course's
notebooks, a test's child interpreter) translated ``models/SpindleBench.mo`` again: pymoca's
parse and flatten, the unit checks and the causalisation. The cache keeps the result on disk,
keyed by the source and the code that translates it. This script measures, in CPU seconds of
the child process (user + system, ``RUSAGE_CHILDREN``: load-independent on this shared
machine), ``RUNS`` times each:

- ``explicit_ode`` alone in a fresh interpreter (imports included), with an empty cache
  folder (the translation, then the file written) and then with the file there;
- a small ``spindlebench calibrate`` end to end (the 30 min ``scenarios/examples/quick.toml``
  recording through 2 sensors and the drift, one parameter fitted), the same two ways.

The minimum and the median are printed with the ratio of cold to warm, and written to
``bench/results/bench_translation.json`` with the machine, load and date.

Run: .venv/bin/python bench/bench_translation.py
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from spindlebench.calibration.mapping import recording_map_text
from spindlebench.model.ode_cache import CACHE_ENV

from results import record

RUNS = 3
REPO = Path(__file__).resolve().parents[1]
#: The twin that is calibrated: the shipped 30-minute smoke-test scenario.
TWIN = REPO / "scenarios" / "examples" / "quick.toml"


def spindlebench() -> list[str]:
    """The console script beside this interpreter, else ``python -m spindlebench``."""
    script = Path(sys.executable).with_name("spindlebench")
    return [str(script)] if script.exists() else [sys.executable, "-m", "spindlebench"]


def child_cpu_s(argv: list[str], cache: Path, cwd: Path) -> float:
    """CPU seconds of one run of ``argv`` with the translated-model cache in ``cache``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(argv, cwd=cwd, env={**os.environ, CACHE_ENV: str(cache)}, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> int:
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-translation-") as name:
        folder = Path(name)
        (folder / "map.toml").write_text(recording_map_text(["T1", "T4"]), encoding="utf-8")
        subprocess.run([*spindlebench(), "simulate", str(TWIN), "-o", "twin.csv", "-q"],
                       cwd=folder, check=True)
        commands = {
            "explicit_ode in a fresh interpreter": [
                sys.executable, "-c", "from spindlebench.model.equations import explicit_ode; "
                f"explicit_ode({str(REPO / 'models')!r})"],
            "small calibrate (30 min, 1 parameter)": [
                *spindlebench(), "calibrate", "twin.csv", "--map", "map.toml", "-o",
                "out/twin.toml", "--models", str(REPO / "models"), "--fit",
                "front_bearing_friction_f0", "-q"],
        }
        print(f"load average before {', '.join(f'{v:.1f}' for v in os.getloadavg())}")
        print(f"{'CPU-s (min / median of ' + str(RUNS) + ')':<44}{'cold':>14}{'warm':>14}"
              f"{'cold/warm':>11}")
        for label, argv in commands.items():
            cold, warm = [], []
            for run in range(RUNS):
                cache = folder / f"cache-{label[:5]}-{run}"
                cold.append(child_cpu_s(argv, cache, folder))  # empty: translated, stored
                warm.append(child_cpu_s(argv, cache, folder))  # the file is there
            ratio = min(cold) / min(warm)
            print(f"{label:<44}{min(cold):7.2f}{statistics.median(cold):7.2f}"
                  f"{min(warm):7.2f}{statistics.median(warm):7.2f}{ratio:10.1f}x")
            rows.append({"command": label, "cold_cpu_s_min": min(cold),
                         "cold_cpu_s_median": statistics.median(cold),
                         "warm_cpu_s_min": min(warm), "warm_cpu_s_median": statistics.median(warm),
                         "cold_over_warm": ratio})
    path = record("bench_translation", rows)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
