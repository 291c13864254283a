"""``spindlebench build``: Modelica package in ``models/`` → ``fmus/SpindleBench.fmu``.

A build with a non-default ``--segments N`` goes to ``fmus/SpindleBench_<N>seg.fmu`` unless
``--out`` names a ``.fmu`` file, so the committed default model is only replaced by itself.
The build itself is ``spindlebench.model.build.build_fmu``.
"""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path
from typing import Any

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU, MODELS_DIR, allow_shipped, refuse_shipped
from spindlebench.core.progress import Stages, for_terminal
from spindlebench.core.provenance import sha256_file
from spindlebench.formats.recording import NODE_PREFIX
from spindlebench.model import DEFAULT_SEGMENTS, FMU_NAME, MAX_SEGMENTS

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "build the FMU from the Modelica model (models/ -> fmus/)"


def build_fmu(model_dir: str | Path, out_path: Path, **options: Any) -> Path:
    """``model.build.build_fmu``, imported on the first build (pymoca, CasADi and SciPy: not
    for ``build --help``)."""
    from spindlebench.model.build import build_fmu as build

    return build(model_dir, out_path, **options)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``build`` sub-command."""
    parser = subparsers.add_parser(
        "build",
        help=HELP,
        description="Translate models/SpindleBench.mo with pymoca, causalise it, export an "
        "FMI 3.0 model-exchange FMU with CasADi and compile it with gcc (or $CC).",
    )
    parser.add_argument(
        "--models", default="models", help="Modelica source folder (default: models)"
    )
    parser.add_argument(
        "--segments",
        type=int,
        default=DEFAULT_SEGMENTS,
        help=f"segments per large part, 2 to {MAX_SEGMENTS} (default: {DEFAULT_SEGMENTS})",
    )
    parser.add_argument(
        "--out",
        default="fmus",
        help=f"output folder, or a path ending in .fmu (default: fmus; in a folder the file "
        f"is {FMU_NAME}.fmu, or {FMU_NAME}_<N>seg.fmu for a non-default --segments N)",
    )
    parser.add_argument(
        "--cross-check",
        metavar="DIR",
        default=None,
        help="also write the FMI Cross-Check folders (me and cs: the FMU, reference results, "
        "options and inputs of the paper's experiment 1) under DIR",
    )
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no step lines on stderr while it builds")
    parser.set_defaults(func=run)


def output_path(out: str | Path, segments: int) -> Path:
    """Where ``build --out OUT --segments N`` writes.

    A path ending in ``.fmu`` is taken as given. In a folder, only the default segment count
    is ``SpindleBench.fmu``: every default ``simulate``, ``sweep`` and ``place`` uses
    ``fmus/SpindleBench.fmu``, so a coarse experiment must not silently replace it.
    """
    out = Path(out)
    if out.suffix == ".fmu":
        return out
    if segments == DEFAULT_SEGMENTS:
        return out / f"{FMU_NAME}.fmu"
    return out / f"{FMU_NAME}_{segments}seg.fmu"


def run(args: argparse.Namespace) -> int:
    """Build the FMU and print where it went (and, for a variant, how to use it)."""
    if not 2 <= args.segments <= MAX_SEGMENTS:
        raise SpindlebenchError(f"--segments: must be from 2 to {MAX_SEGMENTS}, got "
                                f"{args.segments}")
    target = output_path(args.out, args.segments)
    # 'spindlebench build' rebuilds the committed FMU from its own sources (same bytes);
    # anything else (other segments, other models) must not replace it unasked, and the
    # refusal comes now, not after minutes of building
    own = (args.segments == DEFAULT_SEGMENTS
           and Path(args.models).resolve() == MODELS_DIR.resolve())
    stages = Stages("build", enabled=for_terminal(args.quiet))
    with allow_shipped(DEFAULT_FMU) if own else contextlib.nullcontext():
        refuse_shipped(target)
        path = build_fmu(args.models, target, segments=args.segments, say=stages)
    elapsed = stages.seconds
    from fmpy import read_model_description

    description = read_model_description(str(path))
    nodes = sum(v.name.startswith(NODE_PREFIX) for v in description.modelVariables)
    print(
        f"built {path}: {args.segments} segments per part, {nodes} nodes, "
        f"{len(description.derivatives)} states, {elapsed:.1f} s in all, "
        f"sha256 {sha256_file(path)[:12]}"
    )
    if getattr(args, "cross_check", None):
        from spindlebench.core.paths import SCENARIOS_DIR
        from spindlebench.testbench.cross_check import write_cross_check

        for folder in write_cross_check(path, args.cross_check,
                                        SCENARIOS_DIR / "paper" / "exp1.toml"):
            print(f"cross-check folder {folder}")
    if path.name != f"{FMU_NAME}.fmu":
        print(f"the default {FMU_NAME}.fmu is unchanged; to use this build: 'spindlebench "
              f"simulate SCENARIO.toml -o OUT.csv --fmu {path}', or in a sweep/place study "
              f"file's [study] table fmu = \"<{path} relative to the study file>\"")
    return 0
