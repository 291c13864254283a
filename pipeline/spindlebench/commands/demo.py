"""``spindlebench demo``: the main job, end to end, with the commands a user would type.

Builds the FMU from ``models/``, simulates the paper's five experiments with it, reruns the
paper's comparison on those synthetic recordings, and reruns it on the real CAIVIAC recording
(when ``../shared/recordings`` is present). Each stage is an ordinary sub-command, so the
printed command lines are a recipe a reader can repeat one by one.
"""

from __future__ import annotations

import argparse
import os
import shlex
from pathlib import Path

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import (
    DEFAULT_FMU,
    MODELS_DIR,
    SCENARIOS_DIR,
    file_kind,
    refuse_shipped,
    shown,
)
from spindlebench.core.provenance import sha256_file
from spindlebench.machines.variants import add_machine_argument
from spindlebench.model import FMU_NAME

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "main job: build the FMU, simulate the paper's experiments, run the comparisons"

#: The FMU the repository (or the installed package) ships, shown as a user would type it.
COMMITTED_FMU = Path(shown(DEFAULT_FMU))
#: The scenarios the paper stage needs: it trains on exp1 and predicts exp2 … exp5.
PAPER_EXPERIMENTS = tuple(f"exp{i}" for i in range(1, 6))


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``demo`` sub-command."""
    parser = subparsers.add_parser(
        "demo",
        help=HELP,
        description=__doc__.split("\n\n")[0] if __doc__ else None,
    )
    parser.add_argument("--out", default="results", help="results folder (default: results)")
    models, scenarios = shown(MODELS_DIR), shown(SCENARIOS_DIR / "paper")
    parser.add_argument("--models", default=models, help=f"Modelica folder (default: {models})")
    parser.add_argument("--scenarios", default=scenarios,
                        help=f"scenario folder (default: {scenarios})")
    add_machine_argument(parser, "machine variant to simulate",
                         "each scenario's machine key, else 'default'")
    parser.set_defaults(func=run)


def _step(argv: list[str]) -> None:
    """Run one sub-command as a user would, echoing the command line first."""
    from spindlebench.commands.main import main

    print(f"\n$ spindlebench {shlex.join(argv)}", flush=True)
    status = main(argv)
    if status:
        raise SystemExit(status)


def check_inputs(models: str | Path, scenarios: str | Path, synthetic: Path,
                 machine: str | None = None) -> None:
    """Check the Modelica folder and the scenario folder before the ~25 s build writes anything.

    The scenarios are loaded and planned as ``simulate`` will, so a missing experiment or a
    typo in exp5.toml is one line naming that file, not an error about an output file later.
    """
    from spindlebench.model.frontend import model_source
    from spindlebench.testbench.batch import plan_batch

    model_source(models)
    folder = Path(scenarios)
    if not folder.is_dir():
        raise SpindlebenchError(f"--scenarios {folder}: no such folder (it needs "
                                f"{', '.join(f'{name}.toml' for name in PAPER_EXPERIMENTS)})")
    missing = [f"{name}.toml" for name in PAPER_EXPERIMENTS
               if not (folder / f"{name}.toml").is_file()]
    if missing:
        raise SpindlebenchError(f"--scenarios {folder}: lacks {', '.join(missing)} (the paper "
                                "stage trains on exp1 and predicts exp2 … exp5)")
    files = sorted(folder.glob("*.toml"))
    plan_batch(files, [synthetic / f"{file.stem}.csv" for file in files], machine)


def check_out(out: Path) -> None:
    """Refuse an ``--out`` the stages could not write, before the build: a file, a FIFO or
    another non-folder there (or on the way), a folder that cannot be written, or a place
    inside the package's shipped files."""
    at = out
    while not at.exists() and at != at.parent:
        at = at.parent
    if at.exists() and not at.is_dir():
        what = file_kind(at)
        raise SpindlebenchError(f"--out {out}: {at} is {what}, not a folder; give a folder")
    if not os.access(at, os.W_OK | os.X_OK):
        raise SpindlebenchError(f"--out {out}: {at} is not writable; give a folder you can "
                                "write")
    refuse_shipped(out / "README.md")


def run(args: argparse.Namespace) -> int:
    """All stages; the results folder gets a README that links what each stage wrote."""
    # pandas and matplotlib only here: ``demo --help`` stays cheap
    from spindlebench.adapters import caiviac
    from spindlebench.formats.recording import read_recording
    from spindlebench.testbench.overview import plot_recording

    out = Path(args.out)
    fmu = out / "fmu" / f"{FMU_NAME}.fmu"
    synthetic = out / "paper"
    machine = getattr(args, "machine", None)
    check_out(out)  # before the ~25 s build, not after it
    check_inputs(args.models, args.scenarios, synthetic, machine)
    _step(["build", "--models", args.models, "--out", str(fmu)])
    same = COMMITTED_FMU.exists() and sha256_file(fmu) == sha256_file(COMMITTED_FMU)
    print(f"rebuilt FMU {'is byte-identical to' if same else 'differs from'} {COMMITTED_FMU}")
    _step(["simulate", args.scenarios, "-o", str(synthetic), "--fmu", str(fmu), "-q",
           *(["--machine", machine] if machine else [])])
    overview = synthetic / "exp1_overview.png"
    plot_recording(read_recording(synthetic / "exp1.csv"), overview,
                   "Synthetic experiment 1: 4000 rpm, January ambient 5.3-10.4 °C")
    _step(["paper", "--recordings", str(synthetic), "--out", str(out / "paper_study")])
    lines = [
        "# spindlebench demo results",
        "",
        f"- FMU built from `{args.models}/`: `fmu/{FMU_NAME}.fmu` "
        f"({'byte-identical to' if same else 'differs from'} the committed `{COMMITTED_FMU}`)",
        "- Synthetic recordings of the paper's five experiments: `paper/exp*.csv` "
        "(+ JSON provenance), overview of experiment 1: `paper/exp1_overview.png`",
        "- The paper's comparison on them: `paper_study/README.md`",
    ]
    source = caiviac.default_source()
    if source.exists():
        real = out / "caiviac"
        _step(["adapt", "caiviac", "--source", str(source), "--out", str(real)])
        _step(["paper", "--recordings", str(real), "--config", str(real / "paper_study.toml"),
               "--out", str(out / "caiviac_study")])
        lines.append("- The same comparison on the real CAIVIAC recording: "
                     "`caiviac_study/README.md`")
    else:
        print(f"\nreal recording not found at {source}: skipped the real-data comparison")
        lines.append(f"- Real-data comparison skipped: {source} not found")
    atomic.write_text(out / "README.md", "\n".join(lines) + "\n")
    print(f"\ndone: see {out / 'README.md'}")
    return 0
