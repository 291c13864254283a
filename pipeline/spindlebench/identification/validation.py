"""Identified models on the real CAIVIAC recording, scored on cycles they never saw.

    python -m spindlebench.identification.validation [--source data.csv] [--out DIR]

The recording (``../shared/recordings/caiviac-fl-thermal/data.csv``, read in place) is used
as one continuous file: the runs are cut at every switch-on of the spindle as the adapter cuts
them (``adapters.caiviac.find_schedule``; a run is its heating and its cool-down). A split
trains on some runs and predicts the others; every model is simulated (or filtered) through
the whole file, so the state each run starts from is what the model carried over, and a
held-out run's score is the RMSE of the change of ``ch3_um`` since the run's first sample
(the protocol of docs/validation.md, "Calibrating the model to the CAIVIAC machine").

Models: MLR (OLS on the rises of all 16 sensors, each run relative to its first sample, the
project's ``ols``), MLR on the observer's four sensors, the transfer-function baselines and
the grey-box network from the speed alone (order by leave-one-cycle-out), and the observer on
the four sensors most correlated with the error over the training runs (the rule of
``top-k-correlated``) and on all 16. Prints markdown tables and writes ``caiviac.json``.

The other modes, each printing its tables and writing one JSON under ``--out`` that the docs'
tables are generated from (``docs/hooks/tables.py``, ``twin KEY``): ``--evidence``
(``evidence.json``: the error against speed and sensors, per run), ``--room-proxy``
(``room_proxy.json``), ``--every-split [--observer]`` (``every_split.json``: all 20 ways to
train on three runs), ``--evaluate DIR`` (``evaluate.json``: ``spindlebench evaluate
--regressor`` on the adapter's cycles) and ``--synthetic DIR`` (``synthetic.json``: twin
recovery on the testbench's own machine, with the superposition check).
"""

from __future__ import annotations

import argparse
import itertools
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from spindlebench.adapters import caiviac
from spindlebench.core import atomic
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import (
    AMBIENT_COLUMN,
    DRIFT_COLUMN,
    FEED_X_COLUMN,
    FEED_Y_COLUMN,
    HEAT_FLOW_PREFIX,
    SPEED_COLUMN,
    TIME_COLUMN,
    TRUE_DRIFT_COLUMN,
    true_column,
)
from spindlebench.identification.estimators import (
    ObserverRegressor,
    ThermalNetworkRegressor,
    TransferFunctionRegressor,
)
from spindlebench.identification.model import rezeroed_rmse

#: Splits: name -> training runs (1-based); the other runs are predicted.
SPLITS = {"A: 1-3 -> 4-6": (1, 2, 3), "B: 4-6 -> 1-3": (4, 5, 6),
          "C: 1,3,5 -> 2,4,6": (1, 3, 5), "D: 2,4,6 -> 1,3,5": (2, 4, 6)}
OBSERVER_SENSORS = 4
TARGET = caiviac.AXIAL_TARGET


def _rises(values: np.ndarray, runs) -> np.ndarray:
    out = np.full_like(values, np.nan)
    for run in runs:
        rows = slice(run.start, run.stop)
        out[rows] = values[rows] - values[run.start]
    return out


def _mlr(T: np.ndarray, y: np.ndarray, runs, train) -> np.ndarray:
    """OLS on the rises (each run from its first sample), fitted on the training runs."""
    R = _rises(T, runs)
    Y = _rises(y[:, None], runs)[:, 0]
    rows = np.concatenate([np.arange(r.start, r.stop) for r in train])
    A = np.column_stack([R[rows], np.ones(len(rows))])
    coef, *_ = np.linalg.lstsq(A, Y[rows], rcond=None)
    return np.column_stack([np.nan_to_num(R), np.ones(len(R))]) @ coef


def top_correlated(T: np.ndarray, y: np.ndarray, runs, train, k: int) -> list[int]:
    """The ``k`` sensors whose rises correlate most (|r|) with the error's, training runs."""
    rows = np.concatenate([np.arange(r.start, r.stop) for r in train])
    R = _rises(T, runs)[rows]
    Y = _rises(y[:, None], runs)[rows, 0]
    r = [abs(np.corrcoef(R[:, j], Y)[0, 1]) for j in range(T.shape[1])]
    return sorted(np.argsort(r)[::-1][:k].tolist())


def _split(frame, schedule, train_numbers):
    """One split's arrays: time, speed, error, the temperatures, the runs, the training and
    held-out runs, and the training rows' weight (1 on training runs, 0 elsewhere)."""
    t = frame[TIME_COLUMN].to_numpy(float)
    n = frame["spindle_rpm"].to_numpy(float)
    y = frame[TARGET].to_numpy(float)
    T = frame[list(caiviac.TEMPERATURES)].to_numpy(float)
    runs = schedule.runs
    train = [runs[i - 1] for i in train_numbers]
    tests = [r for r in runs if r not in train]
    weight = np.zeros(len(t))
    for run in train:
        weight[run.start:run.stop] = 1.0
    return t, n, y, T, runs, train, tests, weight


def run_split(frame, schedule, train_numbers) -> dict:
    """Every model on one split: per held-out run RMSE (um) and the fit times (s)."""
    t, n, y, T, runs, train, tests, weight = _split(frame, schedule, train_numbers)
    chosen = top_correlated(T, y, runs, train, OBSERVER_SENSORS)
    predictions, seconds, notes = {}, {}, {}
    predictions["zero"] = np.zeros(len(t))
    predictions["MLR, 16 sensors"] = _mlr(T, y, runs, train)
    predictions[f"MLR, {OBSERVER_SENSORS} sensors"] = _mlr(T[:, chosen], y, runs, train)
    speed = np.column_stack([t, n])
    models = {
        "transfer function, 1st order (speed)": (TransferFunctionRegressor(order=1), speed),
        "transfer function, 2nd order (speed)": (TransferFunctionRegressor(order=2), speed),
        "network, order by held-out cycles (speed)": (ThermalNetworkRegressor(), speed),
        f"observer, {OBSERVER_SENSORS} sensors": (ObserverRegressor(),
                                                  np.column_stack([t, n, T[:, chosen]])),
        "observer, 16 sensors": (ObserverRegressor(), np.column_stack([t, n, T])),
    }
    for name, (model, X) in models.items():
        start = time.process_time()
        model.fit(X, y, sample_weight=weight)
        predictions[name] = model.predict(X)
        seconds[name] = time.process_time() - start
        fitted = model.fit_
        notes[name] = {"tau_h": [round(x / 3600, 3) for x in fitted.taus_s],
                       "exponents": [round(x, 3) for x in fitted.exponents],
                       "status": fitted.status}
        if getattr(model, "order_scores_", None):
            notes[name]["order_scores"] = model.order_scores_
        if getattr(model, "choice_scores_", None):
            notes[name]["choice_scores"] = model.choice_scores_
            notes[name]["chosen"] = [model.n_nodes_, model.disturbances_]
    table = {name: {r.name: rezeroed_rmse(p[r.start:r.stop], y[r.start:r.stop]) for r in tests}
             for name, p in predictions.items()}
    return {"train": [r.name for r in train], "tests": [r.name for r in tests],
            "observer_sensors": [caiviac.TEMPERATURES[j] for j in chosen],
            "rmse_um": table, "cpu_s": seconds, "models": notes}


def room_proxy_split(frame, schedule, train_numbers) -> dict:
    """The speed-only network against the same network given a room proxy: the sensor that
    moves least over the training runs (the smallest range; chosen without the error) as the
    ambient column. How much of the gap to MLR an ambient channel would close."""
    t, n, y, T, runs, train, tests, weight = _split(frame, schedule, train_numbers)
    rows = weight > 0
    proxy = int(np.argmin(np.ptp(T[rows], axis=0)))
    predictions = {"MLR, 16 sensors": _mlr(T, y, runs, train)}
    speed = ThermalNetworkRegressor().fit(np.column_stack([t, n]), y, sample_weight=weight)
    predictions["network (speed)"] = speed.predict(np.column_stack([t, n]))
    X = np.column_stack([t, n, T[:, proxy]])
    room = ThermalNetworkRegressor(ambient=True).fit(X, y, sample_weight=weight)
    predictions["network (speed + room proxy)"] = room.predict(X)
    table = {name: {r.name: rezeroed_rmse(p[r.start:r.stop], y[r.start:r.stop]) for r in tests}
             for name, p in predictions.items()}
    return {"proxy": caiviac.TEMPERATURES[proxy], "rmse_um": table,
            "tests": [r.name for r in tests]}


#: The observer of ``every_split(observer=True)``: a fixed structure (the choice by
#: leave-one-cycle-out costs 1-3 CPU-min a split); 2 nodes and 2 disturbances is what it chose
#: on 16 sensors in three of the four splits A-D (``caiviac.json``).
EVERY_SPLIT_OBSERVER = {"n_nodes": 2, "disturbances": 2}


def every_split(frame, schedule, observer: bool = False) -> dict:
    """The goals on every way to train on three of the six runs (20 splits): MLR on the 16
    sensors against the network from the speed (order by leave-one-cycle-out), and with
    ``observer`` the observer on the 16 sensors (``EVERY_SPLIT_OBSERVER``); each split's
    mean held-out RMSE."""
    out = {}
    for train in itertools.combinations(range(1, len(schedule.runs) + 1), 3):
        t, n, y, T, runs, train_runs, tests, weight = _split(frame, schedule, train)
        speed = np.column_stack([t, n])
        network = ThermalNetworkRegressor().fit(speed, y, sample_weight=weight)
        predictions = {"MLR, 16 sensors": _mlr(T, y, runs, train_runs),
                       "network (speed)": network.predict(speed)}
        if observer:
            X = np.column_stack([t, n, T])
            model = ObserverRegressor(**EVERY_SPLIT_OBSERVER).fit(X, y, sample_weight=weight)
            predictions["observer, 16 sensors"] = model.predict(X)
        out[",".join(map(str, train))] = {
            name: _mean({r.name: rezeroed_rmse(p[r.start:r.stop], y[r.start:r.stop])
                         for r in tests}) for name, p in predictions.items()}
        print(f"split {train}: {out[','.join(map(str, train))]}", flush=True)
    return out


def every_split_markdown(result: dict) -> str:
    observer = all("observer, 16 sensors" in row for row in result.values())
    lines = ["| training runs | MLR, 16 sensors | network (speed) | ratio | within 1.5× |"
             + (" observer, 16 sensors | vs MLR | 20 % below |" if observer else ""),
             "|---|---|---|---|---|" + ("---|---|---|" if observer else "")]
    met = below = 0
    for train, row in result.items():
        mlr = row["MLR, 16 sensors"]
        ratio = row["network (speed)"] / mlr
        met += ratio <= 1.5
        line = (f"| {train} | {mlr:.1f} | {row['network (speed)']:.1f} "
                f"| {ratio:.2f}× | {'yes' if ratio <= 1.5 else 'no'} |")
        if observer:
            change = row["observer, 16 sensors"] / mlr - 1
            below += change <= -0.2
            line += (f" {row['observer, 16 sensors']:.1f} | {100 * change:+.0f} % | "
                     f"{'yes' if change <= -0.2 else 'no'} |")
        lines.append(line)
    lines.append(f"| all {len(result)} | | | | {met} of {len(result)} |"
                 + (f" | | {below} of {len(result)} |" if observer else ""))
    return "\n".join(lines)


def markdown(name: str, result: dict) -> str:
    tests = result["tests"]
    lines = [f"### Split {name} (train {', '.join(result['train'])}; observer sensors "
             f"{', '.join(result['observer_sensors'])})", "",
             "| model | " + " | ".join(tests) + " | **mean** |",
             "|---|" + "---|" * (len(tests) + 1)]
    for model, row in result["rmse_um"].items():
        values = [row[t] for t in tests]
        lines.append(f"| {model} | " + " | ".join(f"{v:.1f}" for v in values)
                     + f" | **{np.mean(values):.1f}** |")
    return "\n".join(lines)


#: Sensors that rise in some runs and fall in others (see ``room_evidence``).
SHARED_DRIFT_SENSORS = ("t1_C", "t2_C", "t3_C", "t12_C", "t13_C", "t14_C", "t15_C")


def room_evidence(frame, schedule) -> dict:
    """Per run: speed, start hour, the error's change over the heating, and the mean rise of
    ``SHARED_DRIFT_SENSORS`` over it; and how well speed or that rise explains the error
    across the six runs (|r| over runs). A speed-only model can only use the first."""
    y = frame[TARGET].to_numpy(float)
    runs = []
    for run in schedule.runs:
        a, h = run.start, run.heating_stop - 1
        runs.append({
            "run": run.name, "mean_rpm": float(np.mean(frame["spindle_rpm"].iloc[a:h + 1])),
            "start_h": float(frame[TIME_COLUMN].iloc[a] / 3600),
            "error_change_um": float(y[h] - y[a]),
            "shared_rise_K": float(np.mean([frame[c].iloc[h] - frame[c].iloc[a]
                                            for c in SHARED_DRIFT_SENSORS])),
            "t5_rise_K": float(frame["t5_C"].iloc[h] - frame["t5_C"].iloc[a])})
    change = [r["error_change_um"] for r in runs]
    return {"runs": runs,
            "r_speed": float(abs(np.corrcoef([r["mean_rpm"] for r in runs], change)[0, 1])),
            "r_shared_rise": float(abs(np.corrcoef([r["shared_rise_K"] for r in runs],
                                                   change)[0, 1]))}


def evidence_markdown(evidence: dict) -> str:
    rows = ["| run | rpm | starts at (h) | ch3 change over heating (um) | mean rise of t1-t3, "
            "t12-t15 (K) | t5 rise (K) |", "|---|---|---|---|---|---|"]
    rows += [f"| {r['run']} | {r['mean_rpm']:.0f} | {r['start_h']:.1f} | "
             f"{r['error_change_um']:+.1f} | {r['shared_rise_K']:+.2f} | {r['t5_rise_K']:+.1f} |"
             for r in evidence["runs"]]
    rows += ["", f"|r| across the six runs: error change vs mean speed {evidence['r_speed']:.2f}, "
             f"vs the mean rise of t1-t3, t12-t15 {evidence['r_shared_rise']:.2f}"]
    return "\n".join(rows)


def _mean(row: dict) -> float:
    return float(np.mean(list(row.values())))


def room_proxy_markdown(results: dict) -> str:
    """Mean held-out RMSE per split of ``room_proxy_split``'s results."""
    lines = ["| split | room proxy | MLR, 16 sensors | network (speed) | "
             "network (speed + room proxy) |", "|---|---|---|---|---|"]
    for name, result in results.items():
        lines.append(f"| {name} | {result['proxy']} | " + " | ".join(
            f"{_mean(row):.1f}" for row in result["rmse_um"].values()) + " |")
    return "\n".join(lines)


def summary_markdown(splits: dict) -> str:
    """The splits' means (um): MLR, the speed-only network, the observers, and the goals'
    ratios (speed network / MLR 16; observer 16 / MLR 16 - 1)."""
    lines = ["| split | MLR, 16 sensors | network from speed | ratio | observer, 4 sensors | "
             "observer, 16 sensors | observer 16 vs MLR 16 |", "|---|---|---|---|---|---|---|"]
    means = []
    for result in splits.values():
        m = {k: _mean(row) for k, row in result["rmse_um"].items()}
        means.append([m["MLR, 16 sensors"], m["network, order by held-out cycles (speed)"],
                      m[f"observer, {OBSERVER_SENSORS} sensors"], m["observer, 16 sensors"]])
    rows = [(name, *row) for name, row in zip(splits, means, strict=True)]
    if len(rows) > 1:
        rows.append((f"mean of the {len(rows)}", *np.mean(means, axis=0)))
    for name, mlr, net, obs4, obs16 in rows:
        lines.append(f"| {name} | {mlr:.1f} | {net:.1f} | {net / mlr:.2f}× | {obs4:.1f} | "
                     f"{obs16:.1f} | {100 * (obs16 / mlr - 1):+.0f} % |")
    return "\n".join(lines)


#: ``evaluate``'s protocol on the adapter's CAIVIAC cycles: training run -> rows of
#: (--method, --regressor, --clusters).
EVALUATE_ROWS = {
    "run4_5000rpm": [("all-candidates", "ols", 16), ("top-k-correlated", "ols", 4),
                     ("closure", "tf1", 4), ("closure", "tf2", 4), ("closure", "network", 4),
                     ("top-k-correlated", "observer", 4), ("all-candidates", "observer", 16)],
    "run3_3750rpm": [("all-candidates", "ols", 16), ("top-k-correlated", "ols", 4),
                     ("closure", "network", 4), ("top-k-correlated", "observer", 4)],
}


def _children_cpu_s() -> float:
    """User + system CPU seconds of the ended child processes of this one."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def evaluate_protocol(folder: Path, out: Path) -> dict:
    """``spindlebench evaluate`` (in-process) on the cycles ``spindlebench adapt caiviac
    --phase cycle`` wrote to ``folder``: each training run of ``EVALUATE_ROWS`` against the
    other five, each row's ``--json`` written under ``out`` (its CPU seconds printed, not
    stored: the same inputs give the same bytes). The command runs as a user runs it, in its
    own process: a domain module does not import the command line."""
    runs = sorted(p.stem for p in folder.glob("run*.csv"))
    result: dict = {}
    for train, rows in EVALUATE_ROWS.items():
        tests = [r for r in runs if r != train]
        result[train] = []
        for method, regressor, k in rows:
            path = out / f"evaluate_{train}_{method}_{regressor}.json"
            start = _children_cpu_s()
            status = subprocess.call([
                sys.executable, "-m", "spindlebench", "evaluate", "--train",
                str(folder / f"{train}.csv"), "--test", *[str(folder / f"{r}.csv") for r in tests],
                "--target", TARGET, "--method", method, "--regressor", regressor,
                "--clusters", str(k), "--json", str(path)])
            print(f"evaluate --train {train} --method {method} --regressor {regressor}: "
                  f"{_children_cpu_s() - start:.1f} CPU-s", flush=True)
            if status != 0:
                raise SystemExit(f"evaluate {train} {method} {regressor}: exit {status}")
            document = json.loads(path.read_text(encoding="utf-8"))
            result[train].append({
                "method": method, "regressor": regressor, "clusters": k,
                "selected": document["selected"],
                "rmse_um": {Path(n).stem: v for n, v in document["rmse_um"].items()},
                "mean_rmse_um": document["mean_rmse_um"]})
    return result


def evaluate_markdown(result: dict, train: str) -> str:
    """One training run's rows of ``evaluate_protocol``."""
    rows = result[train]
    tests = list(rows[0]["rmse_um"])
    lines = ["| `--method` / `--regressor` (k) | " + " | ".join(tests) + " | **mean** |",
             "|---|" + "---|" * (len(tests) + 1)]
    for row in rows:
        what = f"{len(row['selected'])}: {', '.join(row['selected'])}" \
            if row["regressor"] in ("ols", "observer") and row["method"] != "all-candidates" \
            else (f"{len(row['selected'])}" if row["method"] == "all-candidates"
                  else "speed only")
        lines.append(f"| `{row['method']}` / `{row['regressor']}` ({what}) | " + " | ".join(
            f"{row['rmse_um'][t]:.1f}" for t in tests) + f" | **{row['mean_rmse_um']:.1f}** |")
    return "\n".join(lines)


SYNTHETIC_TESTS = ("heldout", "exp1", "exp3")


#: The feed-rate columns a user has from the NC programme (their |sum| is one heat input).
FEED_COLUMNS = (FEED_X_COLUMN, FEED_Y_COLUMN)
#: The truth's heat flows (W): the spindle's (bearings and motor) and the feeds' (their
#: axis motors' standing 4 W each taken off). Only an oracle reads them.
SPINDLE_HEAT = tuple(true_column(f"{HEAT_FLOW_PREFIX}{name}_W")
                     for name in ("front_bearing", "rear_bearing", "spindle_motor"))
FEED_HEAT = tuple(true_column(f"{HEAT_FLOW_PREFIX}{axis}_feed_W") for axis in ("x", "y"))


def _synthetic_arrays(folder: Path, name: str) -> dict:
    """One synthetic recording's model inputs: speed; speed + room; speed + room + feeds;
    the oracle's true heat flows + room; and its 20 sensors."""
    from spindlebench.formats.recording import read_recording

    frame = read_recording(folder / f"{name}.csv")
    t = frame[TIME_COLUMN].to_numpy(float)
    n = frame[SPEED_COLUMN].to_numpy(float)
    room = frame[AMBIENT_COLUMN].to_numpy(float)
    feed = np.abs(frame[list(FEED_COLUMNS)].to_numpy(float)).sum(axis=1)
    spindle_W = frame[list(SPINDLE_HEAT)].to_numpy(float).sum(axis=1)
    feed_W = frame[list(FEED_HEAT)].to_numpy(float).sum(axis=1) - 4.0 * len(FEED_HEAT)
    return {"frame": frame, "speed": np.column_stack([t, n]),
            "room": np.column_stack([t, n, room]),
            "feeds": np.column_stack([t, n, room, feed]),
            "oracle": np.column_stack([t, spindle_W, room, feed_W]),
            "T": frame[[f"T{i}" for i in range(1, 21)]].to_numpy(float)}


def synthetic_models() -> dict:
    """label -> (estimator, which inputs of ``_synthetic_arrays`` it reads)."""
    models = {
        "transfer function, 1st order (speed)": (TransferFunctionRegressor(order=1), "speed"),
        "transfer function, 2nd order (speed)": (TransferFunctionRegressor(order=2), "speed"),
        "network, order by held-out cycles (speed + ambient)":
            (ThermalNetworkRegressor(ambient=True), "room"),
    }
    for nodes in (2, 3, 4):
        models[f"network, {nodes} nodes (speed + ambient)"] = (
            ThermalNetworkRegressor(n_nodes=nodes, ambient=True), "room")
    # two heat sources of fixed, distinct exponents, a loss present whenever the spindle
    # turns (exponent 0) and Palmgren friction (5/3), instead of one fitted exponent
    for nodes in (2, 3):
        models[f"network, {nodes} nodes, sources n^0 + n^(5/3) (speed + ambient)"] = (
            ThermalNetworkRegressor(n_nodes=nodes, basis=(0.0, 5 / 3), ambient=True), "room")
    # Hammerstein with the feeds a user has from the NC programme: n^a (a fitted) and
    # |feed_x| + |feed_y| as a second heat input, the room as an input
    models["network, order by held-out cycles, n^a + feeds (speed + feeds + ambient)"] = (
        ThermalNetworkRegressor(ambient=True, feeds=1), "feeds")
    for nodes in (2, 3):
        models[f"network, {nodes} nodes, n^a + feeds (speed + feeds + ambient)"] = (
            ThermalNetworkRegressor(n_nodes=nodes, ambient=True, feeds=1), "feeds")
        models[f"network, {nodes} nodes, n^(5/3) + feeds (speed + feeds + ambient)"] = (
            ThermalNetworkRegressor(n_nodes=nodes, basis=(5 / 3,), ambient=True, feeds=1),
            "feeds")
    # the best an identified input map could do: the truth's own heat flows as the inputs
    for nodes in (2, 3):
        models[f"oracle: network, {nodes} nodes on the truth's heat flows (+ ambient)"] = (
            ThermalNetworkRegressor(n_nodes=nodes, exponent=1.0, ambient=True, feeds=1),
            "oracle")
    models["observer, 4 sensors"] = (ObserverRegressor(), "observer")
    return models


def _rms(values) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def superposition(folder: Path) -> dict:
    """Is the truth linear in its two inputs? For ``train`` and ``heldout``: the drift's
    change (noise-free) of the programme, of the same speed programme with the room held at
    its first value (``NAME_speed``), and of the room's day with the spindle and feeds off
    (``NAME_room``). Any model that is linear time-invariant in the room and in a heat input
    map of the speed (Hammerstein, of any order) predicts full = speed part + room part; the
    RMS of the truth's departure from that sum is ``superposition_error_um``. And the best
    speed-only models on the speed parts: how close an LTI network comes to the heat path
    when the room does not move."""
    from spindlebench.formats.recording import read_recording

    out: dict = {"programmes": {}, "heat_path": {}}
    parts = {}
    for name in ("train", "heldout"):
        change = {}
        for suffix in ("", "_speed", "_room"):
            frame = read_recording(folder / f"{name}{suffix}.csv")
            d = frame[TRUE_DRIFT_COLUMN].to_numpy(float)
            change[suffix] = d - d[0]
            parts[name + suffix] = frame
        out["programmes"][name] = {
            "drift_change_rms_um": _rms(change[""]),
            "speed_part_rms_um": _rms(change["_speed"]),
            "room_part_rms_um": _rms(change["_room"]),
            "superposition_error_um": _rms(change[""] - change["_speed"] - change["_room"])}

    def heat_x(frame):
        t = frame[TIME_COLUMN].to_numpy(float)
        feed = np.abs(frame[list(FEED_COLUMNS)].to_numpy(float)).sum(axis=1)
        return np.column_stack([t, frame[SPEED_COLUMN].to_numpy(float), feed])

    for nodes in (1, 2, 3):
        model = ThermalNetworkRegressor(n_nodes=nodes, feeds=1)
        train = parts["train_speed"]
        model.fit(heat_x(train), train[DRIFT_COLUMN].to_numpy(float))
        row = {}
        for name in ("train_speed", "heldout_speed"):
            d = parts[name][TRUE_DRIFT_COLUMN].to_numpy(float)
            row[name] = _rms(model.predict(heat_x(parts[name])) - (d - d[0]))
        out["heat_path"][f"network, {nodes} nodes, n^a + feeds"] = row
    return out


def superposition_markdown(result: dict) -> str:
    lines = ["| programme | drift change, RMS (um) | speed part (room held) | room part (spindle "
             "off) | truth minus the sum of the parts, RMS (um) |", "|---|---|---|---|---|"]
    for name, row in result["programmes"].items():
        lines.append(f"| {name} | {row['drift_change_rms_um']:.2f} | "
                     f"{row['speed_part_rms_um']:.2f} | {row['room_part_rms_um']:.2f} | "
                     f"{row['superposition_error_um']:.2f} |")
    lines += ["", "| heat path alone (room held), fitted on train_speed | train_speed | "
              "heldout_speed |", "|---|---|---|"]
    for label, row in result["heat_path"].items():
        lines.append(f"| {label} | {row['train_speed']:.2f} | {row['heldout_speed']:.2f} |")
    return "\n".join(lines)


def synthetic(folder: Path) -> dict:
    """Twin recovery: identify on ``train.csv`` (scenarios/identification/train.toml,
    simulated by the FMU), predict the held-out programmes; RMSE against the 81-node
    model's noise-free ``true_drift_um``. The ambient is the recording's ``ambient_C``, the
    feeds its ``feed_*_mm_per_min`` columns. With ``train_speed.csv`` etc. beside them, also
    the superposition check (``superposition``)."""
    train = _synthetic_arrays(folder, "train")
    T, frame = train["T"], train["frame"]
    y = frame[DRIFT_COLUMN].to_numpy(float)
    chosen = sorted(np.argsort([-abs(np.corrcoef(T[:, j] - T[0, j], y)[0, 1])
                                for j in range(20)])[:4])
    tests = {name: _synthetic_arrays(folder, name) for name in SYNTHETIC_TESTS}
    for arrays in [train, *tests.values()]:  # the observer reads the chosen four sensors
        arrays["observer"] = np.column_stack([arrays["speed"], arrays["T"][:, chosen]])
    results: dict = {"observer_sensors": [f"T{j + 1}" for j in chosen], "rmse_um": {},
                     "train_rmse_um": {}, "models": {}}
    A = np.column_stack([T - T[0], np.ones(len(T))])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    results["rmse_um"]["MLR, 20 sensors"] = {
        name: _rms(np.column_stack([a["T"] - a["T"][0], np.ones(len(a["T"]))]) @ coef
                   - a["frame"][TRUE_DRIFT_COLUMN].to_numpy())
        for name, a in tests.items()}
    truth = frame[TRUE_DRIFT_COLUMN].to_numpy(float)
    for label, (model, kind) in synthetic_models().items():
        model.fit(train[kind], y)
        results["train_rmse_um"][label] = _rms(model.predict(train[kind]) - truth)
        results["models"][label] = {"tau_h": [x / 3600 for x in model.fit_.taus_s],
                                    "exponents": model.fit_.exponents.tolist()}
        results["rmse_um"][label] = {
            name: _rms(model.predict(a[kind]) - a["frame"][TRUE_DRIFT_COLUMN].to_numpy())
            for name, a in tests.items()}
    if all((folder / f"{n}{s}.csv").is_file() for n in ("train", "heldout")
           for s in ("_speed", "_room")):
        results["superposition"] = superposition(folder)
    return results


def synthetic_markdown(result: dict) -> str:
    lines = ["| model | fit on train (vs truth) | " + " | ".join(SYNTHETIC_TESTS) + " |",
             "|---|---|" + "---|" * len(SYNTHETIC_TESTS)]
    for model, row in result["rmse_um"].items():
        train = result["train_rmse_um"].get(model)
        lines.append(f"| {model} | {'' if train is None else f'{train:.2f}'} | "
                     + " | ".join(f"{row[t]:.2f}" for t in SYNTHETIC_TESTS) + " |")
    return "\n".join(lines)


def _write(out: str | None, name: str, document: dict, source: str | None = None) -> None:
    """``document`` with its provenance as ``out/name`` (atomic), if ``--out`` was given."""
    if not out:
        return
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    record = provenance(kind=f"spindlebench identification validation ({name})",
                        **({"source": file_entry(source)} if source else {}))
    atomic.write_text(folder / name, json.dumps({"provenance": record, **document}, indent=1,
                                                default=float) + "\n")
    print(f"wrote {folder / name}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", default=str(caiviac.default_source()))
    parser.add_argument("--out", default=None, help="folder for the JSON it writes")
    parser.add_argument("--splits", default=",".join("ABCD"))
    parser.add_argument("--synthetic", default=None, metavar="DIR",
                        help="instead: twin recovery on DIR/train.csv, heldout.csv, exp1.csv, "
                        "exp3.csv (spindlebench simulate scenarios/identification/*.toml "
                        "scenarios/paper/exp1.toml scenarios/paper/exp3.toml -o DIR); "
                        "writes synthetic.json")
    parser.add_argument("--room-proxy", action="store_true",
                        help="only the speed network with and without the least-moving sensor "
                        "as the room (mean held-out RMSE per split); writes room_proxy.json")
    parser.add_argument("--evidence", action="store_true",
                        help="only the per-run table of the error against speed and sensors; "
                        "writes evidence.json")
    parser.add_argument("--evaluate", default=None, metavar="DIR",
                        help="instead: spindlebench evaluate on the cycles of DIR "
                        "(spindlebench adapt caiviac --out DIR --phase cycle), the rows of "
                        "EVALUATE_ROWS; writes evaluate.json")
    parser.add_argument("--every-split", action="store_true",
                        help="only MLR and the speed network on all 20 ways to train on three "
                        "runs; writes every_split.json")
    parser.add_argument("--observer", action="store_true",
                        help="with --every-split: also the observer on the 16 sensors "
                        "(EVERY_SPLIT_OBSERVER)")
    args = parser.parse_args(argv)
    if args.synthetic:
        result = synthetic(Path(args.synthetic))
        print(synthetic_markdown(result))
        if "superposition" in result:
            print()
            print(superposition_markdown(result["superposition"]))
        _write(args.out, "synthetic.json", result)
        return 0
    if args.evaluate:
        with tempfile.TemporaryDirectory() as scratch:
            result = evaluate_protocol(Path(args.evaluate), Path(scratch))
        for train in result:
            print(evaluate_markdown(result, train))
            print()
        _write(args.out, "evaluate.json", {"folder": args.evaluate, "runs": result})
        return 0
    frame = caiviac.read_source(args.source)
    schedule = caiviac.find_schedule(frame["spindle_rpm"].to_numpy())
    evidence = room_evidence(frame, schedule)
    print(evidence_markdown(evidence))
    print()
    if args.evidence:
        _write(args.out, "evidence.json", evidence, args.source)
        return 0
    if args.every_split:
        every = every_split(frame, schedule, observer=args.observer)
        print(every_split_markdown(every))
        _write(args.out, "every_split.json", {"splits": every}, args.source)
        return 0
    chosen = [(name, train) for name, train in SPLITS.items()
              if name[0] in args.splits.split(",")]
    if args.room_proxy:
        proxies = {name: room_proxy_split(frame, schedule, train) for name, train in chosen}
        print(room_proxy_markdown(proxies))
        _write(args.out, "room_proxy.json", {"splits": proxies}, args.source)
        return 0
    results = {}
    for name, train in chosen:
        results[name] = run_split(frame, schedule, train)
        print(markdown(name, results[name]), flush=True)
        print()
    print(summary_markdown(results))
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        record = provenance(kind="spindlebench identification validation (CAIVIAC)",
                            source=file_entry(args.source))
        atomic.write_text(out / "caiviac.json",
                          json.dumps({"provenance": record, "splits": results}, indent=1,
                                     default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
