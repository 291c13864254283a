"""``spindlebench build --cross-check DIR``: the FMI Cross-Check layout, validated by FMPy."""

import argparse
from pathlib import Path

import numpy as np
import pytest
from conftest import FMU
from fmpy import simulate_fmu
from fmpy.cross_check.validate_vendor_repo import read_csv, validate_test_fmu
from fmpy.util import read_ref_opt_file
from spindlebench.commands import build
from spindlebench.testbench.cross_check import write_cross_check

ROOT = Path(__file__).resolve().parents[2]
EXP1 = ROOT / "scenarios" / "paper" / "exp1.toml"


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    return write_cross_check(FMU, tmp_path_factory.mktemp("xc"), EXP1)


@pytest.mark.slow
def test_both_interfaces_pass_fmpy_s_cross_check_validator(folders):
    kinds = sorted(folder.parts[-5] for folder in folders)
    assert kinds == ["cs", "me"]
    for folder in folders:
        assert validate_test_fmu(str(folder)) == []
        assert folder.parts[-6] == "3.0"
        options = read_ref_opt_file(str(folder / "SpindleBench_ref.opt"))
        assert options["StopTime"] == 21600.0 and options["StepSize"] == 1.0


@pytest.mark.slow
def test_fmpy_co_simulation_of_the_cs_folder_matches_the_reference(folders):
    """What a cross-check importer does with the cs folder: default start values, the inputs
    file, the options' step (FMPy's communication step is its output interval); the result
    within 0.001 K and 0.01 um of the reference."""
    folder = next(f for f in folders if f.parts[-5] == "cs")
    reference = read_csv(str(folder / "SpindleBench_ref.csv"))
    inputs = read_csv(str(folder / "SpindleBench_in.csv"))
    assert reference["drift_um"][-1] > 10.0  # the reference really heats up
    options = read_ref_opt_file(str(folder / "SpindleBench_ref.opt"))
    result = simulate_fmu(str(folder / "SpindleBench.fmu"), fmi_type="CoSimulation",
                          stop_time=options["StopTime"], step_size=options["StepSize"],
                          relative_tolerance=options["RelTol"], input=inputs,
                          output_interval=options["StepSize"],
                          output=list(reference.dtype.names[1:]))[::60]
    n = min(len(result), len(reference))
    np.testing.assert_array_equal(result["time"][:n], reference["time"][:n])
    for name in reference.dtype.names[1:]:
        limit = 1e-2 if name.endswith("_um") else 1e-3
        assert np.max(np.abs(result[name][:n] - reference[name][:n])) <= limit, name


def test_build_option_writes_the_folders_after_building(tmp_path, monkeypatch, capsys):
    """``build --cross-check DIR`` builds as usual, then writes the layout for the new FMU."""
    calls = []
    monkeypatch.setattr(build, "build_fmu", lambda models, target, segments, **_: FMU)
    monkeypatch.setattr("spindlebench.testbench.cross_check.write_cross_check",
                        lambda fmu, out, scenario: calls.append((fmu, out, scenario)) or [])
    args = argparse.Namespace(models="models", segments=12, out=str(tmp_path),
                              cross_check=str(tmp_path / "xc"), quiet=True)
    assert build.run(args) == 0
    assert calls == [(FMU, str(tmp_path / "xc"), calls[0][2])]
    assert calls[0][2].name == "exp1.toml"
