"""``spindlebench export-ssp``, and the FMU in tools other than spindlebench (issue 24).

The SSP is read back with pyssp-standard and simulated from what it holds alone (FMPy on the
FMU it carries, the parameter sets and start values of its SSV files, the inputs of its CSV);
fmu-manipulation-toolbox reads the same SSP into an FMU container whose own C runtime
imports the FMU (FMI 3.0 co-simulation): the second importer, run by FMPy.
"""

import dataclasses
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import FMU
from fmpy import simulate_fmu
from pyssp_standard.ssd import SSD
from pyssp_standard.ssv import SSV
from spindlebench.commands.main import main
from spindlebench.core.errors import SpindlebenchError
from spindlebench.testbench import runner
from spindlebench.testbench.scenario import InitialState, load_scenario
from spindlebench.testbench.ssp import export_ssp

ROOT = Path(__file__).resolve().parents[2]
EXP1 = ROOT / "scenarios" / "paper" / "exp1.toml"
DURATION_S = 1200.0


@pytest.fixture(scope="module")
def short_exp1(tmp_path_factory):
    """The paper's experiment 1, its first 20 min, as a scenario file."""
    folder = tmp_path_factory.mktemp("ssp")
    text = EXP1.read_text().replace("duration_s = 21600", f"duration_s = {DURATION_S:g}")
    path = folder / "exp1.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def ssp(short_exp1):
    out = short_exp1.parent / "exp1.ssp"
    assert main(["export-ssp", "--machine", "default", "--scenario", str(short_exp1),
                 "-o", str(out)]) == 0
    folder = short_exp1.parent / "unpacked"
    with zipfile.ZipFile(out) as archive:
        archive.extractall(folder)
    return out, folder


def _ssv_values(path: Path) -> dict[str, float]:
    with SSV(path) as ssv:
        return {p["name"]: float(p["type_value"].parameter["value"]) for p in ssv.parameters}


def _converged_runner(scenario):
    with pytest.MonkeyPatch.context() as patch:
        patch.setitem(runner.RELATIVE_TOLERANCE, "hold", 1e-8)
        return runner.co_simulate(dataclasses.replace(scenario, inputs="hold"), FMU)


def test_ssp_holds_the_fmu_the_parameter_sets_and_the_inputs(ssp):
    out, folder = ssp
    with zipfile.ZipFile(out) as archive:
        names = set(archive.namelist())
    assert {"SystemStructure.ssd", "resources/SpindleBench.fmu", "resources/default.ssv",
            "resources/exp1.ssv", "resources/exp1_inputs.csv"} <= names
    assert (folder / "resources" / "SpindleBench.fmu").read_bytes() == FMU.read_bytes()
    with SSD(folder / "SystemStructure.ssd") as ssd:
        assert ssd.version == "1.0"
        component = ssd.system.elements[0]
        assert [b.source for b in component.parameter_bindings] == [
            "resources/default.ssv", "resources/exp1.ssv"]
        assert len(ssd.connections()) == 4 + len(runner.inspect_fmu(FMU).output_names)
    values = _ssv_values(folder / "resources" / "exp1.ssv")
    assert values["cooling_enabled"] == 0.0
    assert values["front_bearing_T"] == pytest.approx(5.3 + 273.15)  # exp1's cold start


def test_the_ssp_alone_simulates_experiment_1_as_the_runner_does(ssp, short_exp1):
    """FMPy's co-simulation of the FMU the SSP carries, with its SSV values as start values
    and its CSV as inputs, within 0.001 K and 0.01 um of the runner (CVode, converged)."""
    _, folder = ssp
    resources = folder / "resources"
    start = {**_ssv_values(resources / "default.ssv"), **_ssv_values(resources / "exp1.ssv")}
    inputs = np.genfromtxt(resources / "exp1_inputs.csv", delimiter=",", names=True)
    names = ["drift_um", "T1_C", "T10_C", "node_front_bearing_C"]
    result = simulate_fmu(str(resources / "SpindleBench.fmu"), fmi_type="CoSimulation",
                          stop_time=DURATION_S, output_interval=1.0, input=inputs,
                          start_values=start, output=names, relative_tolerance=1e-6)[::60]
    ours = _converged_runner(load_scenario(short_exp1))
    for name in names:
        limit = 1e-2 if name.endswith("_um") else 1e-3
        n = min(len(result), len(ours.outputs[name]))
        assert np.max(np.abs(result[name][:n] - ours.outputs[name][:n])) <= limit, name


def test_fmu_manipulation_toolbox_imports_the_fmu_from_the_ssp(ssp, short_exp1, tmp_path):
    """The second FMI 3.0 importer: fmu-manipulation-toolbox reads the SSP's system structure
    and builds a container whose C runtime instantiates and steps SpindleBench.fmu. It ignores
    SSV parameter bindings, so the run starts from the FMU's defaults (every node at 20 °C);
    with exp1's inputs it gives exactly FMPy's co-simulation of the FMU, and agrees with the
    runner started so."""
    out, folder = ssp
    work = tmp_path / "container"
    work.mkdir()
    (work / "exp1.ssp").write_bytes(out.read_bytes())
    subprocess.run([sys.executable, "-c", "from fmu_manipulation_toolbox.cli.fmucontainer "
                    "import fmucontainer; fmucontainer()", "-container", "exp1.ssp", "-fmi",
                    "3"], cwd=work, check=True, capture_output=True)
    container = work / "exp1.fmu"
    inputs = np.genfromtxt(folder / "resources" / "exp1_inputs.csv", delimiter=",", names=True)
    names = ["drift_um", "T1_C", "T10_C", "node_front_bearing_C"]
    theirs = simulate_fmu(str(container), stop_time=DURATION_S, output_interval=1.0,
                          input=inputs, output=names)
    direct = simulate_fmu(str(FMU), fmi_type="CoSimulation", stop_time=DURATION_S,
                          output_interval=1.0, input=inputs, output=names)
    scenario = dataclasses.replace(load_scenario(short_exp1),
                                   initial=InitialState(kind="cold", temperature_C=20.0))
    ours = _converged_runner(scenario)
    assert ours.outputs["drift_um"][-1] != pytest.approx(0.0, abs=1.0)
    for name in names:
        np.testing.assert_array_equal(theirs[name], direct[name])
        limit = 1e-2 if name.endswith("_um") else 1e-3
        n = min(len(theirs[::60]), len(ours.outputs[name]))
        assert np.max(np.abs(theirs[name][::60][:n] - ours.outputs[name][:n])) <= limit, name


def test_export_ssp_refuses_a_wrong_suffix_and_an_unknown_machine(short_exp1, tmp_path):
    with pytest.raises(SpindlebenchError, match=r"\.ssp"):
        export_ssp("default", short_exp1, tmp_path / "x.zip")
    with pytest.raises(SpindlebenchError):
        export_ssp("no-such-machine", short_exp1, tmp_path / "x.ssp")
    assert not list(tmp_path.glob("x.*"))


def test_export_ssp_is_reproducible(short_exp1, tmp_path):
    a = export_ssp("default", short_exp1, tmp_path / "a.ssp")
    b = export_ssp("default", short_exp1, tmp_path / "b.ssp")
    assert a.read_bytes() == b.read_bytes()
