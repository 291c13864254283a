"""``spindlebench calibrate``: MAP.toml checks, and a small twin recovery through the real FMU.

The twin: the FMU simulates a short recording of a machine whose bearing friction, motor loss
and spindle expansion length differ from the defaults by 25-30 %, with the testbench's sensor
noise; ``calibrate`` fits those three; they come back within their 95 % intervals, and the
calibrated machine predicts a different, held-out programme's drift within 1 um RMSE of the
true machine (both simulated by the FMU).
"""

from __future__ import annotations

import contextlib
import io
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from conftest import MODELS
from spindlebench.calibration.mapping import read_map, recording_map_text
from spindlebench.commands.main import main
from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.recording import read_recording

OUTPUTS = [f"T{i}_C" for i in range(1, 21)] + ["drift_um", "node_housing_1_C",
                                                 "node_spindle_motor_C"]
TWIN_MAP = recording_map_text(["T1", "T4", "T6", "T8"])
TRUE = {"front_bearing_friction_f0": 1.1 * 1.3, "P_spindle_motor_ref": 140.0 * 0.75,
        "spindle_shaft_L": 0.55 * 1.3}


def _map(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "map.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_map_reads_columns_constants_and_model_names(tmp_path):
    m = read_map(_map(tmp_path, TWIN_MAP.replace('ambient_C = "ambient_C"',
                                                 'ambient_C = "unknown"')
                      + '[ambient]\nknot_h = 2\n[noise]\nT1 = 0.1\n'), OUTPUTS)
    assert m.ambient_unknown and m.ambient_knot_h == 2.0
    assert m.temperatures == {"T1": "T1_C", "T4": "T4_C", "T6": "T6_C", "T8": "T8_C"}
    assert m.noise == {"T1": 0.1}
    unmapped = m.check_columns(["time_s", "spindle_speed_rpm", "feed_x_mm_per_min",
                                "feed_y_mm_per_min", "T1", "T4", "T6", "T8", "drift_um", "T2"],
                               tmp_path / "r.csv")
    assert unmapped == ["T2"]


@pytest.mark.parametrize(("change", "key"), [
    (("[error]", "[error]\nsgn = 1"), "error.sgn"),
    (('T8 = "T8"', 'T8 = "T21"'), "temperatures.T8"),
    (('T8 = "T8"', 'T8 = "node_housing_9"'), "temperatures.T8"),
    (('spindle_speed_rpm = "spindle_speed_rpm"', 'spindle_speed_rpm = "unknown"'),
     "inputs.spindle_speed_rpm"),
    (('feed_y_mm_per_min = "feed_y_mm_per_min"\n', ""), "inputs.feed_y_mm_per_min"),
    (("[error]", "[ambient]\nknot_h = 1\n[error]"), "ambient.knot_h"),
    # issue 25: knots 0 h apart, a table that maps nothing, a constant input out of range
    (('ambient_C = "ambient_C"', 'ambient_C = "unknown"\n[ambient]\nknot_h = 0'),
     "ambient.knot_h"),
    (('T1 = "T1"\nT4 = "T4"\nT6 = "T6"\nT8 = "T8"', ""), "temperatures"),
    (('spindle_speed_rpm = "spindle_speed_rpm"', "spindle_speed_rpm = -500"),
     "inputs.spindle_speed_rpm"),
])
def test_bad_map_is_one_line_naming_the_key(tmp_path, change, key):
    with pytest.raises(SpindlebenchError) as info:
        read_map(_map(tmp_path, TWIN_MAP.replace(*change)), OUTPUTS)
    message = str(info.value)
    assert "\n" not in message and f"key '{key}'" in message and "map.toml" in message


def test_a_recording_with_a_negative_speed_is_one_line_naming_column_and_key(tmp_path):
    from spindlebench.calibration.series import load_series

    recording = tmp_path / "logger.csv"
    rows = [f"{60 * i},{-1200 if i == 3 else 1200},0,0,21.0,{21 + 0.1 * i},{0.5 * i * i}"
            for i in range(6)]
    recording.write_text("time_s,rpm,feed_x_mm_per_min,feed_y_mm_per_min,ambient_C,T1,drift_um\n"
                         + "\n".join(rows) + "\n", encoding="utf-8")
    m = read_map(_map(tmp_path, recording_map_text(["T1"]).replace(
        'spindle_speed_rpm = "spindle_speed_rpm"', 'spindle_speed_rpm = "rpm"')), OUTPUTS)
    with pytest.raises(SpindlebenchError) as info:
        load_series(recording, m, None)
    assert str(info.value) == (
        f"recording {recording}: column 'rpm' (map.toml key 'inputs.spindle_speed_rpm') is "
        "-1200 at time_s = 180; the model's spindle_speed_rpm is 0 … 30000 rev/min (for a "
        "reversed spindle give the magnitude)")


def test_map_column_missing_from_recording_names_key(tmp_path):
    m = read_map(_map(tmp_path, TWIN_MAP), OUTPUTS)
    with pytest.raises(SpindlebenchError, match=r"key 'temperatures.T8': column is not in"):
        m.check_columns(["time_s", "spindle_speed_rpm", "feed_x_mm_per_min",
                         "feed_y_mm_per_min", "ambient_C", "T1", "T4", "T6", "drift_um"],
                        tmp_path / "r.csv")


def _scenario(path: Path, speed_steps: str, parameters: dict[str, float], seed: int) -> Path:
    lines = [
        'description = "calibration test"', "duration_s = 7200", "step_s = 60.0",
        "sample_interval_s = 60.0", f"seed = {seed}",
        "[speed]", 'kind = "steps"', f"steps = {speed_steps}",
        "[feed]", 'kind = "with_spindle"', "x_mm_per_min = 1500", "y_mm_per_min = 1500",
        "[ambient]", 'kind = "season"', "low_C = 19", "high_C = 22",
        "[parameters]", *[f"{k} = {v!r}" for k, v in parameters.items()],
    ]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def twin(tmp_path_factory):
    """A twin recording simulated by the FMU and calibrated once: (folder, CLI output)."""
    folder = tmp_path_factory.mktemp("twin")
    scenario = _scenario(folder / "twin.toml", "[{at_s = 0, rpm = 3000}, {at_s = 2400, rpm = "
                         "6000}, {at_s = 4800, rpm = 0}]", TRUE, seed=5)
    assert main(["simulate", str(scenario), "-o", str(folder / "twin.csv")]) == 0
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        status = main(["calibrate", str(folder / "twin.csv"), "--map",
                       str(_map(folder, TWIN_MAP)), "-o", str(folder / "machines" / "twin.toml"),
                       "--models", str(MODELS), "--fit", ",".join(TRUE), "--design"])
    assert status == 0, buffer.getvalue()
    return folder, buffer.getvalue()


def test_twin_recovery_and_held_out_prediction(twin):
    tmp_path, out = twin
    machine = tmp_path / "machines" / "twin.toml"
    assert "ignored (not in the map): T2, T3" in out and "design:" in out
    report = json.loads((tmp_path / "machines" / "twin.calibration.json").read_text())
    assert (tmp_path / "machines" / "twin.calibration.png").stat().st_size > 10_000
    assert report["provenance"]["recordings"][0]["sha256"]
    assert report["evaluation_limit"] == 50  # the default --max-iter
    assert report["stop_reason"].startswith("converged") and "stopped: converged" in out
    # the twin's structure is right: nothing runs to a bound (a real machine's fit does)
    assert report["at_bound"] == [] and "at a bound of the factor range" not in out
    for row in report["parameters"]:
        lo, hi = row["ci95"]
        assert lo <= TRUE[row["name"]] <= hi, row
        assert abs(row["estimate"] / TRUE[row["name"]] - 1) < 0.1, row
    fitted = tomllib.loads(machine.read_text(encoding="utf-8"))["parameters"]
    assert set(fitted) == set(TRUE)

    # held out: another programme, the calibrated machine against the true one
    held_out = "[{at_s = 0, rpm = 5000}, {at_s = 3600, rpm = 1500}]"
    truth = _scenario(tmp_path / "truth.toml", held_out, TRUE, seed=6)
    model = _scenario(tmp_path / "model.toml", held_out, fitted, seed=6)
    default = _scenario(tmp_path / "default.toml", held_out, {}, seed=6)
    for scenario in (truth, model, default):
        assert main(["simulate", str(scenario), "-o", str(scenario.with_suffix(".csv"))]) == 0

    def true_drift(name: str) -> np.ndarray:
        return read_recording(tmp_path / f"{name}.csv")["true_drift_um"].to_numpy()

    rmse = float(np.sqrt(np.mean((true_drift("model") - true_drift("truth")) ** 2)))
    uncalibrated = float(np.sqrt(np.mean((true_drift("default") - true_drift("truth")) ** 2)))
    assert rmse < 1.0 and rmse < uncalibrated / 3, (rmse, uncalibrated)


def test_calibrated_machine_runs_through_sweep_unchanged(twin, repo):
    """The machine file calibrate writes is a machine like the shipped ones."""
    machines = pytest.importorskip("spindlebench.machines.variants")
    tmp_path, _ = twin
    machine_file = tmp_path / "machines" / "twin.toml"
    machine = machines.load_machine(str(machine_file))
    assert set(machine.parameters) == set(TRUE)
    out = tmp_path / "sweep"
    assert main(["sweep", str(repo / "scenarios" / "studies" / "tiny_sweep.toml"), "-o", str(out),
                 "--machine", str(machine_file)]) == 0
    provenance = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    assert "twin" in json.dumps(provenance)


def test_fit_bounds_respect_the_fmus_declared_range():
    """A factor range that would leave the FMU's min/max is narrowed to it (h_nat <= 100)."""
    from spindlebench.calibration.problem import Discretisation
    from spindlebench.model.equations import explicit_ode

    ode = explicit_ode(MODELS, segments=2)
    assert ode.bounds["h_nat"][1] == 100.0
    lower, upper = Discretisation(ode, ["h_nat"], ode.parameter_vector(h_nat=50.0)).log_bounds()
    assert np.exp(upper[0]) == pytest.approx(2.0) and np.exp(lower[0]) == pytest.approx(0.1)
    with pytest.raises(SpindlebenchError, match="h_nat: the start value is outside"):
        Discretisation(ode, ["h_nat"], ode.parameter_vector(h_nat=150.0)).log_bounds()


def test_fitted_end_state_continues_the_recording(twin):
    """Issue 22: calibrate writes the fitted states (``NAME.state.json``, the sidecar format)
    and a ``continue`` scenario on ``simulate --machine`` starts the calibrated machine where
    the recording ended: its drift follows the true machine's continuation (from the twin
    recording's own end state) far closer than a cold start does."""
    tmp_path, out = twin
    machine = tmp_path / "machines" / "twin.toml"
    state = tmp_path / "machines" / "twin.state.json"
    assert "twin.state.json" in out and "twin.state.json" in machine.read_text()
    saved = json.loads(state.read_text())
    true_end = json.loads((tmp_path / "twin.json").read_text())["end_state"]["states_K"]
    fitted_end = saved["end_state"]["states_K"]
    assert set(fitted_end) == set(true_end) and saved["end_state"]["time_s"] > 0
    # the fitted end state of the parts the error comes from is the true one to about 1 K
    for name in ("spindle_shaft_1_T", "front_bearing_T", "housing_1_T"):
        assert abs(fitted_end[name] - true_end[name]) < 1.5, name
    report = json.loads((tmp_path / "machines" / "twin.calibration.json").read_text())
    assert report["fitted_states_K"][0]["end"] == fitted_end

    def scenario(name: str, parameters: dict, initial: str) -> Path:
        path = tmp_path / f"{name}.toml"
        path.write_text("\n".join([
            'description = "continuation"', "duration_s = 3600", "step_s = 60.0",
            "sample_interval_s = 60.0", "seed = 7", "[speed]", 'kind = "steps"',
            "steps = [{at_s = 0, rpm = 2000}]", "[feed]", 'kind = "with_spindle"',
            "x_mm_per_min = 1500", "y_mm_per_min = 1500", "[ambient]", 'kind = "season"',
            "low_C = 19", "high_C = 22", initial, "[parameters]",
            *[f"{k} = {v!r}" for k, v in parameters.items()]]) + "\n", encoding="utf-8")
        return path

    runs = {
        "truth": (scenario("truth", TRUE, f'[initial]\nkind = "continue"\nfrom = '
                                          f'"{tmp_path / "twin.json"}"'), []),
        "continued": (scenario("continued", {}, f'[initial]\nkind = "continue"\nfrom = '
                                                f'"{state}"'), ["--machine", str(machine)]),
        "cold": (scenario("cold", {}, ""), ["--machine", str(machine)]),
    }
    drift = {}
    for name, (path, extra) in runs.items():
        assert main(["simulate", str(path), "-o", str(path.with_suffix(".csv")), *extra]) == 0
        drift[name] = read_recording(path.with_suffix(".csv"))["true_drift_um"].to_numpy()
    continued = float(np.sqrt(np.mean((drift["continued"] - drift["truth"]) ** 2)))
    cold = float(np.sqrt(np.mean((drift["cold"] - drift["truth"]) ** 2)))
    assert continued < 1.0 and continued < cold / 3, (continued, cold)


@pytest.mark.slow
def test_a_step_whose_chord_iterations_fail_is_solved_by_newton(tmp_path, monkeypatch):
    """Issue 22 (found rerunning docs/validation.md's CAIVIAC calibration with 15 parameters:
    the prediction over the held-out runs aborted at the 5000 rpm switch-on): when the chord
    iterations at a step do not converge, the step is solved by Newton with a refreshed
    Jacobian, to the same trajectory, and only a step Newton cannot solve raises."""
    from spindlebench.calibration import problem
    from spindlebench.calibration.fitset import DEFAULT_FIT
    from spindlebench.calibration.series import load_series
    from spindlebench.model.equations import explicit_ode

    t = np.arange(0.0, 4 * 3600 + 1, 120.0)
    rpm = np.where(t >= 3600, 5000.0, 0.0)
    lines = ["time_s,spindle_speed_rpm,feed_x_mm_per_min,feed_y_mm_per_min,ambient_C,drift_um,"
             "T1"] + [f"{a:g},{b:g},0,0,21.0,{a / 1e3:g},{22 + (a / 7200) ** 2:g}"
                      for a, b in zip(t, rpm, strict=True)]
    (tmp_path / "rec.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    recording_map = read_map(_map(tmp_path, recording_map_text(["T1"])), OUTPUTS)
    series = load_series(tmp_path / "rec.csv", recording_map, None)
    ode = explicit_ode(MODELS, segments=2)
    fit = [n for n in DEFAULT_FIT if n in ode.parameters]
    d = problem.Discretisation(ode, fit, ode.parameter_vector())
    s = np.log(np.where([n.endswith("_C") for n in fit], 0.1, 1.0))  # fast, stiff nodes
    z0 = d.initial_guess(series, s, 21.0)
    chord, S_chord = problem.trajectory(d, series, z0, s, np.zeros(0))
    monkeypatch.setattr(problem, "MAX_CHORD_ITERATIONS", 1)
    newton, S_newton = problem.trajectory(d, series, z0, s, np.zeros(0))
    assert np.max(np.abs(newton - chord)) < 1e-5
    # the sensitivities: the chord's at the predictor, Newton's at the solution; with these
    # stiff (x0.1 capacity) nodes at a 5000 rpm switch-on they differ by 3.5 % (measured)
    assert np.linalg.norm(S_newton - S_chord) < 0.1 * np.linalg.norm(S_chord), \
        np.linalg.norm(S_newton - S_chord) / np.linalg.norm(S_chord)
    monkeypatch.setattr(problem, "MAX_NEWTON_ITERATIONS", 1)
    with pytest.raises(problem.StepFailedError, match=r"rec\.csv: the step at time_s = "):
        problem.trajectory(d, series, z0, s, np.zeros(0))
