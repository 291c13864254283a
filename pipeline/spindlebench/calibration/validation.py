"""Calibration on the real CAIVIAC recording, validated on cycles it never saw.

    python -m spindlebench.calibration.validation RUNS_DIR [--out docs/figures] [--json FILE]

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

- **The fit-set variants** (``identifiability.VARIANTS``): the same fold with fewer effective
  parameters, and the same protocol one level down (train on run1 and run2, predict run3) as
  the choice a user could make without the held-out runs.

Writes everything to ``results/caiviac_calibration/caiviac_calibration.json`` (``--json``),
from which ``docs/validation.md``'s tables are generated (``heldout_table``,
``variants_table``, ``runs_table``, through ``docs/hooks/tables.py``); prints the same tables
and draws ``calibration_caiviac.png``.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from sklearn.linear_model import LinearRegression

from spindlebench.adapters import caiviac
from spindlebench.calibration import identifiability
from spindlebench.calibration.fitset import DEFAULT_FIT
from spindlebench.calibration.mapping import RecordingMap
from spindlebench.calibration.problem import Discretisation, Fit, calibrate, trajectory
from spindlebench.calibration.series import Series, load_series
from spindlebench.core import atomic
from spindlebench.core.paths import MODELS_DIR
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import (
    AMBIENT_COLUMN,
    DRIFT_COLUMN,
    FEED_X_COLUMN,
    FEED_Y_COLUMN,
    SPEED_COLUMN,
    TIME_COLUMN,
    read_recording,
)
from spindlebench.model import MODEL_FILE
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
#: Where the results go (the docs' tables read it, or its copy under docs/snapshots/).
DEFAULT_JSON = "results/caiviac_calibration/caiviac_calibration.json"
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


def _measured_error(runs_dir: Path, names: tuple[str, ...]) -> list[np.ndarray]:
    """The (signed) error of each run on the calibration grid, relative to its first sample."""
    measured = [load_series(runs_dir / f"{n}.csv", _map({}, runs_dir), STEP_S).channels[0].values
                for n in names]
    return [m - m[0] for m in measured]


def variant_fold(d: Discretisation, runs_dir: Path, train: tuple[str, ...],
                 test: tuple[str, ...], first: Fit | None = None) -> dict:
    """Every fit-set variant (``identifiability.VARIANTS``) calibrated on ``train`` with the
    best-correlated map chosen on ``train``, and its held-out RMSE (µm) on each of ``test``
    predicted from the speed programme alone (as ``run``'s table)."""
    probe = _load(runs_dir, train, _map({c: "T1_C" for c in TEMPERATURES}, runs_dir))
    recording_map = _map(choose_map(d, probe, 0), runs_dir)
    series = _load(runs_dir, train, recording_map)
    every = _load(runs_dir, train + test, _map({}, runs_dir))
    measured = _measured_error(runs_dir, test)

    def score(result: identifiability.VariantFit) -> list[float]:
        predicted = predict_error(result.discretisation, result.fit, every)[len(train):]
        return [_rmse(p, m) for p, m in zip(predicted, measured, strict=True)]

    results = identifiability.evaluate_variants(d, series, MAX_EVALUATIONS, score,
                                                first=first)
    rows = {}
    for variant, (result, rmse) in results.items():
        fit = result.fit
        rows[variant] = {
            "heldout_rmse_um": dict(zip(test, rmse, strict=True)),
            "mean_heldout_rmse_um": float(np.mean(rmse)),
            "training_error_rmse_um": float(np.mean(
                [r["rmse"] for r in fit.channel_rmse if r["kind"] == "error"])),
            "fitted": list(fit.fit), "fixed": list(result.fixed),
            "at_bound": identifiability.at_bound(result.discretisation, fit),
            "estimates": result.discretisation.parameters(fit.log_factors),
            "strongest_correlation": _strongest(fit),
            "evaluations": result.evaluations, "fit_s": result.seconds,
            "chi2_reduced": fit.chi2_reduced,
        }
    return {"train": list(train), "test": list(test), "variants": rows}


def _strongest(fit: Fit) -> dict:
    """The most correlated pair of estimates."""
    n = len(fit.fit)
    if n < 2:
        return {}
    i, j = max(((i, j) for i in range(n) for j in range(i)),
               key=lambda ij: abs(fit.correlation[ij]))
    return {"pair": [fit.fit[i], fit.fit[j]], "r": float(fit.correlation[i, j])}


def run(runs_dir: Path, out: Path, json_path: Path) -> dict:
    """The validation: the calibration table, the fit-set variants on the same fold and one
    level down (``identifiability.nested_choice``), the runs as the adapter cut them; written
    to ``json_path`` (what the docs' tables are generated from) and printed as Markdown."""
    started = time.perf_counter()
    cpu_started = time.process_time()
    ode = explicit_ode(MODELS_DIR, segments=SEGMENTS)
    d = Discretisation(ode, FIT, ode.parameter_vector())
    error_only = _map({}, runs_dir)
    probe = _load(runs_dir, TRAIN, _map({c: "T1_C" for c in TEMPERATURES}, runs_dir))
    maps = {"best-correlated": choose_map(d, probe, 0),
            "second-best": choose_map(d, probe, 1), "error only": {}}
    print("sensor map (best-correlated):\n" + map_text(maps["best-correlated"]))
    measured = _measured_error(runs_dir, TEST)
    rows, fits = [], {}
    for label, temperatures in maps.items():
        recording_map = _map(temperatures, runs_dir)
        train = _load(runs_dir, TRAIN, recording_map)
        fit = calibrate(d, train, max_iter=MAX_EVALUATIONS)
        fits[label] = fit
        predicted = predict_error(d, fit, _load(runs_dir, TRAIN + TEST, error_only))[len(TRAIN):]
        temperature_rmse = [r["rmse"] for r in fit.channel_rmse if r["kind"] == "temperature"]
        fit_error = [r["rmse"] for r in fit.channel_rmse if r["kind"] == "error"]
        rows.append({"method": _calibrated_label(label), "map": label,
                     "heldout_rmse_um": [_rmse(p, m) for p, m in zip(predicted, measured,
                                                                     strict=True)],
                     "evaluations": fit.evaluations, "evaluation_limit": MAX_EVALUATIONS,
                     "fit_s": fit.seconds,
                     "training_error_rmse_um": float(np.mean(fit_error)),
                     "training_temperature_rmse_K": (float(np.mean(temperature_rmse))
                                                     if temperature_rmse else None)})
        if label == "best-correlated":
            best_predicted = predicted
    mlr = mlr_predictions(runs_dir)
    rows.append({"method": "MLR on all 16 sensors (measured at prediction time)", "map": None,
                 "heldout_rmse_um": [_rmse(p, m) for p, m in zip(mlr, measured, strict=True)]})
    best = fits["best-correlated"]
    outer = variant_fold(d, runs_dir, TRAIN, TEST, first=best)
    inner = variant_fold(d, runs_dir, TRAIN[:-1], TRAIN[-1:])
    inner_scores = {v: r["mean_heldout_rmse_um"] for v, r in inner["variants"].items()}
    document = {
        "provenance": provenance(
            kind="spindlebench CAIVIAC calibration validation",
            script="python -m spindlebench.calibration.validation",
            source=file_entry(caiviac.default_source()),
            runs={n: file_entry(runs_dir / f"{n}.csv") for n in TRAIN + TEST},
            model=file_entry(MODELS_DIR / MODEL_FILE), segments=SEGMENTS, step_s=STEP_S,
            fit=FIT, evaluation_limit=MAX_EVALUATIONS),
        "train": list(TRAIN), "test": list(TEST),
        "runs": caiviac.run_summary(),
        "error_range_um": [float(np.ptp(m)) for m in measured],
        "maps": {label: dict(m) for label, m in maps.items()},
        "rows": rows,
        "estimates": {name: {"start": best.start_values[name], "estimate": best.values[name],
                             "interval95": list(interval)}
                      for name, interval in best.interval95().items()},
        "correlated": [{"pair": [best.fit[i], best.fit[j]], "r": float(best.correlation[i, j])}
                       for i in range(len(best.fit)) for j in range(i)
                       if abs(best.correlation[i, j]) >= 0.8],
        "variants": {"outer": outer, "inner": inner,
                     "nested_choice": identifiability.nested_choice(inner_scores)},
    }
    print(heldout_table(document))
    print()
    print(variants_table(document))
    print(f"\nnested choice (inner fold {', '.join(inner['train'])} -> "
          f"{', '.join(inner['test'])}): {document['variants']['nested_choice']}")
    print("\nestimates (best-correlated map):")
    for name, row in document["estimates"].items():
        lo, hi = row["interval95"]
        print(f"  {name}: {row['start']:.4g} -> {row['estimate']:.4g} [{lo:.4g}, {hi:.4g}]")
    print("correlated (|r| >= 0.8): " + (", ".join(
        f"{c['pair'][0]}~{c['pair'][1]} {c['r']:+.2f}" for c in document["correlated"])
        or "none"))
    figure = out / "calibration_caiviac.png"
    _figure(best, best_predicted, mlr, measured, figure)
    json_path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(json_path, json.dumps(document, indent=1, sort_keys=True) + "\n")
    print(f"\n{time.perf_counter() - started:.0f} s wall, {time.process_time() - cpu_started:.0f}"
          f" CPU-s in all; figure {figure}, results {json_path}")
    return document


def _calibrated_label(map_label: str) -> str:
    """The table's name of a calibration with the sensor map ``map_label``."""
    if map_label == "error only":
        return "calibrated model, error only (no temperature channel)"
    return f"calibrated model, {map_label} map (speed programme only)"


def _cells(values: list[float]) -> str:
    return " | ".join(f"{v:.1f}" for v in values)


def heldout_table(document: dict) -> str:
    """The calibration table: held-out RMSE (µm) of each calibration and of MLR."""
    test = document["test"]
    lines = [f"| method | {' | '.join(test)} | notes |", "|---|" + "---|" * len(test) + "---|",
             f"| error range (max − min) | {_cells(document['error_range_um'])} | |"]
    for row in document["rows"]:
        note, method = "", row["method"]
        if row.get("map") is not None:
            method = _calibrated_label(row["map"])
            temperatures = row["training_temperature_rmse_K"]
            note = (f"{row['evaluations']} of at most {row['evaluation_limit']} evaluations; "
                    f"training fit: error {row['training_error_rmse_um']:.1f} µm, temperatures "
                    + (f"{temperatures:.1f} K" if temperatures is not None else "–"))
        lines.append(f"| {method} | {_cells(row['heldout_rmse_um'])} | {note} |")
    return "\n".join(lines)


VARIANT_LABELS = {
    "full": "default set (13 fitted)",
    "no-capacities": "without the heat capacities (10)",
    "tied-capacities": "default set, the three capacities by one common factor",
    "regularised": "default set, refitted with the noise at the misfit",
    "pruned": "default set, then those at a bound left at their start value",
}


def variants_table(document: dict) -> str:
    """The fit-set variants: held-out RMSE (µm) on the protocol's fold and on the inner fold
    (training runs only), the training error, and what sits at a bound."""
    outer, inner = document["variants"]["outer"], document["variants"]["inner"]
    test = outer["test"]
    inner_name = ", ".join(inner["test"])
    lines = [f"| fit set | fitted | {' | '.join(test)} | mean | training error (µm) | at a bound "
             f"| inner fold: {inner_name} |", "|---|---|" + "---|" * len(test) + "---|---|---|---|"]
    for variant in (v for v in identifiability.VARIANTS if v in outer["variants"]):
        row, inner_row = outer["variants"][variant], inner["variants"][variant]
        rmse = [row["heldout_rmse_um"][n] for n in test]
        lines.append(f"| {VARIANT_LABELS[variant]} | {len(row['fitted'])} | {_cells(rmse)} | "
                     f"{row['mean_heldout_rmse_um']:.1f} | {row['training_error_rmse_um']:.1f} | "
                     f"{len(row['at_bound'])} | {inner_row['mean_heldout_rmse_um']:.1f} |")
    return "\n".join(lines)


def runs_table(document: dict) -> str:
    """The runs as the adapter cuts the source (0-based source rows; ch3 re-zeroed, µm)."""
    lines = ["| run | rpm | heating rows (n) | cycle rows (n) | ch3_um in heating (µm) | ch3_um at "
             "end of heating | at end of cycle |", "|---|---|---|---|---|---|---|"]
    for row in document["runs"]:
        (h0, h1), (c0, c1) = row["heating_rows"], row["cycle_rows"]
        rpm = " → ".join(f"{v:g}" for v in row["speeds_rpm"])
        lines.append(f"| {row['run']} | {rpm} | {h0}–{h1} ({h1 - h0 + 1}) | {c0}–{c1} "
                     f"({c1 - c0 + 1}) | {row['heating_min_um']:.1f} … "
                     f"{row['heating_max_um']:.1f} | {row['end_of_heating_um']:.1f} | "
                     f"{row['end_of_cycle_um']:.1f} |")
    return "\n".join(lines)


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
    parser.add_argument("--out", type=Path, default=Path("docs/figures"),
                        help="folder of the figure")
    parser.add_argument("--json", type=Path, default=Path(DEFAULT_JSON),
                        help=f"the results (default {DEFAULT_JSON}: the docs' tables)")
    args = parser.parse_args()
    run(args.runs, args.out, args.json)
