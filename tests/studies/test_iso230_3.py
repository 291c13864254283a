"""``spindlebench iso230-3``: the report's numbers, the recording map and the command."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from spindlebench.commands.main import main
from spindlebench.core.errors import SpindlebenchError
from spindlebench.studies.iso230_3 import evaluation
from spindlebench.studies.iso230_3.channels import load_map


def test_stability_is_met_when_the_last_hour_changes_less_than_15_percent_of_the_first():
    t = np.arange(0.0, 6 * 3600.0 + 1, 60.0)
    tau = 1800.0
    z = 30.0 * (1.0 - np.exp(-t / tau))
    s = evaluation.stability(t, {"Z": z}, phase_end_s=t[-1])
    # change over [t-1h, t] = 30 e^{-t/tau}(e^{1h/tau} - 1) <= 0.15 * 30 (1 - e^{-1h/tau})
    ratio = 0.15 * (1 - np.exp(-3600 / tau)) / (np.exp(3600 / tau) - 1)
    expected = -tau * np.log(ratio)
    assert s.met_at_s == pytest.approx(expected, abs=60.0)
    assert s.per_direction_s["Z"] == s.met_at_s
    both = evaluation.stability(t, {"Z": z, "Y": np.zeros_like(t)}, phase_end_s=t[-1])
    assert both.met_at_s == s.met_at_s  # a still direction (under the floor) holds nothing up
    late = evaluation.stability(t, {"Z": z}, phase_end_s=expected - 600.0)
    assert late.met_at_s is None and late.to_dict()["met"] is False


def test_ranges_and_spindle_phase():
    t = np.arange(0.0, 10.0) * 600.0
    speed = np.array([4000.0] * 6 + [0.0] * 4)
    assert evaluation.spindle_on_end_s(t, speed) == 3600.0
    r = evaluation.ranges(t, {"Y": np.array([0, 1, 4, 2, 2, 2, 1, 0, -1, 0.0])})["Y"]
    assert r["range"] == 5.0 and r["at_max_h"] == pytest.approx(2 * 600 / 3600)


def test_map_errors_name_the_key(tmp_path):
    path = tmp_path / "map.toml"
    path.write_text('[directions]\nW = "ch1_um"\n')
    with pytest.raises(SpindlebenchError, match=r"map.toml: key 'directions.W'"):
        load_map(path)
    path.write_text('[directions]\nX = { upper = "a", lower = "b" }\n')
    with pytest.raises(SpindlebenchError, match="probe_l_m"):
        load_map(path)
    path.write_text('[directions]\nZ = { column = "a", sign = 2 }\n')
    with pytest.raises(SpindlebenchError, match="sign"):
        load_map(path)


def test_report_from_a_recording_through_its_map(tmp_path, capsys):
    t = np.arange(0.0, 8 * 3600.0 + 1, 300.0)
    on = t < 4 * 3600
    heat = np.where(on, 1 - np.exp(-t / 3600), (1 - np.exp(-4)) * np.exp(-(t - 4 * 3600) / 3600))
    frame = pd.DataFrame({"time_s": t, "rpm": np.where(on, 3000.0, 0.0),
                          "t1_C": 20 + 10 * heat, "air_C": np.full(t.size, 20.0),
                          "ch1_um": 12 * heat, "ch2_um": 10 * heat,
                          "ch3_um": -40 * heat + 5.0, "ch4_um": 2 * heat, "ch5_um": 0 * heat})
    csv = tmp_path / "run.csv"
    frame.to_csv(csv, index=False)
    mapping = tmp_path / "map.toml"
    mapping.write_text('air = "air_C"\nspeed = "rpm"\nprobe_l_m = 0.1\n'
                       'temperatures = ["t1_C"]\nothers = ["ch4_um"]\n[directions]\n'
                       'X = { upper = "ch1_um", lower = "ch2_um" }\n'
                       'Z = { column = "ch3_um", sign = -1 }\nY = "ch5_um"\n')
    out = tmp_path / "report"
    assert main(["iso230-3", "spindle", "--recording", str(csv), "--map", str(mapping),
                 "-o", str(out)]) == 0
    report = json.loads((out / "spindle.json").read_text())
    peak = 1 - np.exp(-4)
    assert report["range_um"]["Z"]["range"] == pytest.approx(40 * peak, abs=1e-3)
    assert report["range_um"]["X"]["range"] == pytest.approx(10 * peak, abs=1e-3)
    # tilt B from the X pair: (12 - 10) heat / 0.1 m
    assert report["range_urad"]["B"]["range"] == pytest.approx(20 * peak, abs=1e-2)
    assert report["spindle_on_end_h"] == 4.0
    assert report["stability"]["met"] is True
    assert report["provenance"]["recording"]["sha256"]
    series = pd.read_csv(out / "spindle_series.csv")
    assert {"Z_um", "tilt_B_urad", "ch4_um", "ch1_um", "air_C", "t1_C"} <= set(series.columns)
    assert (out / "spindle.png").stat().st_size > 10_000


@pytest.mark.slow
def test_spindle_test_on_the_default_machine(tmp_path):
    out = tmp_path / "spindle"
    assert main(["iso230-3", "spindle", "--machine", "default", "-o", str(out)]) == 0
    report = json.loads((out / "spindle.json").read_text())
    z = report["heating_range_um"]["Z"]["range"]
    y = report["heating_range_um"]["Y"]["range"]
    assert 10.0 < z < 60.0 and 3.0 < y < z  # a VMC: Z largest, Y from the column, tens of µm
    assert report["range_urad"]["A"]["range"] > 5.0
    assert (out / "spindle_recording.csv").is_file()


def test_compensate_reports_what_a_trained_model_leaves_of_z(tmp_path, capsys):
    t = np.arange(0.0, 4 * 3600.0 + 1, 300.0)
    heat = 1 - np.exp(-t / 3600)
    t1, t2 = 20 + 10 * heat, 20 + 4 * heat
    z = 0.5 + 2.0 * (t1 - t1[0]) + 1.0 * ((t1 - t1[0]) - (t2 - t2[0]))
    z = z - z[0]  # the probe is zeroed; the model's intercept 0.5 stays in the residual
    csv = tmp_path / "run.csv"
    pd.DataFrame({"time_s": t, "T1": t1, "T2": t2, "z_um": z}).to_csv(csv, index=False)
    mapping = tmp_path / "map.toml"
    mapping.write_text('temperatures = ["T1"]\n[directions]\nZ = "z_um"\n')
    models = {"models": {"never": {"m": [{"trained_on_day": 1, "inputs": ["T1", "T1-T2"],
                                          "excluded": [], "coefficients": [0.5, 2.0, 1.0]}]}}}
    trained = tmp_path / "provenance.json"
    trained.write_text(json.dumps(models))
    out = tmp_path / "report"
    assert main(["iso230-3", "spindle", "--recording", str(csv), "--map", str(mapping),
                 "--compensate", str(trained), "-o", str(out)]) == 0
    report = json.loads((out / "spindle.json").read_text())
    residual = report["range_um"]["Z residual (m)"]
    assert report["range_um"]["Z"]["range"] > 20.0
    assert residual["range"] < 1e-3 and residual["final"] == pytest.approx(-0.5, abs=1e-3)
    assert report["provenance"]["compensation"]["inputs"] == ["T1", "T1-T2"]
    capsys.readouterr()
    assert main(["iso230-3", "spindle", "--recording", str(csv), "--map", str(mapping),
                 "--compensate", str(trained), "--model", "x", "-o", str(out)]) != 0
    assert "key 'models': no model 'x' (has m)" in capsys.readouterr().err
