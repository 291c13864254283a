"""Benchmark: ``spindlebench calibrate`` on a real recording, the issue-22 goal "a 39 h
recording at 60 s calibrates in <= 2 min".

The issue's 39 h motorized-spindle recording is not in ``../shared/recordings``; CAIVIAC's
46 h at 15 s is. Its first ``--hours`` (default 39, and the whole file) are cut into a
temporary CSV and calibrated as a user would (``docs/twin.md``, "calibrate on the 46 h
recording"): ``--step-s 60``, the default fit set (15 parameters), 11 of the 16 sensors mapped
to sensor places guessed by name, the room unknown (a knot every 4 h), ``ch3_um`` with sign
-1. The whole command runs in this process (model translation, reading, fit, report and
figure), and its CPU seconds (user + system of this process: the fit is single-threaded) are
what the goal is measured in: the wall time on the shared 2-core machine mostly says how
many other jobs ran.

    .venv/bin/python bench/bench_calibration_caiviac.py [--hours 39 46.3]

The rows are written to ``bench/results/bench_calibration_caiviac.json`` (``bench/results.py``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import resource
import tempfile
import time
from pathlib import Path

import numpy as np
from spindlebench.adapters.caiviac import default_source
from spindlebench.commands.main import main

from results import record

MAP = """[inputs]
spindle_speed_rpm = "spindle_rpm"
feed_x_mm_per_min = 0.0
feed_y_mm_per_min = 0.0
ambient_C = "unknown"

[ambient]
knot_h = 4.0

[error]
column = "ch3_um"
sign = -1

[temperatures]
""" + "".join(f't{i}_C = "T{i}"\n' for i in range(1, 10)) + 't12_C = "T11"\nt13_C = "T12"\n'
#: The issue's goal: at most 2 minutes for a 39 h recording at 60 s.
GOAL_CPU_S = 120.0


def _cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def cut(source: Path, hours: float, path: Path) -> int:
    """The first ``hours`` of ``source`` (the header and every row up to that time) as
    ``path``; returns the number of data rows."""
    lines = source.read_text(encoding="utf-8").splitlines(keepends=True)
    header, rows = lines[0], lines[1:]
    times = np.array([float(r.split(",", 1)[0]) for r in rows])
    kept = [r for r, t in zip(rows, times, strict=True) if t <= hours * 3600 + 1e-9]
    path.write_text(header + "".join(kept), encoding="utf-8")
    return len(kept)


def run(hours_list: list[float]) -> None:
    source = default_source()
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        (folder / "map.toml").write_text(MAP, encoding="utf-8")
        for hours in hours_list:
            recording = folder / f"caiviac_{hours:g}h.csv"
            n = cut(source, hours, recording)
            out = folder / f"caiviac_{hours:g}h.toml"
            cpu, wall = _cpu_s(), time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):
                code = main(["calibrate", str(recording), "--map", str(folder / "map.toml"),
                             "-o", str(out), "--step-s", "60", "-q"])
            cpu, wall = _cpu_s() - cpu, time.perf_counter() - wall
            if code != 0:
                raise SystemExit(f"calibrate on {hours:g} h failed ({code})")
            report = json.loads(out.with_suffix(".calibration.json").read_text("utf-8"))
            evaluations = report.get("evaluations")
            row = {"fit": f"CAIVIAC first {hours:g} h at 60 s", "hours": hours,
                   "source_rows": n, "parameters": len(report.get("parameters", {})) or None,
                   "cpu_s": cpu, "wall_s": wall, "evaluations": evaluations,
                   "evaluation_limit": report.get("evaluation_limit"),
                   "stop_reason": report.get("stop_reason"),
                   "chi2_reduced": report.get("chi2_reduced")}
            rows.append(row)
            print(f"{row['fit']}: {cpu:.1f} CPU-s, {wall:.0f} s wall (load average "
                  f"{os.getloadavg()[0]:.1f}), {evaluations} evaluations, "
                  f"{row['stop_reason']}; goal <= {GOAL_CPU_S:g} s for 39 h")
    print(f"wrote {record('bench_calibration_caiviac', rows, {'cpu_s_39h': GOAL_CPU_S})}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[39.0, 46.3])
    args = parser.parse_args()
    run(args.hours)
