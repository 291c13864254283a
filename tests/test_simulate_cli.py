"""``spindlebench simulate`` on the command line: outputs, one-line errors, nothing half-written."""

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from spindlebench import cli
from spindlebench.testbench.runner import DEFAULT_FMU

QUICK = """\
duration_s = 600
step_s = 1.0
sample_interval_s = 60
seed = 2

[speed]
kind = "constant"
rpm = 3000

[feed]
kind = "with_spindle"
x_mm_per_min = 1500
y_mm_per_min = 1500

[ambient]
kind = "constant"
temperature_C = 18.0
"""


def write(directory: Path, name: str, text: str) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    path.write_text(text, encoding="utf-8")
    return path


def test_simulate_writes_recording_and_sidecar(tmp_path, capsys):
    scenario = write(tmp_path, "quick.toml", QUICK)
    out = tmp_path / "out" / "quick.csv"
    status = cli.main(["simulate", str(scenario), "-o", str(out), "--seed", "11"])
    captured = capsys.readouterr()
    assert status == 0
    assert "quick.csv" in captured.out
    assert "it/s" not in captured.err and "sim-s" not in captured.err  # no bar: not a TTY
    frame = pd.read_csv(out)
    assert len(frame) == 11 and frame.time_s.iloc[-1] == 600.0
    sidecar = json.loads(out.with_suffix(".json").read_text())
    assert sidecar["seed"] == 11
    assert sidecar["fmu"]["path"] == str(DEFAULT_FMU)
    assert sorted(p.name for p in out.parent.iterdir()) == ["quick.csv", "quick.json"]


def test_simulate_a_directory_of_scenarios_into_a_directory(tmp_path, capsys):
    folder = tmp_path / "scen"
    write(folder, "a.toml", QUICK)
    write(folder, "b.toml", QUICK.replace("rpm = 3000", "rpm = 1000"))
    status = cli.main(["simulate", str(folder), "-o", str(tmp_path / "res"), "--quiet"])
    assert status == 0
    assert capsys.readouterr().out == ""
    names = sorted(p.name for p in (tmp_path / "res").iterdir())
    assert names == ["a.csv", "a.json", "b.csv", "b.json"]
    a = pd.read_csv(tmp_path / "res" / "a.csv")
    b = pd.read_csv(tmp_path / "res" / "b.csv")
    assert a.true_T1_C.iloc[-1] > b.true_T1_C.iloc[-1]


@pytest.mark.parametrize(
    ("edit", "key"),
    [
        (lambda t: t.replace("rpm = 3000", "rpm = -3000"), "speed.rpm"),
        (lambda t: t.replace("temperature_C = 18.0", "temperature_C = 291.15"),
         "ambient.temperature_C"),
        (lambda t: t + "[cooling]\nmode = \"absolute\"\nsetpoint = 20\n", "cooling.setpoint"),
        (lambda t: t.replace("step_s = 1.0", "step_s = 900"), "step_s"),
        (lambda t: t.replace("seed = 2", "seed = 2.5"), "seed"),
    ],
)
def test_bad_scenario_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, edit, key):
    scenario = write(tmp_path, "bad.toml", edit(QUICK))
    out = tmp_path / "out" / "bad.csv"
    status = cli.main(["simulate", str(scenario), "-o", str(out)])
    err = capsys.readouterr().err
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("error: ") and "bad.toml" in lines[0] and f"'{key}'" in lines[0]
    assert not out.parent.exists()


def test_a_bad_file_among_several_stops_before_any_simulation(tmp_path, capsys):
    good = write(tmp_path, "good.toml", QUICK)
    bad = write(tmp_path, "zbad.toml", QUICK.replace("[feed]", "[feeed]"))
    status = cli.main(["simulate", str(good), str(bad), "-o", str(tmp_path / "res")])
    assert status == 2
    assert "zbad.toml" in capsys.readouterr().err
    assert not (tmp_path / "res").exists()


def test_output_must_be_csv_or_directory(tmp_path, capsys):
    scenario = write(tmp_path, "quick.toml", QUICK)
    assert cli.main(["simulate", str(scenario), str(scenario), "-o",
                     str(tmp_path / "x.csv")]) == 2
    assert "output directory" in capsys.readouterr().err
    assert cli.main(["simulate", str(scenario), "-o", str(tmp_path / "x.json")]) == 2
    assert "must be a .csv file (one scenario) or a directory" in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists()


def test_negative_seed_is_refused_before_simulating(tmp_path, capsys):
    scenario = write(tmp_path, "quick.toml", QUICK)
    status = cli.main(["simulate", str(scenario), "-o", str(tmp_path / "q.csv"), "--seed", "-1"])
    assert status == 2
    assert capsys.readouterr().err == "error: --seed: must be >= 0, got -1\n"
    assert not (tmp_path / "q.csv").exists()


def test_missing_fmu_is_one_line(tmp_path, capsys):
    scenario = write(tmp_path, "quick.toml", QUICK)
    status = cli.main(["simulate", str(scenario), "-o", str(tmp_path / "q.csv"),
                       "--fmu", str(tmp_path / "none.fmu")])
    assert status == 2
    assert "none.fmu: no such FMU" in capsys.readouterr().err
    assert not (tmp_path / "q.csv").exists()


def test_console_script_runs_a_shipped_scenario(tmp_path):
    """The installed ``spindlebench`` entry point, on a real shipped example (30 min)."""
    root = Path(__file__).resolve().parents[1]
    executable = Path(sys.executable).with_name("spindlebench")
    result = subprocess.run(
        [str(executable), "simulate", str(root / "scenarios" / "examples" / "quick.toml"),
         "-o", str(tmp_path / "quick.csv")],
        capture_output=True, text=True, timeout=300,
    )
    assert result.returncode == 0, result.stderr
    frame = pd.read_csv(tmp_path / "quick.csv")
    assert frame.time_s.iloc[-1] == 1800.0
    assert frame.T1.iloc[-1] > frame.T1.iloc[0]


def test_progress_bar_path_runs_and_stays_quiet_for_short_runs(tmp_path, capsys):
    from spindlebench.testbench import simulate_scenario

    scenario = write(tmp_path, "quick.toml", QUICK)
    first = simulate_scenario(scenario, tmp_path / "a.csv", progress=True)
    second = simulate_scenario(scenario, tmp_path / "b.csv", progress=False)
    assert first.read_bytes() == second.read_bytes()
    assert "sim-s" not in capsys.readouterr().err  # shown only after 2 s of wall time
