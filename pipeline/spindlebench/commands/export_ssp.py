"""``spindlebench export-ssp``: the FMU, a machine's parameter set and a scenario as an SSP file
(``testbench.ssp`` writes it)."""

from __future__ import annotations

import argparse

from spindlebench.testbench.ssp import export_ssp

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "write an SSP file: the FMU, a machine's parameter set and a scenario's inputs"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``export-ssp`` sub-command."""
    parser = subparsers.add_parser(
        "export-ssp",
        help=HELP,
        description="Write an SSP 1.0 archive (SystemStructure.ssd, the FMU, the machine's "
        "parameters as an SSV, and with --scenario its parameters, start state and inputs) "
        "for SSP tools.",
    )
    parser.add_argument("--machine", required=True,
                        help="machine name (scenarios/machines/NAME.toml) or a .toml path")
    parser.add_argument("--scenario", default=None, help="scenario TOML file (optional)")
    parser.add_argument("--fmu", default=None, help="FMU (default: fmus/SpindleBench.fmu)")
    parser.add_argument("-o", "--out", required=True, help="output file (.ssp)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Write the SSP and say where."""
    path = export_ssp(args.machine, args.scenario, args.out, args.fmu)
    print(f"wrote {path}")
    return 0
