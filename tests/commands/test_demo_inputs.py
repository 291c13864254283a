"""``spindlebench demo`` checks its inputs before the ~25 s FMU build writes anything."""

import shutil
from pathlib import Path

import pytest
from conftest import REPO
from spindlebench.commands import main as cli

ROOT = REPO
PAPER = ROOT / "scenarios" / "paper"


@pytest.fixture
def no_build(monkeypatch):
    """Fail loudly if the demo gets as far as building."""
    from spindlebench.commands import demo

    def refuse(argv):
        raise AssertionError(f"demo ran {argv} before checking its inputs")

    monkeypatch.setattr(demo, "_step", refuse)


def run_demo(tmp_path: Path, scenarios: Path, capsys) -> str:
    status = cli.main(["demo", "--models", str(ROOT / "models"), "--scenarios", str(scenarios),
                       "--out", str(tmp_path / "o")])
    assert status == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert not (tmp_path / "o").exists()
    return err


def test_missing_scenario_folder_is_refused_before_building(tmp_path, capsys, no_build):
    err = run_demo(tmp_path, tmp_path / "nope", capsys)
    assert "--scenarios" in err and "nope: no such folder" in err


def test_a_folder_without_the_paper_experiments_is_refused(tmp_path, capsys, no_build):
    folder = tmp_path / "scen"
    folder.mkdir()
    for name in ("exp1.toml", "exp2.toml", "exp4.toml"):
        shutil.copy(PAPER / name, folder / name)
    err = run_demo(tmp_path, folder, capsys)
    assert "lacks exp3.toml, exp5.toml" in err


def test_a_bad_scenario_is_refused_before_building(tmp_path, capsys, no_build):
    folder = tmp_path / "scen"
    shutil.copytree(PAPER, folder)
    exp5 = folder / "exp5.toml"
    exp5.write_text("colour = 1\n" + exp5.read_text(encoding="utf-8"), encoding="utf-8")
    err = run_demo(tmp_path, folder, capsys)
    assert "exp5.toml: key 'colour'" in err
