"""``spindlebench simulate`` on the command line: outputs, one-line errors, nothing half-written."""

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from conftest import QUICK as QUICK_10S_STEP
from conftest import REPO
from spindlebench.commands import main as cli
from spindlebench.core.paths import DEFAULT_FMU

#: conftest's 10-minute scenario at a 1 s communication step.
QUICK = QUICK_10S_STEP.replace("step_s = 10.0", "step_s = 1.0")


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
    root = REPO
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


def shipped_pair(folder: Path) -> None:
    """The shipped two-part example, 10 + 10 simulated minutes instead of 3 + 3 hours."""
    examples = REPO / "scenarios" / "examples"
    first = (examples / "day1_warmup.toml").read_text(encoding="utf-8")
    second = (examples / "continue_day1.toml").read_text(encoding="utf-8")
    assert "duration_s = 10800" in first and "at_s = 3600" in second
    write(folder, "day1_warmup.toml", first.replace("duration_s = 10800", "duration_s = 600"))
    write(folder, "continue_day1.toml", second.replace("duration_s = 10800", "duration_s = 600")
          .replace("at_s = 3600", "at_s = 300"))


def test_folder_run_continues_from_a_sibling_after_it(tmp_path, capsys):
    """continue_day1 sorts first, yet runs second and starts from the output folder's day 1."""
    shipped_pair(tmp_path / "scen")
    stale = write(tmp_path / "elsewhere", "day1_warmup.json", "{}")  # must not be used
    out = tmp_path / "res"
    assert cli.main(["simulate", str(tmp_path / "scen"), "-o", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert [line.split()[0].rsplit("/", 1)[-1] for line in printed] == [
        "day1_warmup.toml", "continue_day1.toml"]
    day1 = json.loads((out / "day1_warmup.json").read_text())
    second = json.loads((out / "continue_day1.json").read_text())
    assert second["initial_state_from"]["path"] == str(out / "day1_warmup.json")
    assert second["initial_state"]["states_K"] == day1["end_state"]["states_K"]
    assert stale.read_text() == "{}"


def test_one_scenario_continues_from_a_sibling_in_its_output_folder(tmp_path, capsys):
    shipped_pair(tmp_path / "scen")
    alone = ["simulate", str(tmp_path / "scen" / "continue_day1.toml"), "-o"]
    assert cli.main([*alone, str(tmp_path / "res" / "c.csv")]) == 2
    err = capsys.readouterr().err
    missing = tmp_path / "res" / "day1_warmup.json"
    assert err.count("\n") == 1 and "continue_day1.toml: key 'initial.from': no scenario " \
        f"'day1_warmup' in this batch and no recording {missing}" in err
    assert not (tmp_path / "res").exists()
    assert cli.main(["simulate", str(tmp_path / "scen" / "day1_warmup.toml"), "-o",
                     str(tmp_path / "res" / "day1_warmup.csv"), "-q"]) == 0
    assert cli.main([*alone, str(tmp_path / "res" / "c.csv"), "-q"]) == 0
    sidecar = json.loads((tmp_path / "res" / "c.json").read_text())
    assert sidecar["initial_state_from"]["path"] == str(tmp_path / "res" / "day1_warmup.json")


def test_circular_continuation_is_one_line_before_any_simulation(tmp_path, capsys):
    folder = tmp_path / "scen"
    write(folder, "a.toml", QUICK + '[initial]\nkind = "continue"\nfrom = "b"\n')
    write(folder, "b.toml", QUICK + '[initial]\nkind = "continue"\nfrom = "a"\n')
    write(folder, "c.toml", QUICK)
    assert cli.main(["simulate", str(folder), "-o", str(tmp_path / "res")]) == 2
    err = capsys.readouterr().err
    assert err == (f"error: {folder / 'a.toml'}: key 'initial.from': circular continuation: "
                   "a continues from b continues from a\n")
    assert not (tmp_path / "res").exists()


def test_a_path_to_a_batch_output_also_orders_the_batch(tmp_path):
    """from = "../res/b.json" names what b.toml is about to write: b runs first."""
    folder = tmp_path / "scen"
    write(folder, "a.toml", QUICK + '[initial]\nkind = "continue"\nfrom = "../res/b.json"\n')
    write(folder, "b.toml", QUICK)
    assert cli.main(["simulate", str(folder), "-o", str(tmp_path / "res"), "-q"]) == 0
    a = json.loads((tmp_path / "res" / "a.json").read_text())
    b = json.loads((tmp_path / "res" / "b.json").read_text())
    assert a["initial_state"]["states_K"] == b["end_state"]["states_K"]


def test_two_scenarios_writing_one_recording_are_refused(tmp_path, capsys):
    write(tmp_path / "x", "quick.toml", QUICK)
    write(tmp_path / "y", "quick.toml", QUICK)
    assert cli.main(["simulate", str(tmp_path / "x"), str(tmp_path / "y"), "-o",
                     str(tmp_path / "res")]) == 2
    assert "rename one of the two scenario files" in capsys.readouterr().err
    assert not (tmp_path / "res").exists()


def test_shipped_examples_plan_day1_before_its_continuation():
    """The real example folder, planned (not simulated) for a fresh output folder."""
    from spindlebench.testbench.batch import plan_batch

    examples = REPO / "scenarios" / "examples"
    files = sorted(examples.glob("*.toml"))
    out = Path("/nonexistent-output-folder")
    order = [files[i].stem for i in plan_batch(files, [out / f"{f.stem}.csv" for f in files]).order]
    assert sorted(order) == sorted(f.stem for f in files)
    assert order.index("day1_warmup") < order.index("continue_day1")


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        ("[parameters]\nfoo = 1.0\n", "key 'parameters.foo'"),
        ('[initial]\nkind = "continue"\nfrom = "prev.json"\n', "prev.json lacks state"),
    ],
)
def test_a_batch_checks_every_scenario_against_the_fmu_before_simulating(tmp_path, capsys,
                                                                          extra, words):
    """a.toml is fine, b.toml fails only against the FMU: nothing of a is written either."""
    (tmp_path / "prev.json").write_text(
        json.dumps({"end_state": {"states_K": {"front_bearing_T": "abc"}}}), encoding="utf-8")
    folder = tmp_path / "scen"
    write(folder, "a.toml", QUICK)
    write(folder, "b.toml", QUICK + extra.replace("prev.json", "../prev.json"))
    status = cli.main(["simulate", str(folder), "-o", str(tmp_path / "res"), "-q"])
    err = capsys.readouterr().err
    assert status == 2
    assert err.count("\n") == 1 and "b.toml" in err and words in err
    assert not (tmp_path / "res").exists()


def test_a_batch_continuation_from_a_sibling_is_not_read_before_it_is_written(tmp_path):
    """The sibling's old recording in the output folder is bad; the batch rewrites it first."""
    folder = tmp_path / "scen"
    write(folder, "a.toml", QUICK)
    write(folder, "b.toml", QUICK + '[initial]\nkind = "continue"\nfrom = "a"\n')
    write(tmp_path / "res", "a.json", "not json")
    assert cli.main(["simulate", str(folder), "-o", str(tmp_path / "res"), "-q"]) == 0


def test_an_output_with_another_suffix_is_refused(tmp_path, capsys):
    """`-o x.txt` made a folder x.txt/; the README's form is `-o OUT.csv` for one scenario."""
    scenario = write(tmp_path, "quick.toml", QUICK)
    assert cli.main(["simulate", str(scenario), "-o", str(tmp_path / "x.txt")]) == 2
    assert "not a .txt file" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quick.toml"]


def test_an_existing_folder_with_a_dot_is_still_an_output_folder(tmp_path):
    scenario = write(tmp_path, "quick.toml", QUICK)
    (tmp_path / "run.v2").mkdir()
    assert cli.main(["simulate", str(scenario), "-o", str(tmp_path / "run.v2"), "-q"]) == 0
    assert (tmp_path / "run.v2" / "quick.csv").is_file()


def test_an_output_csv_that_is_a_directory_is_refused_before_simulating(tmp_path, capsys):
    scenario = write(tmp_path, "quick.toml", QUICK)
    (tmp_path / "out.csv").mkdir()
    assert cli.main(["simulate", str(scenario), "-o", str(tmp_path / "out.csv")]) == 2
    assert "out.csv: is a directory" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv", "quick.toml"]
