"""Regenerate the "Use your own recording" example: two runs as another logger writes them.

    .venv/bin/python docs/examples/other-logger/make_example.py

Simulates two 3-hour runs of the testbench (``run1.toml``: 4000 rpm, ``run2.toml``: 2000 rpm)
and rewrites each recording the way a foreign data logger might: semicolon-separated with a
decimal comma, a ``Time [s]`` column, descriptive temperature names with ``[degC]``, the
spindle speed, and two displacement channels (``dz [um]`` the axial drift, ``dx [um]`` a
second channel that is nearly a scaled copy of it). Synthetic data only: no real recording is
copied into the repository.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from spindlebench.testbench.simulate import simulate_scenario

HERE = Path(__file__).resolve().parent
#: Testbench column -> the other logger's name.
NAMES = {
    "time_s": "Time [s]",
    "spindle_speed_rpm": "Spindle speed [rpm]",
    "T1": "Spindle front [degC]",
    "T2": "Seat flange [degC]",
    "T6": "Headstock side [degC]",
    "T8": "Spindle motor [degC]",
    "T10": "Workshop air [degC]",
    "T13": "X motor [degC]",
    "T16": "Y motor [degC]",
    "drift_um": "dz [um]",
}


def convert(recording: Path, out: Path, seed: int) -> None:
    import pandas as pd

    frame = pd.read_csv(recording)
    other = frame[list(NAMES)].rename(columns=NAMES)
    rng = np.random.default_rng(seed)
    other["dx [um]"] = 0.4 * frame["drift_um"] + rng.normal(scale=0.01, size=len(frame))
    other.round(4).to_csv(out, sep=";", decimal=",", index=False, lineterminator="\n")


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        for seed, name in enumerate(("run1", "run2"), start=1):
            csv = simulate_scenario(HERE / f"{name}.toml", Path(tmp) / f"{name}.csv")
            convert(csv, HERE / f"{name}.csv", seed)
            print(f"wrote {HERE / f'{name}.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
