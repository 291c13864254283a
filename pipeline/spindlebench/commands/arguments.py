"""Argument helpers shared by several sub-commands: the study-file options and results folder
of every study command (``sweep``, ``place``, ``compensate``), and the study command itself
(``register_study_command``): one results folder, then one run per machine; the target
columns (``--target A [B ...]``, ``--joint``) of the commands that select or fingerprint.
"""

from __future__ import annotations

import argparse
import functools
import re
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

from spindlebench.core.errors import SpindlebenchError
from spindlebench.machines.variants import add_machine_argument
from spindlebench.studies.family.family_file import SweepStudy, machine_runs
from spindlebench.studies.family.population import Member, Population, draw_population_of

#: What ``--target`` says about several targets (each command adds what its one target is).
SEVERAL_TARGETS = ("; several (e.g. --target drift_um drift_y_um tilt_a_urad): each is "
                   "reported on its own")


def add_target_argument(parser: argparse.ArgumentParser, help: str, *,
                        required: bool = False, joint: bool = False) -> None:
    """``--target COLUMN [COLUMN ...]``: one target keeps its old meaning and output; several
    are reported per target (``targets_of``). ``joint``: also ``--joint``, the joint
    selections (one sensor set for every target) of a command that selects."""
    parser.add_argument("--target", nargs="+", required=required, default=None,
                        metavar="COLUMN", help=help + SEVERAL_TARGETS
                        + (", and with the joint selections of --joint" if joint else ""))
    if joint:
        from spindlebench.selection.method_registry import joint_names

        names = joint_names()
        parser.add_argument("--joint", nargs="+", default=None, metavar="NAME",
                            help="with several --target: one sensor set for all of them, "
                            f"each scored per target: {names[0]} (the union of the "
                            "per-target selections) or a multi-output method (k for all "
                            f"targets): {', '.join(names[1:])} (default: {', '.join(names)})")


def targets_of(args: argparse.Namespace) -> list[str] | None:
    """The ``--target`` columns (None: not given), refused if one is given twice; ``--joint``
    only with several targets, and only known names."""
    targets = getattr(args, "target", None)
    joint = getattr(args, "joint", None)
    if targets is None:
        if joint is not None:
            raise SpindlebenchError("--joint: needs several --target columns")
        return None
    targets = list(targets)
    twice = sorted({t for t in targets if targets.count(t) > 1})
    if twice:
        raise SpindlebenchError(f"--target: {', '.join(twice)} given twice")
    if joint is not None:
        from spindlebench.selection.method_registry import joint_names

        names = joint_names()
        if len(targets) < 2:
            raise SpindlebenchError("--joint: needs several --target columns (one target's "
                                    "selection is already one sensor set)")
        unknown = [name for name in joint if name not in names]
        if unknown:
            raise SpindlebenchError(f"--joint: {', '.join(unknown)} is not a joint selection "
                                    f"(choose from {', '.join(names)})")
    return targets


def joint_of(args: argparse.Namespace) -> tuple[str, ...]:
    """The joint selections asked for (default: the union and every multi-output method)."""
    from spindlebench.selection.method_registry import joint_names

    joint = getattr(args, "joint", None)
    return tuple(dict.fromkeys(joint)) if joint else joint_names()


#: A study name that may serve as the default results folder ``results/<name>``.
FOLDER_NAME = re.compile(r"[A-Za-z0-9._-]+")


def add_study_file_arguments(parser: argparse.ArgumentParser, example: str) -> None:
    """The study file and its results folder (``-o``; default ``default_results_folder``):
    every command that runs a study file (``sweep``, ``place``, ``compensate``)."""
    parser.add_argument("study", type=Path, help=f"study file (e.g. {example})")
    parser.add_argument("-o", "--out", type=Path, default=None,
                        help="results folder (required: e.g. results/<study name>; a study "
                        "writes nowhere else)")


def add_study_arguments(parser: argparse.ArgumentParser, example: str) -> None:
    """The options every study command shares: study file, results folder, where to run."""
    add_study_file_arguments(parser, example)
    parser.add_argument("--workers", type=int, default=None,
                        help="local worker processes (default: all cores; 0 = in-process)")
    parser.add_argument("--dask-address", default=None, metavar="tcp://HOST:PORT",
                        help="run on an existing Dask distributed cluster instead")
    parser.add_argument("-q", "--quiet", "--no-progress", dest="no_progress",
                        action="store_true", help="no progress bar or step lines on stderr")
    add_machine_argument(parser, "machine variant of every run",
                         "the study's [study] machine, else 'default'")


def results_folder(args: argparse.Namespace, study_name: Callable[[Path], str]) -> Path:
    """The study command's output folder, after refusing contradictory execution options."""
    # compensate runs in-process: it has neither option
    if getattr(args, "workers", None) is not None and getattr(args, "dask_address", None):
        raise SpindlebenchError("give either --workers or --dask-address, not both")
    if args.out is not None:
        from spindlebench.core.files import check_output

        return check_output(args.out, "-o", [args.study], folder=True)
    return default_results_folder(args.study, study_name(args.study))


def default_results_folder(study_path: Path, name: str) -> NoReturn:
    """A study without ``-o``: one line asking for it, suggesting ``results/<name>``.

    It wrote into ``results/<name>`` of whatever folder it was run from (a checkout, a
    student's folder): a command writes only where it is told. The study is read first, so
    its own errors come first; a name that cannot be a folder is said so."""
    if not FOLDER_NAME.fullmatch(name) or set(name) == {"."}:
        raise SpindlebenchError(
            f"{study_path}: key 'study.name': {name!r} cannot name a folder under results/ "
            "(use only letters, digits, '.', '_' and '-'), or give -o/--out")
    raise SpindlebenchError(f"{study_path}: give the results folder with -o/--out (e.g. -o "
                            f"results/{name}); a study writes only into the folder it is given")


#: What a study kind writes over a population's machines once each has run (None: the
#: machines' own folders and ``population.csv`` only).
PopulationReport = Callable[[Path, Population, list[Member], Path, Path], str]


def register_study_command(subparsers: argparse._SubParsersAction, name: str, *, help: str,
                           description: str, example: str,
                           load_family: Callable[[Path], SweepStudy],
                           run_one: Callable[[argparse.Namespace, Path, str | None], None],
                           population_report: PopulationReport | None = None) -> None:
    """Add a study sub-command with the options every study shares.

    ``load_family`` loads (and checks) the study file and gives its experiment family;
    ``run_one`` runs the study on one machine into one results folder;
    ``population_report`` sums up a population's machines (``studies.family.population``)."""
    parser = subparsers.add_parser(name, help=help, description=description)
    add_study_arguments(parser, example)
    parser.set_defaults(func=functools.partial(run_study_command, load_family=load_family,
                                               run_one=run_one,
                                               population_report=population_report))


def run_study_command(args: argparse.Namespace, *, load_family: Callable[[Path], SweepStudy],
                      run_one: Callable[[argparse.Namespace, Path, str | None], None],
                      population_report: PopulationReport | None = None) -> int:
    """A study command: its results folder, then one run per machine (``machine_runs``, or
    every kept machine of the study's population)."""
    loaded: list[SweepStudy] = []  # the study is read (and its FMU inspected) once

    def study_name(path: Path) -> str:
        loaded.append(load_family(path))
        return loaded[0].name

    out = results_folder(args, study_name)
    study = loaded[0] if loaded else load_family(args.study)
    members: list[Member] | None = None
    if args.machine is None and study.population is not None:
        print(f"population: {study.population.describe()}")
        members = draw_population_of(study, out)
        runs: list[tuple[str | None, Path]] = [(str(m.path), out / m.name)
                                               for m in members if m.kept]
    else:
        runs = machine_runs(study, args.machine, out)
    for machine, folder in runs:
        if machine is not None and folder != out:
            print(f"machine {Path(machine).stem if machine.endswith('.toml') else machine}:")
        run_one(args, folder, machine)
    if members is not None and population_report is not None:
        population_report(out, study.population, members, Path(args.study), study.fmu)
        print(f"population summary: {out / 'README.md'}")
    return 0
