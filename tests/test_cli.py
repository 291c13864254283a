"""The command-line shell: version, help, and one-line errors."""

import subprocess
import sys

from spindlebench import __version__, cli


def test_version_flag_prints_version(capsys):
    try:
        cli.main(["--version"])
    except SystemExit as exc:
        assert exc.code == 0
    assert __version__ in capsys.readouterr().out


def test_console_script_is_installed():
    result = subprocess.run(
        [sys.executable, "-m", "spindlebench.cli", "--help"], capture_output=True, text=True
    )
    assert result.returncode == 0
    assert "spindlebench" in result.stdout
