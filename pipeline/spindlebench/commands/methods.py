"""``spindlebench methods``: list the selection methods, inside-cluster choices and regressors.

The names and lines come from ``spindlebench.core.names`` (their one home), so this list, the
``evaluate`` flags and the study files cannot disagree.
"""

from __future__ import annotations

import argparse

from spindlebench.selection.registry import listing

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "list the selection methods, choices inside clusters and regressors"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``methods`` sub-command."""
    parser = subparsers.add_parser(
        "methods", help=HELP,
        description="Every method name evaluate --method, paper_study.toml and sweep study "
        "files accept, with one line each.")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print the listing."""
    print(listing())
    return 0
