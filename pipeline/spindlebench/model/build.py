"""The build: Modelica package in ``models/`` → an FMU (the command is ``commands.build``).

A build with a non-default ``--segments N`` goes to ``fmus/SpindleBench_<N>seg.fmu`` unless
``--out`` names a ``.fmu`` file, so the committed default model is only replaced by itself.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from spindlebench.core.errors import SpindlebenchError
from spindlebench.model import DEFAULT_SEGMENTS, FMU_NAME
from spindlebench.model.equations import build_explicit_ode
from spindlebench.model.fmu_export import export_fmu, find_compiler
from spindlebench.model.frontend import check_segments, model_source, translate, validate


def build_fmu(
    model_dir: str | Path = "models",
    out_path: str | Path = f"fmus/{FMU_NAME}.fmu",
    segments: int = DEFAULT_SEGMENTS,
    say: Callable[[str], None] | None = None,
) -> Path:
    """Check, translate, causalise, export and compile the machine model into one FMU file.

    rumoca checks the package first (the second, independent front end the issue asks for);
    its first complaint, if any, stops the build with the file, line and column. ``say``
    hears each step as it starts (``build`` prints them: the whole takes minutes).
    """
    say = say or (lambda _: None)
    check_segments(segments)
    find_compiler()
    problems = validate(model_source(model_dir))
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise SpindlebenchError(f"{problems[0]}{more}")
    say(f"[1/4] checked the Modelica source in {model_dir} (rumoca)")
    say(f"[2/4] translating it with pymoca, {segments} segments per large part")
    flat = translate(model_dir, segments)
    say("[3/4] causalising the equations into an explicit ODE (CasADi)")
    ode = build_explicit_ode(flat)
    say(f"[4/4] exporting the FMU and compiling its C code with the C compiler into {out_path}"
        " (the longest step)")
    return export_fmu(ode, out_path)
