"""Calibration on the real CAIVIAC recording, validated on cycles it never saw.

    python -m spindlebench.calibration.validation RUNS_DIR [--out docs/figures]

``RUNS_DIR`` is the output of ``spindlebench adapt caiviac --phase cycle --out RUNS_DIR``: six
contiguous runs (five 4 h-on / 4 h-off cycles at 1250, 2500, 3750, 5000, 3500 rpm and a stepped
block). The fold: calibrate on the first three cycles, predict the other three.

- **Prediction from the speed programme alone**: the calibrated model runs once through all six
  runs from the state it estimated at the start of the first, with the mean estimated ambient as
  a constant (the recording has no ambient channel); the predicted error of a held-out run is
  the model's drift change since that run's start. No temperature is read at prediction time.
- **MLR on sensors**, same fold: ordinary least squares of the error on all 16 temperature rises
  (each run relative to its first sample), fitted on the three training cycles and applied to
  the held-out runs with their measured temperatures.
- **The sensor map**: the recording does not say where its sensors are. Each sensor is mapped
  to the model output (a model sensor T1…T20 or any field node) whose rise over the training
  cycles, simulated with the default machine, correlates best with the sensor's rise. How much
  the choice matters is measured by calibrating again with every sensor on its second-best
  output, and once on the error alone (no temperature channel).

Prints a markdown table (for docs/validation.md) and draws ``calibration_caiviac.png``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from sklearn.linear_model import LinearRegression

from spindlebench.adapters import caiviac
from spindlebench.calibration.fitset import DEFAULT_FIT
from spindlebench.calibration.mapping import RecordingMap
from spindlebench.calibration.problem import Discretisation, Fit, calibrate, trajectory
from spindlebench.calibration.series import Series, load_series
from spindlebench.core import atomic
from spindlebench.core.paths import MODELS_DIR
from spindlebench.formats.recording import (
    AMBIENT_COLUMN,
    DRIFT_COLUMN,
    FEED_X_COLUMN,
    FEED_Y_COLUMN,
    SPEED_COLUMN,
    TIME_COLUMN,
    read_recording,
)
from spindlebench.model.equations import explicit_ode

TRAIN = ("run1_1250rpm", "run2_2500rpm", "run3_3750rpm")
TEST = ("run4_5000rpm", "run5_3500rpm", "run6_stepped")
#: The CAIVIAC recording's sensors and axial error column, as its adapter names them.
TEMPERATURES = caiviac.TEMPERATURES
ERROR = caiviac.AXIAL_TARGET
#: ch3 falls while the spindle heats up; the model's drift_um is positive toward the table.
ERROR_SIGN = -1.0
#: 2 min steps and 4 segments per part: three calibrations of 24 h of data in minutes; the
#: recording's sensors are at unknown places, so a finer model resolves nothing more.
STEP_S = 120.0
SEGMENTS = 4
MAX_EVALUATIONS = 30
#: No feed axis moves in this recording: the feed losses cannot be fitted.
FIT = [name for name in DEFAULT_FIT if name not in ("c_x_motor", "c_y_motor")]


def _map(temperatures: dict[str, str], runs_dir: Path) -> RecordingMap:
    return RecordingMap(
        path=runs_dir / "(generated map)",
        inputs={SPEED_COLUMN: SPEED_COLUMN, FEED_X_COLUMN: 0.0,
                FEED_Y_COLUMN: 0.0, AMBIENT_COLUMN: "unknown"},
        ambient_knot_h=4.0, error_column=ERROR, error_sign=ERROR_SIGN,
        temperatures=temperatures,
    )


def map_text(temperatures: dict[str, str]) -> str:
    """The MAP.toml of a sensor map (what a user would write)."""
    lines = ["[inputs]", 'spindle_speed_rpm = "spindle_speed_rpm"', "feed_x_mm_per_min = 0.0",
             "feed_y_mm_per_min = 0.0", 'ambient_C = "unknown"', "", "[ambient]", "knot_h = 4.0",
             "", "[error]", f'column = "{ERROR}"', f"sign = {int(ERROR_SIGN)}", "",
             "[temperatures]"]
    lines += [f'{c} = "{o.removesuffix("_C")}"' for c, o in temperatures.items()]
    return "\n".join(lines) + "\n"


def _joined(series_list: list[Series]) -> Series:
    """Contiguous runs as one series (times shifted so they follow each other)."""
    times, offset = [], 0.0
    for series in series_list:
        times.append(series.time_s + offset)
        offset = times[-1][-1] + STEP_S
    first = series_list[0]
    channels = tuple(replace(c, values=np.concatenate([s.channels[i].values for s in series_list]))
                     for i, c in enumerate(first.channels))
    return replace(first, name="joined", time_s=np.concatenate(times),
                   inputs=np.concatenate([s.inputs for s in series_list], axis=1),
                   channels=channels)


def choose_map(d: Discretisation, runs: list[Series], rank: int) -> dict[str, str]:
    """Each sensor -> the model output whose simulated rise correlates best (rank 0) or
    second best (rank 1) with its measured rise over the training runs."""
    joined = _joined(runs)
    ambient = joined.ambient_guess()
    joined = replace(joined, ambient_unknown=False,
                     inputs=np.vstack([joined.inputs[:3], np.full(len(joined.time_s), ambient)]))
    z0 = np.full(d.n_x, ambient)
    states, _ = trajectory(d, joined, z0, np.zeros(len(d.fit)), np.zeros(0), sensitivities=False)
    Y = np.asarray(d.outputs.map(joined.intervals + 1)(states, joined.inputs, np.zeros(len(d.fit))))
    candidates = [n for n in d.ode.outputs if n.endswith("_C")]
    model = np.array([Y[d.output_index[n]] for n in candidates])
    model = model - model[:, :1]
    chosen = {}
    for channel in joined.channels:
        if channel.kind != "temperature":
            continue
        measured = channel.values - channel.values[0]
        scores = [np.corrcoef(measured, m)[0, 1] if np.std(m) > 1e-9 else -1.0 for m in model]
        chosen[channel.column] = candidates[int(np.argsort(scores)[::-1][rank])]
    return chosen


def _load(runs_dir: Path, names: tuple[str, ...], recording_map: RecordingMap) -> list[Series]:
    return [load_series(runs_dir / f"{n}.csv", recording_map, STEP_S) for n in names]


def predict_error(d: Discretisation, fit: Fit, runs: list[Series]) -> list[np.ndarray]:
    """Predicted error of each run from the speed programme alone (see the module docstring)."""
    joined = _joined(runs)
    ambient = float(np.mean(np.concatenate([t[AMBIENT_COLUMN] for t in fit.trajectories])))
    joined = replace(joined, ambient_unknown=False,
                     inputs=np.vstack([joined.inputs[:3], np.full(len(joined.time_s), ambient)]))
    states, _ = trajectory(d, joined, fit.initial_states[0], fit.log_factors, np.zeros(0),
                           sensitivities=False)
    Y = np.asarray(d.outputs.map(joined.intervals + 1)(states, joined.inputs, fit.log_factors))
    drift = Y[d.output_index[DRIFT_COLUMN]]
    predictions, start = [], 0
    for series in runs:
        piece = drift[start:start + len(series.time_s)]
        predictions.append(piece - piece[0])
        start += len(series.time_s)
    return predictions


def mlr_predictions(runs_dir: Path) -> list[np.ndarray]:
    """OLS of the (signed) error on the 16 temperature rises, trained on TRAIN."""
    def rises(name: str) -> tuple[np.ndarray, np.ndarray]:
        frame = read_recording(runs_dir / f"{name}.csv").iloc[:: int(STEP_S / 15.0)]
        X = frame[list(TEMPERATURES)].to_numpy()
        y = ERROR_SIGN * frame[ERROR].to_numpy()
        return X - X[0], y - y[0]

    train = [rises(n) for n in TRAIN]
    model = LinearRegression().fit(np.vstack([x for x, _ in train]),
                                   np.concatenate([y for _, y in train]))
    return [model.predict(rises(n)[0]) for n in TEST]


def _rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)))


def run(runs_dir: Path, out: Path) -> None:
    started = time.perf_counter()
    ode = explicit_ode(MODELS_DIR, segments=SEGMENTS)
    d = Discretisation(ode, FIT, ode.parameter_vector())
    error_only = _map({}, runs_dir)
    probe = _load(runs_dir, TRAIN, _map({c: "T1_C" for c in TEMPERATURES}, runs_dir))
    maps = {"best-correlated": choose_map(d, probe, 0),
            "second-best": choose_map(d, probe, 1), "error only": {}}
    print("sensor map (best-correlated):\n" + map_text(maps["best-correlated"]))
    measured = [load_series(runs_dir / f"{n}.csv", error_only, STEP_S).channels[0].values
                for n in TEST]
    measured = [m - m[0] for m in measured]
    rows, fits = [], {}
    for label, temperatures in maps.items():
        recording_map = _map(temperatures, runs_dir)
        train = _load(runs_dir, TRAIN, recording_map)
        fit = calibrate(d, train, max_iter=MAX_EVALUATIONS)
        fits[label] = fit
        predicted = predict_error(d, fit, _load(runs_dir, TRAIN + TEST, error_only))[len(TRAIN):]
        temperature_rmse = [r["rmse"] for r in fit.channel_rmse if r["kind"] == "temperature"]
        fit_error = [r["rmse"] for r in fit.channel_rmse if r["kind"] == "error"]
        rows.append((f"calibrated model, {label} map",
                     [_rmse(p, m) for p, m in zip(predicted, measured, strict=True)],
                     f"{fit.evaluations} evaluations, {fit.seconds:.0f} s; training fit: "
                     f"error {np.mean(fit_error):.2f} um, temperatures "
                     + (f"{np.mean(temperature_rmse):.2f} K" if temperature_rmse else "-")))
        if label == "best-correlated":
            best_predicted = predicted
    mlr = mlr_predictions(runs_dir)
    rows.append(("MLR on all 16 sensors (measured at prediction time)",
                 [_rmse(p, m) for p, m in zip(mlr, measured, strict=True)], ""))
    ranges = [float(np.ptp(m)) for m in measured]
    print(f"| method | {' | '.join(TEST)} | notes |")
    print("|---|" + "---|" * len(TEST) + "---|")
    print(f"| error range (max - min) | {' | '.join(f'{r:.1f}' for r in ranges)} | |")
    for label, values, note in rows:
        print(f"| {label} | {' | '.join(f'{v:.1f}' for v in values)} | {note} |")
    best = fits["best-correlated"]
    print("\nestimates (best-correlated map):")
    for name, (lo, hi) in best.interval95().items():
        print(f"  {name}: {best.start_values[name]:.4g} -> {best.values[name]:.4g} "
              f"[{lo:.4g}, {hi:.4g}]")
    strong = [(best.fit[i], best.fit[j], best.correlation[i, j]) for i in range(len(best.fit))
              for j in range(i) if abs(best.correlation[i, j]) >= 0.8]
    print("correlated (|r| >= 0.8): " + (", ".join(f"{a}~{b} {r:+.2f}" for a, b, r in strong)
                                         or "none"))
    figure = out / "calibration_caiviac.png"
    _figure(best, best_predicted, mlr, measured, figure)
    print(f"\n{time.perf_counter() - started:.0f} s in all; figure {figure}")


def _figure(fit: Fit, predicted, mlr, measured, path: Path) -> None:
    fig = Figure(figsize=(13, 6.5))
    axes = fig.subplots(2, 3)
    for k, curves in enumerate(fit.trajectories):
        ax = axes[0, k]
        hours = curves[TIME_COLUMN] / 3600
        for i, channel in enumerate(c for c in curves["channels"] if c["kind"] == "temperature"):
            if i % 4:
                continue  # every fourth sensor keeps the panel readable
            ax.plot(hours, channel["measured"], ".", ms=1, color=f"C{i // 4}")
            ax.plot(hours, channel["model"], "-", lw=1, color=f"C{i // 4}",
                    label=f"{channel['column']} → {channel['output'].removesuffix('_C')}")
        error = next(c for c in curves["channels"] if c["kind"] == "error")
        twin = ax.twinx()
        twin.plot(hours, error["measured"], ".", ms=1, color="k")
        twin.plot(hours, error["model"], "-", color="C3", lw=1.2)
        twin.set_ylabel("-ch3 (µm)")
        ax.set_title(f"training {TRAIN[k]}", fontsize=9)
        ax.set_ylabel("°C")
        ax.legend(fontsize=6, loc="lower right")
    for k, name in enumerate(TEST):
        ax = axes[1, k]
        hours = np.arange(len(measured[k])) * STEP_S / 3600
        ax.plot(hours, measured[k], ".", ms=1.5, color="k", label="measured -ch3")
        ax.plot(hours, predicted[k], "-", color="C3", label="calibrated model (speed only)")
        ax.plot(hours, mlr[k], "-", color="C0", lw=0.8, label="MLR on 16 sensors")
        ax.set_title(f"held out {name}", fontsize=9)
        ax.set_xlabel("time (h)")
        ax.set_ylabel("error (µm)")
        ax.legend(fontsize=6)
    fig.suptitle("CAIVIAC: calibrated on three cycles (top, dots measured, lines model), "
                 "predicting the others (bottom)", fontsize=10)
    fig.tight_layout()
    with atomic.atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", type=Path, help="output folder of 'adapt caiviac --phase cycle'")
    parser.add_argument("--out", type=Path, default=Path("docs/figures"))
    args = parser.parse_args()
    run(args.runs, args.out)
