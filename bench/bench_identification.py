"""Identification of the 46 h CAIVIAC recording (issue 22: <= 60 s on this machine).

    PYTHONPATH=pipeline python bench/bench_identification.py [--source data.csv]

Runs ``spindlebench identify`` on the whole recording (11 115 samples at 15 s, read in place
from ``../shared/recordings/caiviac-fl-thermal/data.csv``) with the map below (speed, ch3 as
the error, the ambient unknown, t1/t4 as sensors), once per form: the grey-box network with
its order chosen by leave-one-cycle-out (six cycles x three orders, then the final fit), a
fixed 2-node network, the first-order transfer function, and the 2-node network with the
observer on t1 and t4. Prints wall and CPU seconds of each (the command in-process, so the
interpreter's start-up is not counted) and the load average, since the machine is shared,
and writes the rows to ``bench/results/bench_identification.json`` (``bench/results.py``).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from spindlebench.adapters import caiviac
from spindlebench.commands.main import main

from results import record

MAP = """[inputs]
spindle_speed_rpm = "spindle_rpm"
feed_x_mm_per_min = 0.0
feed_y_mm_per_min = 0.0
ambient_C = "unknown"

[error]
column = "ch3_um"
sign = -1

[temperatures]
t1_C = "T1"
t4_C = "T8"
"""

RUNS = {
    "network, order by leave-one-cycle-out": [],
    "network, 2 nodes": ["--nodes", "2"],
    "transfer function, 1st order": ["--kind", "tf1"],
    "network, 2 nodes + observer (t1, t4)": ["--nodes", "2", "--observer"],
}


#: Issue 22's budget for the whole recording, wall seconds on this machine.
GOAL_S = 60.0


def run(source: Path) -> None:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        map_file = Path(folder) / "map.toml"
        map_file.write_text(MAP, encoding="utf-8")
        for label, flags in RUNS.items():
            wall, cpu = time.perf_counter(), time.process_time()
            status = main(["identify", str(source), "--map", str(map_file),
                           "-o", str(Path(folder) / "model.json"), *flags])
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            assert status == 0
            print(f"BENCH {label}: {wall:.1f} s wall, {cpu:.1f} s CPU "
                  f"(load average {os.getloadavg()[0]:.1f})", flush=True)
            rows.append({"form": label, "flags": " ".join(flags) or "(defaults)",
                         "wall_s": wall, "cpu_s": cpu, "met": wall <= GOAL_S})
    print(f"wrote {record('bench_identification', rows, {'wall_s': GOAL_S})}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", default=str(caiviac.default_source()))
    run(Path(parser.parse_args().source))
