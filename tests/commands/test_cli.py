"""The command-line shell: version, help, and one-line errors."""

import subprocess
import sys

from spindlebench import __version__
from spindlebench.commands import main as cli


def test_version_flag_prints_version(capsys):
    try:
        cli.main(["--version"])
    except SystemExit as exc:
        assert exc.code == 0
    assert __version__ in capsys.readouterr().out


def test_console_script_is_installed():
    """The installed ``spindlebench`` entry point (not ``python -m``) lists every command."""
    from pathlib import Path

    executable = Path(sys.executable).with_name("spindlebench")
    result = subprocess.run([str(executable), "--help"], capture_output=True, text=True)
    assert result.returncode == 0
    assert result.stdout.startswith("usage: spindlebench")
    for command in ("build", "simulate", "evaluate", "paper", "adapt", "sweep", "place", "demo"):
        assert f"    {command} " in result.stdout, command


def test_unwritable_output_is_one_line_error(tmp_path, capsys):
    """An output folder that cannot be created (a file is in the way) is reported in one
    line naming the path, with status 2 and no traceback, and nothing is written."""
    from selection_data import synthetic_experiment

    train, test = tmp_path / "a.csv", tmp_path / "b.csv"
    synthetic_experiment(0).to_csv(train, index=False)
    synthetic_experiment(1).to_csv(test, index=False)
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a folder")
    before = sorted(p.name for p in tmp_path.iterdir())
    status = cli.main(["evaluate", "--train", str(train), "--test", str(test), "--target",
                       "drift_um", "--clusters", "2", "--json", str(blocker / "out.json")])
    err = capsys.readouterr().err
    assert status == 2
    assert err.startswith("error: ") and err.count("\n") == 1
    assert str(blocker) in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert blocker.read_text() == "a file, not a folder"


def test_usage_mistake_is_one_error_line(capsys):
    """A bad flag value is reported like every other bad input: one line, status 2."""
    try:
        status = cli.main(["evaluate", "--train", "a.csv", "--test", "b.csv", "--target",
                           "drift_um", "--clusters", "two"])
    except SystemExit as exc:
        status = exc.code
    err = capsys.readouterr().err
    assert status == 2
    assert err.count("\n") == 1
    assert err.startswith("error: spindlebench evaluate: argument --clusters: invalid int")


def test_warnings_are_one_line_each(capsys):
    """A warning from a sub-command prints as one 'warning:' line, not Python's source echo."""
    import warnings

    from spindlebench.core.console import print_warning

    with warnings.catch_warnings():
        warnings.showwarning = print_warning
        warnings.warn("cluster ties:\n  exactly 3 clusters impossible", UserWarning, stacklevel=1)
    err = capsys.readouterr().err
    assert err == "warning: cluster ties: exactly 3 clusters impossible\n"


def _status_and_err(capsys, argv):
    try:
        status = cli.main(argv)
    except SystemExit as exc:
        status = exc.code
    return status, capsys.readouterr().err


def test_unknown_argument_after_a_command_points_to_that_commands_help(capsys):
    """Left-over words after a sub-command are its mistake: the hint names its --help (which
    lists its flags), not the top level's."""
    status, err = _status_and_err(capsys, ["paper", "--recordings", "r", "--bogus", "1"])
    assert status == 2 and err.count("\n") == 1
    assert err == ("error: spindlebench paper: unrecognized arguments: --bogus 1 "
                   "(see 'spindlebench paper --help')\n")
    status, err = _status_and_err(capsys, ["--bogus", "paper", "--recordings", "r"])
    assert status == 2
    assert err.startswith("error: spindlebench: unrecognized arguments: --bogus (see "
                          "'spindlebench --help')")


def test_an_error_message_with_newlines_is_printed_as_one_line(tmp_path, capsys):
    """A message that embeds another library's (pandas: 'Error tokenizing data. C error:
    Expected 23 fields in line 4, saw 24\\n') is still one line."""
    from spindlebench.adapters import caiviac

    path = tmp_path / "data.csv"
    header = ",".join(caiviac.SOURCE_COLUMNS)
    row = ",".join(["0"] * len(caiviac.SOURCE_COLUMNS))
    path.write_text(f"{header}\n{row}\n{row}\n{row},7\n{row}\n")
    status = cli.main(["adapt", "caiviac", "--source", str(path), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert status == 2
    assert err.startswith(f"error: {path}: not a readable CSV") and err.count("\n") == 1
    assert "line 4, saw 24)" in err


def test_any_error_with_a_newline_is_collapsed(capsys):
    """The collapse is in cli, for every sub-command, not in each message."""
    import argparse

    from spindlebench.core.errors import SpindlebenchError

    def fail(_args):
        raise SpindlebenchError("first part\n  second part\r\n")

    assert cli._run(argparse.Namespace(func=fail)) == 2
    assert capsys.readouterr().err == "error: first part second part\n"
