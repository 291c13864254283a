"""A non-editable install works outside the checkout: the wheel carries the FMU, the Modelica
source and the scenarios, and the installed command finds them from any folder.

One real ``pip install`` (no ``-e``) into a folder of its own serves every test here. The
whole ``spindlebench demo`` is not rerun from the wheel (it rebuilt the FMU and ran the five
paper experiments: a minute of CPU): what it needs from the wheel is checked piece by piece:
its defaults point into the wheel, the wheel's data are the checkout's files byte for byte
(so the demo's rebuild from them is the committed FMU, which ``test_fmu_build`` shows for
the checkout's models), and a short simulation through the installed script reads the
wheel's FMU and machine files.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import FMU, MODELS, QUICK, REPO, SCENARIOS

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, Path, dict[str, str]]:
    """(site folder of the install, an unrelated working folder, the environment to use)."""
    root = tmp_path_factory.mktemp("install")
    site = root / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--target", str(site), str(REPO)], check=True, cwd=root)
    elsewhere = root / "elsewhere"
    elsewhere.mkdir()
    return site, elsewhere, {**os.environ, "PYTHONPATH": str(site)}


def files_below(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and "__pycache__" not in p.parts}


def test_the_installed_package_finds_its_data_inside_the_wheel(installed):
    site, elsewhere, env = installed
    where = subprocess.run(
        [sys.executable, "-c",
         "import spindlebench.core.paths as p; print(p.__file__, p.DEFAULT_FMU, p.MODELS_DIR,"
         " p.SCENARIOS_DIR)"],
        check=True, cwd=elsewhere, env=env, capture_output=True, text=True).stdout.split()
    assert all(path.startswith(str(site)) for path in where), where  # not the checkout
    data = site / "spindlebench" / "_data"
    assert Path(where[1]) == data / "fmus" / "SpindleBench.fmu"
    assert Path(where[1]).read_bytes() == FMU.read_bytes()
    assert files_below(Path(where[2])) == files_below(MODELS)
    assert files_below(Path(where[3])) == files_below(SCENARIOS)


def test_the_installed_demo_defaults_to_the_wheels_models_and_scenarios(installed):
    site, elsewhere, env = installed
    result = subprocess.run([str(site / "bin" / "spindlebench"), "demo", "--help"],
                            cwd=elsewhere, env={**env, "COLUMNS": "10000"},  # no wrapping
                            capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr[-2000:]
    text = result.stdout
    data = site / "spindlebench" / "_data"
    assert f"(default: {data / 'models'})" in text, text
    assert f"(default: {data / 'scenarios' / 'paper'})" in text, text


def test_the_installed_command_simulates_with_the_wheels_fmu_and_machine(installed):
    site, elsewhere, env = installed
    # a machine by name: found in the wheel's scenarios/machines/, not in the checkout's
    (elsewhere / "quick.toml").write_text('machine = "motor-spindle"\n' + QUICK,
                                          encoding="utf-8")
    result = subprocess.run([str(site / "bin" / "spindlebench"), "simulate", "quick.toml",
                             "-o", "X/quick.csv", "-q"],
                            cwd=elsewhere, env=env, capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr[-2000:]
    sidecar = json.loads((elsewhere / "X" / "quick.json").read_text(encoding="utf-8"))
    data = site / "spindlebench" / "_data"
    assert sidecar["fmu"]["path"] == str(data / "fmus" / "SpindleBench.fmu"), sidecar["fmu"]
    assert sidecar["machine"]["name"] == "motor-spindle", sidecar["machine"]
    assert (elsewhere / "X" / "quick.csv").stat().st_size > 0


def test_the_benchmark_suites_travel_and_their_task_hash_does_not_depend_on_the_folder(
        installed, tmp_path):
    from spindlebench.studies.benchmark.benchmark_file import load_suite

    site, elsewhere, env = installed
    code = ("import sys; from spindlebench.studies.benchmark.benchmark_file import "
            "load_suite, SUITES_DIR; "
            "print(SUITES_DIR, load_suite('default', sys.argv[1]).tasks_sha256)")
    suites, digest = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], check=True, cwd=elsewhere, env=env,
        capture_output=True, text=True).stdout.split()
    assert suites.startswith(str(site)) and digest == load_suite("default", tmp_path).tasks_sha256
