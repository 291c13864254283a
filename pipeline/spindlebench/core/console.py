"""Console lines: every error and warning the user sees is one line.

The command line (``commands.main``) and the study workers (``studies.running.executor``)
both print warnings this way; it lives here, on the ground floor, so a worker does not import
the command line to print one.
"""

from __future__ import annotations

import sys


def one_line(text: str) -> str:
    """``text`` with every run of whitespace (newlines of an embedded pandas or TOML message)
    as one space: an error is one line, whoever wrote the message."""
    return " ".join(text.split())


def print_warning(message: Warning | str, category: type[Warning], filename: str,
                  lineno: int, file=None, line: str | None = None) -> None:
    """A warning as one ``warning:`` line, like errors (not Python's two lines of source)."""
    print(f"warning: {one_line(str(message))}", file=sys.stderr)


def one_line_error(exc: BaseException) -> str:
    """``Type: message`` on one line, short enough for a results table."""
    message = " ".join(str(exc).split()) or "(no message)"
    if len(message) > 300:
        message = message[:297] + "..."
    return f"{type(exc).__name__}: {message}"
