"""A non-editable install works outside the checkout: the wheel carries the FMU, the Modelica
source and the scenarios, and ``spindlebench demo`` finds them from any folder."""

import json
import os
import subprocess
import sys

from conftest import REPO


def test_installed_wheel_runs_the_demo_from_another_folder(tmp_path):
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--target", str(site), str(REPO)], check=True, cwd=tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {**os.environ, "PYTHONPATH": str(site)}
    where = subprocess.run(
        [sys.executable, "-c",
         "import spindlebench.core.paths as p; print(p.__file__, p.DEFAULT_FMU)"],
        check=True, cwd=elsewhere, env=env, capture_output=True, text=True).stdout.split()
    assert where[0].startswith(str(site)), where  # the installed copy, not the checkout
    assert where[1].startswith(str(site)), where
    # the benchmark suites travel too, and their task hash does not depend on where they are
    from spindlebench.studies.benchmark.benchmark_file import load_suite

    code = ("import sys; from spindlebench.studies.benchmark.benchmark_file import "
            "load_suite, SUITES_DIR; "
            "print(SUITES_DIR, load_suite('default', sys.argv[1]).tasks_sha256)")
    suites, digest = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], check=True, cwd=elsewhere, env=env,
        capture_output=True, text=True).stdout.split()
    assert suites.startswith(str(site)) and digest == load_suite("default", tmp_path).tasks_sha256

    result = subprocess.run([str(site / "bin" / "spindlebench"), "demo", "--out", "X"],
                            cwd=elsewhere, env=env, capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-2000:]
    out = elsewhere / "X"
    readme = (out / "README.md").read_text(encoding="utf-8")
    assert f"FMU built from `{site / 'spindlebench' / '_data' / 'models'}/`" in readme
    # the wheel's FMU is the committed one, so the rebuild from its models matches it
    assert "byte-identical to" in readme
    sidecar = json.loads((out / "paper" / "exp1.json").read_text(encoding="utf-8"))
    assert sidecar["scenario"]["path"].startswith(str(site)), sidecar["scenario"]
    assert (out / "paper_study" / "README.md").is_file()
