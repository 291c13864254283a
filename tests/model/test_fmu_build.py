"""Building the FMU from models/: same as the committed one, coarse ~ fine, clear failures.

The rebuild is the slowest test of the suite (translation, code generation and a gcc compile).
"""

import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Model
from spindlebench.commands.build import output_path
from spindlebench.core.errors import SpindlebenchError
from spindlebench.model.build import build_fmu
from spindlebench.model.cold_start import cold_start, rise
from spindlebench.model.equations import explicit_ode

ROOT = REPO
MODELS = ROOT / "models"
COMMITTED = ROOT / "fmus" / "SpindleBench.fmu"


@pytest.fixture(scope="module")
def rebuilt(tmp_path_factory):
    return build_fmu(MODELS, tmp_path_factory.mktemp("default") / "SpindleBench.fmu")


@pytest.fixture(scope="module")
def coarse(tmp_path_factory):
    return build_fmu(MODELS, tmp_path_factory.mktemp("coarse") / "SpindleBench.fmu", segments=6)


def archive_text(fmu, name):
    with zipfile.ZipFile(fmu) as archive:
        return archive.read(name).decode()


@pytest.mark.slow
@pytest.mark.fmu_build
@pytest.mark.parametrize(
    "member",
    ["modelDescription.xml", "sources/SpindleBench.c", "sources/SpindleBench_wrap.c"],
)
def test_rebuild_has_the_committed_description_and_sources(rebuilt, member):
    assert archive_text(rebuilt, member) == archive_text(COMMITTED, member), (
        f"fmus/SpindleBench.fmu is stale: run 'spindlebench build' ({member} differs)"
    )


@pytest.mark.slow
@pytest.mark.fmu_build
def test_rebuild_gives_the_committed_outputs(rebuilt):
    ours = cold_start(rebuilt, speed_rpm=4000.0, hours=2.0, ambient_C=10.0, output_interval_s=300.0)
    committed = cold_start(
        COMMITTED, speed_rpm=4000.0, hours=2.0, ambient_C=10.0, output_interval_s=300.0
    )
    assert list(ours.columns) == list(committed.columns)
    np.testing.assert_allclose(ours.to_numpy(), committed.to_numpy(), rtol=1e-9, atol=1e-9)


@pytest.mark.slow
@pytest.mark.fmu_build
def test_coarse_and_default_builds_agree_on_drift(coarse):
    fine = cold_start(
        COMMITTED, speed_rpm=4000.0, hours=3.0, ambient_C=10.0, output_interval_s=300.0
    )
    rough = cold_start(coarse, speed_rpm=4000.0, hours=3.0, ambient_C=10.0, output_interval_s=300.0)
    assert sum(c.startswith("node_") for c in rough.columns) < sum(
        c.startswith("node_") for c in fine.columns
    )
    for minutes in (60, 180):
        assert rise(rough, "drift_um", minutes) == pytest.approx(
            rise(fine, "drift_um", minutes), rel=0.05
        )


@pytest.mark.slow  # a Modelica translation
def test_explicit_ode_is_what_the_fmu_computes():
    ode = explicit_ode(MODELS)
    rng = np.random.default_rng(7)
    x = 283.15 + 15.0 * rng.random(len(ode.states))
    u = np.array([3500.0, 1200.0, 800.0, 14.0])
    p = ode.parameter_vector()
    xdot, y = (np.array(v).ravel() for v in ode.ode(x, u, p))

    description = read_model_description(str(COMMITTED))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    unzipped = extract(str(COMMITTED))
    fmu = FMU3Model(
        guid=description.guid,
        unzipDirectory=unzipped,
        modelIdentifier=description.modelExchange.modelIdentifier,
        instanceName="check",
    )
    fmu.instantiate()
    fmu.setFloat64([vr[n] for n in ode.states], list(x))
    fmu.setFloat64([vr[n] for n in ode.inputs], list(u))
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu_y = np.array(fmu.getFloat64([vr[n] for n in ode.outputs], len(ode.outputs)))
    derivative_vrs = [d.variable.valueReference for d in description.derivatives]
    fmu_xdot = np.array(fmu.getFloat64(derivative_vrs, len(derivative_vrs)))
    fmu.terminate()
    fmu.freeInstance()
    states_in_fmu_order = [d.variable.derivative.name for d in description.derivatives]
    assert states_in_fmu_order == ode.states
    np.testing.assert_allclose(fmu_y, y, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(fmu_xdot, xdot, rtol=1e-12, atol=1e-15)


def test_missing_compiler_is_reported(tmp_path, monkeypatch):
    monkeypatch.setenv("CC", "no-such-cc")
    with pytest.raises(SpindlebenchError, match="no C compiler: 'no-such-cc' is not on PATH"):
        build_fmu(MODELS, tmp_path / "x.fmu")
    monkeypatch.delenv("CC")
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(SpindlebenchError, match="no C compiler: 'gcc'"):
        build_fmu(MODELS, tmp_path / "x.fmu")
    assert not (tmp_path / "x.fmu").exists()


def test_build_command_rejects_bad_segments_in_one_line(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "spindlebench.commands.main",
            "build",
            "--segments",
            "1",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0
    assert "--segments" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_build_command_refuses_too_many_segments_before_building(tmp_path, capsys):
    """--segments 100000 ran for minutes; the model is meant for 2 to 50."""
    from spindlebench.commands import main as cli

    assert cli.main(["build", "--segments", "100000", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err == "error: --segments: must be from 2 to 50, got 100000\n"
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(SpindlebenchError, match="from 2 to 50"):
        build_fmu(MODELS, tmp_path / "x.fmu", segments=51)


def test_build_stops_at_the_first_modelica_problem_with_its_line(tmp_path):
    text = (MODELS / "SpindleBench.mo").read_text()
    broken = text.replace(
        'Real T(unit = "K") "Port temperature";', 'Real T(unit = "K") "Port temperature"', 1
    )
    assert broken != text
    (tmp_path / "SpindleBench.mo").write_text(broken)
    line = next(i for i, s in enumerate(broken.splitlines(), 1) if "flow Real Q_flow" in s)
    with pytest.raises(
        SpindlebenchError, match=rf"^{tmp_path / 'SpindleBench.mo'}:{line}:\d+: unexpected"
    ):
        build_fmu(tmp_path, tmp_path / "out.fmu")
    assert not (tmp_path / "out.fmu").exists()


@pytest.mark.parametrize(
    ("out", "segments", "written"),
    [
        ("fmus", 12, "fmus/SpindleBench.fmu"),
        ("fmus", 6, "fmus/SpindleBench_6seg.fmu"),
        ("elsewhere", 24, "elsewhere/SpindleBench_24seg.fmu"),
        ("elsewhere/coarse.fmu", 6, "elsewhere/coarse.fmu"),
    ],
)
def test_only_the_default_segment_count_is_written_as_spindlebench_fmu(out, segments, written):
    assert output_path(out, segments) == Path(written)


@pytest.mark.slow
@pytest.mark.fmu_build
def test_build_with_other_segments_keeps_the_default_fmu(coarse, tmp_path, monkeypatch, capsys):
    """`spindlebench build --segments 6` (no --out) next to fmus/SpindleBench.fmu leaves it be.

    The compile itself is the `coarse` fixture's; here only where the command puts it.
    """
    import shutil

    from spindlebench.commands import build
    from spindlebench.commands import main as cli

    def fake_build(model_dir, out_path, segments, **_):
        assert segments == 6
        Path(out_path).parent.mkdir(parents=True, exist_ok=True)
        return Path(shutil.copyfile(coarse, out_path))

    monkeypatch.chdir(tmp_path)
    (tmp_path / "fmus").mkdir()
    default = tmp_path / "fmus" / "SpindleBench.fmu"
    default.write_bytes(COMMITTED.read_bytes())
    monkeypatch.setattr(build, "build_fmu", fake_build)
    assert cli.main(["build", "--segments", "6"]) == 0
    printed = capsys.readouterr().out
    assert default.read_bytes() == COMMITTED.read_bytes()
    assert (tmp_path / "fmus" / "SpindleBench_6seg.fmu").read_bytes() == coarse.read_bytes()
    assert "built fmus/SpindleBench_6seg.fmu: 6 segments" in printed
    assert "--fmu fmus/SpindleBench_6seg.fmu" in printed


def test_variant_builds_are_not_committed():
    if not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    ignored = subprocess.run(
        ["git", "check-ignore", "-q", "fmus/SpindleBench_6seg.fmu"], cwd=ROOT, check=False
    )
    assert ignored.returncode == 0, ".gitignore should hold fmus/SpindleBench_*seg.fmu"
