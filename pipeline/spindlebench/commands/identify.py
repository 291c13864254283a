"""``spindlebench identify``: a low-order thermal model identified from recordings.

``identify RECORDING… --map MAP.toml -o MODEL.json`` fits the grey-box network (``--kind
network``, the order by leave-one-cycle-out unless ``--nodes N``) or a transfer-function
baseline (``tf1``, ``tf2``) from the speed programme to the error column of the map, prints
the time constants and exponents with 95 % intervals and the training RMSE, and writes the
model as JSON with provenance. ``--observer`` adds the steady-state Kalman filter on the map's
temperature columns. ``--test RECORDING…`` predicts other recordings of the same machine
(each simulated from rest at its first sample) and prints their RMSE beside MLR (OLS on the
rises of the map's temperatures, the project's ``ols``) trained on the same recordings.

The map is calibrate's MAP.toml (``calibration.mapping``): ``inputs.spindle_speed_rpm`` must
name a column, ``error.column`` the error; ``inputs.ambient_C`` a column makes the ambient an
input, ``"unknown"`` or a number leaves it constant; a temperature's model output is not used.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from spindlebench.calibration.mapping import read_map
from spindlebench.calibration.series import Series, load_series
from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.recording import AMBIENT_COLUMN, NODE_PREFIX, SPEED_COLUMN, node_output
from spindlebench.formats.roles import ColumnRoles, add_role_arguments
from spindlebench.formats.toml import load_toml

if TYPE_CHECKING:  # SciPy with the model: imported where it is used, not for ``--help``
    from spindlebench.identification.model import Inputs

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "identify a low-order thermal model (and observer) from recordings"

AUTO = "auto"


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "identify", help=HELP,
        description=__doc__.split("\n\n")[0] if __doc__ else None,
    )
    parser.add_argument("recordings", nargs="+", metavar="RECORDING",
                        help="recording CSV(s) of the machine (one shared model)")
    parser.add_argument("--map", required=True, dest="map_file",
                        help="MAP.toml: the speed, error and (optional) ambient and sensors")
    parser.add_argument("-o", "--out", required=True, help="model JSON to write")
    parser.add_argument("--kind", choices=("network", "tf1", "tf2"), default="network",
                        help="grey-box network (default) or a 1st/2nd-order transfer function")
    parser.add_argument("--nodes", default=AUTO,
                        help="thermal nodes of the network, or 'auto' (1-3, leave-one-cycle-"
                        "out; default)")
    parser.add_argument("--sources", type=int, choices=(1, 2), default=1,
                        help="heat sources of the speed, each (n/n_ref)^a (default 1)")
    parser.add_argument("--exponent", type=float, default=None,
                        help="fix the heat-input exponent a (default: fitted in [0.3, 3])")
    parser.add_argument("--observer", action="store_true",
                        help="also a Kalman filter on the map's temperature columns")
    parser.add_argument("--disturbances", type=int, default=1,
                        help="random-walk disturbance states of the observer (default 1)")
    parser.add_argument("--test", nargs="+", default=[], metavar="RECORDING",
                        help="recordings to predict (RMSE beside MLR on the map's sensors)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the starting points")
    parser.add_argument("--starts", type=int, default=4, help="least-squares starts")
    parser.add_argument("--step-s", type=float, default=None,
                        help="identify on every step_s seconds (a multiple of the sampling)")
    add_role_arguments(parser, sensors=False, exclude=False)
    parser.set_defaults(func=_run)


def _map(path: str):
    """calibrate's map reader; the temperatures' model outputs are not used here, so any
    ``node_…`` name is accepted (T1 … T20 always are)."""
    raw = load_toml(Path(path), "map")
    temperatures = raw.get("temperatures", {}) if isinstance(raw, dict) else {}
    outputs = {node_output(str(v).removeprefix(NODE_PREFIX).removesuffix("_C"))
               for v in temperatures.values() if isinstance(v, str)}
    recording_map = read_map(path, outputs)
    speed = recording_map.inputs[SPEED_COLUMN]
    if not isinstance(speed, str):
        raise SpindlebenchError(f"{path}: key 'inputs.spindle_speed_rpm': identification needs "
                                "the speed programme as a column, got a constant")
    if not recording_map.error_column:
        raise SpindlebenchError(f"{path}: key 'error.column': identification needs the error "
                                "column (the output the model predicts)")
    return recording_map


def _parts(series: Series, ambient: bool) -> tuple[Inputs, np.ndarray, np.ndarray, list[str]]:
    """Inputs, the error and the temperature columns of one recording."""
    from spindlebench.identification.model import Inputs

    error = next(c for c in series.channels if c.kind == "error")
    temperatures = [c for c in series.channels if c.kind == "temperature"]
    inputs = Inputs(series.time_s, series.inputs[0],
                    ambient_C=series.inputs[3] if ambient else None)
    T = np.column_stack([c.values for c in temperatures]) if temperatures else \
        np.empty((len(series.time_s), 0))
    return inputs, error.values, T, [c.column for c in temperatures]


def _mlr_rmse(train: list[tuple[np.ndarray, np.ndarray]], T: np.ndarray, y: np.ndarray
              ) -> float:
    """OLS of the error on the rises (each recording from its first sample)."""
    from spindlebench.identification.model import rezeroed_rmse

    A = np.vstack([np.column_stack([Tr - Tr[0], np.ones(len(Tr))]) for Tr, _ in train])
    b = np.concatenate([yr - yr[0] for _, yr in train])
    ok = np.all(np.isfinite(A), axis=1) & np.isfinite(b)
    coef, *_ = np.linalg.lstsq(A[ok], b[ok], rcond=None)
    return rezeroed_rmse(np.column_stack([T - T[0], np.ones(len(T))]) @ coef, y)


def _run(args: argparse.Namespace) -> int:
    from spindlebench.identification.model import Structure, fit, select_order

    out = Path(args.out)
    if out.suffix != ".json":
        raise SpindlebenchError(f"-o {out}: the model file ends in .json")
    recording_map = _map(args.map_file)
    roles = ColumnRoles.from_args(args)
    ambient = isinstance(recording_map.inputs[AMBIENT_COLUMN], str) and \
        not recording_map.ambient_unknown
    series = [load_series(p, recording_map, args.step_s, roles) for p in args.recordings]
    parts = [_parts(s, ambient) for s in series]
    inputs = [p[0] for p in parts]
    y = np.concatenate([p[1] for p in parts])
    if args.nodes != AUTO:
        try:
            nodes = int(args.nodes)
        except ValueError:
            raise SpindlebenchError(f"--nodes {args.nodes!r}: a number or 'auto'") from None
    else:
        nodes = AUTO
    def structure_of(n: int) -> Structure:
        return Structure(args.kind, n, args.sources, 0, ambient, False, args.exponent)

    order_scores: list[dict] = []
    if args.kind == "network" and nodes == AUTO:
        structure, order_scores = select_order(
            [structure_of(n) for n in (1, 2, 3)], inputs if len(inputs) > 1 else inputs[0],
            y, np.isfinite(y), seed=args.seed)
        for row in order_scores:
            print(f"held-out RMSE {row['structure']}: {row['mean']:.3g} (per block: "
                  + ", ".join(f"{v:.3g}" for v in row["held_out_rmse"]) + ")")
    else:
        structure = structure_of(2 if nodes == AUTO else nodes)
    model_inputs = inputs if len(inputs) > 1 else inputs[0]
    result = fit(structure, model_inputs, y, seed=args.seed, starts=args.starts,
                 output_names=(recording_map.error_column,))
    print(f"{structure.label}: {result.status} after {result.evaluations} evaluations "
          f"({result.starts} starts); training RMSE {result.rmse[0]:.3g} um")
    for tau, (lo, hi) in zip(result.taus_s, result.tau_interval95(), strict=True):
        print(f"  time constant {tau / 3600:.3g} h  [{lo / 3600:.3g}, {hi / 3600:.3g}]")
    for a, se in zip(result.exponents, result.theta_se[structure.n_taus:], strict=False):
        print(f"  heat-input exponent {a:.3g} +- {1.96 * se:.2g}")
    content = {"model": result.to_dict(), "order_selection": order_scores,
               "error_sign": recording_map.error_sign}
    observer_model = None
    if args.observer:
        observer_model = _observer(args, recording_map, inputs, parts, content)
    if args.test:
        _test(args, recording_map, result, observer_model, parts, roles, ambient, content)
    content["provenance"] = provenance(
        kind="spindlebench identification", recordings=[file_entry(s.path) for s in series],
        map=file_entry(recording_map.path), seed=args.seed, starts=args.starts,
        step_s=args.step_s)
    atomic.write_text(out, json.dumps(content, indent=1, sort_keys=True) + "\n")
    print(f"wrote {out}")
    return 0


def _observer(args, recording_map, inputs, parts, content):
    from spindlebench.identification.estimators import ObserverRegressor
    from spindlebench.identification.model import rezeroed_rmse

    if len(parts) != 1:
        raise SpindlebenchError("--observer: identify on one recording (the filter runs "
                                "through it continuously)")
    if not parts[0][3]:
        raise SpindlebenchError(f"{recording_map.path}: --observer needs temperature columns "
                                "in the map's [temperatures]")
    inp, y, T, names = parts[0]
    X = np.column_stack([inp.time_s, inp.speed_rpm, T])
    model = ObserverRegressor(n_nodes=2, disturbances=args.disturbances,
                              random_state=args.seed).fit(X, y)
    obs = model.observer_
    rmse = rezeroed_rmse(model.predict(X), y)
    print(f"observer on {', '.join(names)}: q = {obs.q:.3g}, training RMSE {rmse:.3g} um")
    content["observer"] = {"sensors": names, "q": obs.q, "gain": obs.K.tolist(),
                           "network": model.fit_.to_dict(), "training_rmse": rmse}
    return model


def _test(args, recording_map, result, observer_model, parts, roles, ambient, content):
    from spindlebench.identification.model import rezeroed_rmse

    rows = []
    train = [(T, y) for _, y, T, _ in parts]
    for path in args.test:
        series = load_series(path, recording_map, args.step_s, roles)
        inp, y, T, _ = _parts(series, ambient)
        row = {"recording": str(path), "model": rezeroed_rmse(result.predict(inp)[:, 0], y),
               "zero": rezeroed_rmse(np.zeros(len(y)), y)}
        if T.shape[1]:
            row["mlr"] = _mlr_rmse(train, T, y)
        if observer_model is not None:
            X = np.column_stack([inp.time_s, inp.speed_rpm, T])
            row["observer"] = rezeroed_rmse(observer_model.predict(X), y)
        rows.append(row)
        print(f"{path}: RMSE model {row['model']:.3g} um"
              + (f", observer {row['observer']:.3g}" if "observer" in row else "")
              + (f", MLR {row['mlr']:.3g}" if "mlr" in row else "")
              + f" (predicting 0: {row['zero']:.3g})")
    content["test"] = rows
