"""``spindlebench calibrate``: recordings of a real machine → a machine file for the testbench.

``calibrate RECORDING… --map MAP.toml -o scenarios/machines/NAME.toml [--fit P1,P2,…]`` fits
the default parameter set (``calibration.fitset.DEFAULT_FIT``) or the named FMU parameters to
the recordings, prints estimates with 95 % intervals, the strongest correlations and each
channel's residual, and writes the machine file, ``NAME.calibration.json`` (report) and
``NAME.calibration.png`` (measured vs calibrated). The map names every column used; the time
column and CSV dialect are ``--time-column``/``--delimiter``/``--decimal`` (column roles,
``formats.roles``), and a mapped temperature that copies the error column is refused
unless ``--allow-target-copy``. ``--design`` then ranks excitations that
would separate the parameters the recordings could not.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from spindlebench.calibration.fitset import DEFAULT_FIT, check_fit_names
from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.files import check_output
from spindlebench.core.listflags import split_list_flag
from spindlebench.core.paths import MODELS_DIR, refuse_shipped
from spindlebench.core.progress import Stages, for_terminal
from spindlebench.core.provenance import file_entry, provenance
from spindlebench.formats.roles import ColumnRoles, add_role_arguments
from spindlebench.formats.toml import load_toml
from spindlebench.machines.variants import DEFAULT_MACHINE, add_machine_argument, load_machine
from spindlebench.model import DEFAULT_SEGMENTS, MAX_SEGMENTS, MODEL_FILE

if TYPE_CHECKING:
    from spindlebench.calibration.problem import Fit

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "fit the model to recordings of a real machine; write a machine file"

#: Correlations at least this strong are reported as "cannot be separated by these data".
STRONG_CORRELATION = 0.8


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "calibrate", help=HELP,
        description=__doc__.split("\n\n")[0] if __doc__ else None,
    )
    parser.add_argument("recordings", nargs="+", metavar="RECORDING",
                        help="recording CSV(s) of the machine (one shared parameter set)")
    parser.add_argument("--map", required=True, dest="map_file",
                        help="MAP.toml: columns -> model inputs, sensors, nodes, error")
    parser.add_argument("-o", "--out", required=True,
                        help="machine file to write, e.g. scenarios/machines/mine.toml")
    parser.add_argument("--fit", default=None,
                        help="comma-separated FMU parameters to fit (default: "
                        f"{', '.join(DEFAULT_FIT)})")
    parser.add_argument("--step-s", type=float, default=None,
                        help="calibrate on every step_s seconds (a multiple of the sampling)")
    parser.add_argument("--segments", type=int, default=DEFAULT_SEGMENTS,
                        help=f"segments per large part of the model (default {DEFAULT_SEGMENTS})")
    parser.add_argument("--models", default=str(MODELS_DIR), help="Modelica model folder")
    add_machine_argument(parser, "machine to start from (its parameters are kept in the "
                         "output)", f"{DEFAULT_MACHINE!r}", default=DEFAULT_MACHINE)
    parser.add_argument("--method", choices=("gauss-newton", "ipopt"), default="gauss-newton",
                        help="reduced-space Gauss-Newton (default) or IPOPT on the full "
                        "discretisation")
    parser.add_argument("--max-iter", type=int, default=50, help="iteration limit")
    parser.add_argument("--design", action="store_true",
                        help="afterwards, rank excitations that would separate correlated "
                        "parameters")
    parser.add_argument("--description", default=None, help="machine description")
    parser.add_argument("--verbose", action="store_true", help="print the solver's progress")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="no step lines or progress bar on stderr")
    # the map names the columns
    add_role_arguments(parser, sensors=False, exclude=False, speed=False)
    parser.set_defaults(func=_run)


def summary_lines(fit: Fit) -> list[str]:
    """Estimates, intervals, strong correlations and residuals as printed lines."""
    lines = [f"{'parameter':30s} {'start':>10s} {'estimate':>10s}   95 % interval"]
    for name, (lo, hi) in fit.interval95().items():
        lines.append(f"{name:30s} {fit.start_values[name]:10.4g} {fit.values[name]:10.4g}   "
                     f"[{lo:.4g}, {hi:.4g}]")
    pairs = [(abs(fit.correlation[i, j]), fit.fit[i], fit.fit[j], fit.correlation[i, j])
             for i in range(len(fit.fit)) for j in range(i)]
    strong = sorted((p for p in pairs if p[0] >= STRONG_CORRELATION), reverse=True)
    if strong:
        lines.append("not separated by these recordings (|correlation| >= "
                     f"{STRONG_CORRELATION:g}): " + ", ".join(
                         f"{a}~{b} {c:+.2f}" for _, a, b, c in strong))
    if fit.at_bound:
        lines.append(f"at a bound of the factor range ({len(fit.at_bound)} of {len(fit.fit)}: "
                     "the fit compensates there for what the model cannot do; docs/validation"
                     ".md, 'Which parameters to fit'): " + ", ".join(fit.at_bound))
    lines.append(f"residuals (reduced chi-square {fit.chi2_reduced:.3g}):")
    for row in fit.channel_rmse:
        unit = "um" if row["kind"] == "error" else "K"
        lines.append(f"  {row['recording']}: {row['column']} -> {row['output']}: RMSE "
                     f"{row['rmse']:.3g} {unit} (noise {row['noise']:.2g} {unit})")
    return lines


def _run(args: argparse.Namespace) -> int:
    # CasADi, SciPy, matplotlib and pymoca only here: ``calibrate --help`` stays cheap
    from spindlebench.calibration import fit_report as report
    from spindlebench.calibration.mapping import read_map
    from spindlebench.calibration.problem import Discretisation, calibrate
    from spindlebench.calibration.series import check_roles, load_series
    from spindlebench.model.equations import explicit_ode

    out = Path(args.out)
    if out.suffix != ".toml":
        raise SpindlebenchError(f"-o {out}: a machine file ends in .toml")
    report_path, figure_path = report.report_paths(out)
    for written in (out, report_path, figure_path, report.state_path(out)):
        check_output(written, "-o", [*args.recordings, args.map_file])
        refuse_shipped(written)  # now, not after minutes of fitting
    if not 2 <= args.segments <= MAX_SEGMENTS:
        raise SpindlebenchError(f"--segments {args.segments}: must be in [2, {MAX_SEGMENTS}]")
    if args.step_s is not None and not args.step_s > 0:
        raise SpindlebenchError(f"--step-s {args.step_s:g}: must be > 0")
    roles = ColumnRoles.from_args(args)
    for path in args.recordings:  # a wrong file or time column before the slow translation
        check_roles(Path(path), roles)
    load_toml(args.map_file, "map")  # an unreadable map too (its names need the model)
    stages = Stages("calibrate", enabled=for_terminal(args.quiet))
    stages(f"translating the model in {args.models} ({args.segments} segments per part)")
    ode = explicit_ode(args.models, segments=args.segments)
    stages(f"reading {len(args.recordings)} recording(s) through {args.map_file}")
    recording_map = read_map(args.map_file, ode.outputs)
    fit_names = check_fit_names(
        split_list_flag("--fit", args.fit, "parameter") if args.fit is not None else DEFAULT_FIT,
        ode.parameters, "--fit")
    series_list, ignored = [], {}
    for path in args.recordings:
        series = load_series(path, recording_map, args.step_s, roles)
        series_list.append(series)
        if series.ignored:
            ignored[str(path)] = list(series.ignored)
            print(f"{path}: ignored (not in the map): {', '.join(series.ignored)}")
    machine = load_machine(args.machine)
    base = ode.parameter_vector(**machine.parameters)
    discretisation = Discretisation(ode, fit_names, base)
    stages(f"fitting {len(fit_names)} parameter(s) by {args.method} (at most "
           f"{args.max_iter} model evaluations)")
    fit = calibrate(discretisation, series_list, method=args.method, max_iter=args.max_iter,
                    verbose=args.verbose, progress=for_terminal(args.quiet) and not args.verbose)
    for line in summary_lines(fit):
        print(line)
    model_file = Path(args.models) / MODEL_FILE
    record = provenance(
        kind="spindlebench calibration",
        recordings=[file_entry(s.path) for s in series_list],
        map=file_entry(recording_map.path),
        model=file_entry(model_file),
        segments=args.segments,
        step_s=args.step_s,
        fit=fit_names,
        machine=machine.provenance(),
    )
    name = out.stem
    description = args.description or (
        f"Machine '{machine.name}' calibrated to {', '.join(s.path.name for s in series_list)} "
        f"({len(fit_names)} parameters fitted)")
    machine_text = report.machine_text(name, description, {**machine.parameters, **fit.values},
                                       fit, record)
    report_path, figure_path = report.report_paths(out)
    content = report.report_dict(fit, record, ignored)
    limited = fit.evaluations >= args.max_iter
    content["evaluation_limit"] = args.max_iter
    content["stop_reason"] = (f"evaluation limit ({args.max_iter}) reached: not converged"
                              if limited else f"converged: {fit.status}")
    if args.design:
        from spindlebench.calibration.design import design_lines, rank_excitations

        stages("ranking excitations (--design)")
        ranking = rank_excitations(discretisation, fit, series_list)
        content["design"] = ranking
        for line in design_lines(ranking):
            print(line)
    stages("writing the machine file, its report and figure")
    report.figure(fit, figure_path, title=f"{name}: measured (dots) vs calibrated (lines)")
    report.write_report(report_path, content)
    state_file = report.state_path(out)
    report.write_report(state_file, report.state_record(fit, series_list, record))
    atomic.write_text(out, machine_text)
    print(f"wrote {out} (+ {report_path.name}, {figure_path.name}, {state_file.name}); "
          f"{fit.evaluations} of at most {args.max_iter} evaluations, fit {fit.seconds:.0f} s, "
          f"{stages.seconds:.0f} s in all; stopped: {content['stop_reason']}")
    return 0

