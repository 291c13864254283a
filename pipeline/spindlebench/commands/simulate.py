"""``spindlebench simulate``: scenario file(s) → recording(s) (CSV + JSON sidecar).

One file and ``-o OUT.csv`` names the recording; several (or folders of them) go into an
output folder. The batch is validated whole before the first run (``testbench.batch``), and
each run is ``testbench.simulate.record``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_output
from spindlebench.core.listflags import expand_folders
from spindlebench.core.paths import DEFAULT_FMU, refuse_shipped
from spindlebench.formats.recording import (
    write_recording,
)
from spindlebench.machines.variants import add_machine_argument
from spindlebench.testbench.scenario import MeasuredAmbient

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "co-simulate scenario(s) with the FMU into recording(s)"


def _scenario_files(arguments: list[str]) -> list[Path]:
    return expand_folders(arguments, ".toml", "scenario")


def _output_targets(files: list[Path], out: Path) -> list[Path]:
    """The CSV each scenario is written to, or one error line about ``-o``.

    ``simulate SCENARIO.toml -o OUT.csv`` names the recording; any other ``-o`` is a folder
    that gets ``<scenario>.csv`` per scenario. A folder name with a suffix (``-o x.txt``) is
    taken for a mistyped file name unless that folder already exists.
    """
    suffix = out.suffix.lower()
    single = len(files) == 1 and suffix == ".csv"
    if not single and suffix == ".csv":
        raise SpindlebenchError(f"{out}: several scenarios need an output directory, not a "
                                ".csv file")
    if not single and (out.is_file() or (suffix and not out.is_dir())):
        raise SpindlebenchError(f"{out}: -o must be a .csv file (one scenario) or a directory "
                                f"(a name without a suffix), not a {suffix or 'plain'} file")
    targets = [out if single else out / f"{scenario.stem}.csv" for scenario in files]
    for target in targets:
        for path in (target, target.with_suffix(".json")):
            if path.is_dir():
                raise SpindlebenchError(f"{path}: is a directory; the recording needs it as "
                                        "a file name (choose another -o)")
            refuse_shipped(path)  # not a shipped file: refused before any simulation
    return targets


def run(args: argparse.Namespace) -> int:
    """Simulate every scenario given; one file → ``-o`` is the CSV, several → a directory."""
    # the runner (FMPy, pandas, SciPy) only here: ``simulate --help`` stays cheap
    from spindlebench.testbench.batch import check_batch, plan_batch
    from spindlebench.testbench.simulate import record_run

    if args.seed is not None and args.seed < 0:
        raise SpindlebenchError(f"--seed: must be >= 0, got {args.seed}")
    files = _scenario_files(args.scenarios)
    check_output(args.output, "-o", folder=True)  # not the root folder, a device or a FIFO
    targets = _output_targets(files, Path(args.output))
    if args.plot:
        for target in targets:
            if target.with_suffix(".png").is_dir():
                raise SpindlebenchError(f"{target.with_suffix('.png')}: is a directory; "
                                        "--plot writes the figure there (choose another -o)")
    # validate all first: a typo in the last file should cost nothing
    plan = plan_batch(files, targets, args.machine)
    inputs = [*files, *(s.ambient.file for s in plan.scenarios if isinstance(s.ambient,
                                                                             MeasuredAmbient)),
              *(s.initial.from_file for s, ours in zip(plan.scenarios, plan.state_from_batch,
                                                        strict=True)
                if s.initial.from_file and not ours),  # an earlier run's sidecar is ours
              *([args.fmu] if args.fmu else [])]
    for target in targets:  # the recording, its sidecar, its figure: none over an input
        for written in (target, target.with_suffix(".json"),
                        *([target.with_suffix(".png")] if args.plot else [])):
            check_output(written, "-o", inputs)
    check_batch(plan, args.fmu)
    show_progress = not args.quiet and sys.stderr.isatty()
    continued = {p for p in plan.producers if p is not None}
    saved: dict[int, bytes] = {}  # end FMU states of the runs that a later run continues
    for i in plan.order:
        producer = plan.producers[i] if plan.producers else None
        frame, sidecar, end = record_run(
            plan.scenarios[i], args.fmu, args.seed, show_progress,
            start_fmu_state=None if producer is None else saved.get(producer),
            save_end_state=i in continued)
        if end is not None:
            saved[i] = end
        written = write_recording(targets[i], frame, sidecar)
        extras = [written.with_suffix(".json").name]
        if args.plot:
            from spindlebench.testbench.overview import plot_recording  # matplotlib: only here

            frame.attrs["path"] = str(written)
            plot_recording(frame, written.with_suffix(".png"), files[i].stem)
            extras.append(written.with_suffix(".png").name)
        if not args.quiet:
            print(f"{files[i]} -> {written} (+ {', '.join(extras)})")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``simulate`` sub-command."""
    parser = subparsers.add_parser(
        "simulate",
        help=HELP,
        description="Co-simulate scenario TOML files with the SpindleBench FMU and write "
        "recordings: a CSV (measured T1..T20, drift_um, drivers, noise-free truth) and a "
        "JSON sidecar with provenance and the end state.",
    )
    parser.add_argument("scenarios", nargs="+", metavar="SCENARIO",
                        help="scenario .toml file(s) or directories of them")
    parser.add_argument("-o", "--output", required=True, metavar="OUT",
                        help="output .csv for one scenario, else an output directory")
    parser.add_argument("--fmu", type=Path, default=None,
                        help=f"FMU to simulate (default: {DEFAULT_FMU.name} in fmus/). Loading "
                        "an FMU runs its native code: give only FMUs you built or trust (its zip "
                        "is checked first: names, sizes, binary, instantiation token)")
    parser.add_argument("--seed", type=int, default=None,
                        help="random seed of the sensor model (default: the scenario's)")
    add_machine_argument(parser, "machine variant for every scenario",
                         "each scenario's machine key, else 'default'")
    parser.add_argument("--plot", action="store_true",
                        help="also draw each recording (as `spindlebench plot`) into "
                        "<recording>.png beside it")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no progress bar, no summary")
    parser.set_defaults(func=run)
