"""``spindlebench paper``: the paper's whole comparison on a folder of recordings."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from spindlebench.commands.arguments import add_target_argument, joint_of, targets_of
from spindlebench.core.listflags import split_list_flag
from spindlebench.core.names import GROUP_LABELS, SIMILARITIES
from spindlebench.formats.roles import add_role_arguments
from spindlebench.studies.paper import config as study_config

#: The one-line help of ``spindlebench --help`` (copied into ``commands.main.COMMAND_HELP``).
HELP = "rerun the paper's comparison (3 sensor groups x 2/3/4 clusters) on recordings"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``paper`` sub-command."""
    parser = subparsers.add_parser(
        "paper",
        help=HELP,
        description="Train on one experiment, predict the others, for all raw sensors, six raw "
        "sensors and those six plus their differences, at each number of clusters; write the "
        "analogues of the paper's Tables 4-6 and Figures 3-6 plus dendrograms. Defaults are "
        "the paper's set-up on synthetic recordings exp1 ... exp5 (T1 ... T20, drift_um); a "
        f"--config TOML (or, without --config, the folder's own {study_config.CONFIG_NAME}, "
        "as 'spindlebench adapt caiviac' writes) or the flags below change it (flags win). "
        "Only the columns the study uses are read; a gap or a note in another column is "
        "ignored.",
    )
    parser.add_argument("--recordings", required=True, help="folder with <experiment>.csv files")
    parser.add_argument("--out", default=None,
                        help="output folder (default: <recordings>/paper_study)")
    parser.add_argument("--config", default=None,
                        help="study TOML (see spindlebench.studies.paper.config); default: "
                        f"<recordings>/{study_config.CONFIG_NAME} when the folder has one (the "
                        "CAIVIAC adapter writes it; said on stderr), else the paper's set-up")
    add_target_argument(parser, "thermal-error column (default drift_um)", joint=True)
    parser.add_argument("--train", default=None, help="training experiment (default exp1)")
    parser.add_argument("--tests", default=None, nargs="+", metavar="NAME",
                        help="predicted experiments, space- or comma-separated "
                        "(default exp2 exp3 exp4 exp5)")
    parser.add_argument("--sensors-all", default=None, nargs="+", metavar="NAME",
                        help="sensors of group 1, space- or comma-separated (default T1 ... T20)")
    parser.add_argument("--six", default=None, nargs="+", metavar="NAME",
                        help="six-sensor subset, space- or comma-separated, or 'auto' "
                        "(default T1 T6 T8 T10 T13 T16)")
    parser.add_argument("--clusters", default=None, nargs="+", metavar="K",
                        help="k values, space- or comma-separated (default 2 3 4)")
    parser.add_argument("--similarity", default=None, choices=SIMILARITIES,
                        help="reading of eq. 1 (default abs-pearson)")
    parser.add_argument("--missing", default=None, choices=study_config.MISSING_MODES,
                        help="missing (empty/NaN) values in the columns the study uses "
                        "(target, sensors_all, time_s; other columns are ignored): one-line "
                        "error (default), or drop the samples where the target or a used "
                        "sensor is missing (warned)")
    parser.add_argument("--methods", default=None, nargs="+", metavar="LABEL",
                        help="method labels to compare besides the paper's tables "
                        "(method[+within][+regressor], see 'spindlebench methods'), space- or "
                        "comma-separated, or 'all' (default: closure, the paper's, only)")
    parser.add_argument("--seed", default=None, type=int,
                        help="seed of fcm, kmeans and stability selection (default 0)")
    add_role_arguments(parser, sensors=False)  # --sensors-all names the sensors here
    parser.set_defaults(func=_run)


def _joined(flag: str, values: list[str] | None) -> str | None:
    """A list flag's words as one comma-separated value (``T1 T6,T8`` -> ``T1,T6,T8``)."""
    names = split_list_flag(flag, values)
    return None if names is None else ",".join(names)


def _run(args: argparse.Namespace) -> int:
    # pandas, matplotlib and the selection methods only here: ``paper --help`` stays cheap
    from spindlebench.studies.paper.analysis import run_study
    from spindlebench.studies.paper.paper_report import check_out_dir, write_outputs

    lists = {key: _joined("--" + key.replace("_", "-"), getattr(args, key))
             for key in ("tests", "sensors_all", "six", "clusters", "methods")}
    lists["exclude"] = _joined("--exclude", args.exclude)
    targets = targets_of(args)
    args.target = targets[0] if targets and len(targets) == 1 else None  # one: as before
    overrides = {
        "target": args.target, "targets": targets if targets and len(targets) > 1 else None,
        "train": args.train, "similarity": args.similarity,
        "missing": args.missing, "seed": args.seed, "time_column": args.time_column,
        "delimiter": args.delimiter, "decimal": args.decimal,
        "allow_target_copy": True if args.allow_target_copy else None, **lists,
    }
    config_path = args.config
    own = Path(args.recordings) / study_config.CONFIG_NAME
    if config_path is None and own.is_file():
        config_path = str(own)
        print(f"using {own} (the folder's own study file; --config chooses another)",
              file=sys.stderr)
    config = study_config.load(config_path, overrides)
    out_dir = Path(args.out) if args.out else Path(args.recordings) / "paper_study"
    command = "spindlebench paper " + " ".join(
        f"{flag} {shlex.quote(str(value))}"
        for flag, value in (
            ("--recordings", args.recordings), ("--out", str(out_dir)),
            ("--config", config_path),
            ("--target", args.target),
            ("--train", args.train),
            ("--tests", lists["tests"]), ("--sensors-all", lists["sensors_all"]),
            ("--six", lists["six"]), ("--clusters", lists["clusters"]),
            ("--similarity", args.similarity), ("--missing", args.missing),
            ("--methods", lists["methods"]), ("--seed", args.seed),
            ("--time-column", args.time_column), ("--exclude", lists["exclude"]),
            ("--delimiter", args.delimiter), ("--decimal", args.decimal),
        )
        if value is not None
    ) + (" --allow-target-copy" if args.allow_target_copy else "") + (
        " --target " + " ".join(map(shlex.quote, targets))
        if targets and len(targets) > 1 else "") + (
        " --joint " + " ".join(args.joint) if getattr(args, "joint", None) else "")
    check_out_dir(out_dir)  # before the study's minutes, not after
    if len(config.targets) > 1:
        return _several(args, config, out_dir, command)
    result = run_study(args.recordings, config)
    paths = write_outputs(result, out_dir, command)
    print(f"paper comparison: train {config.train}, predict {', '.join(config.tests)}; "
          f"target {config.target}; six = {', '.join(result.six)}")
    print(f"{'k':>2}  {'group':<18} " + " ".join(f"{t:>12}" for t in config.tests) + "     mean")
    for cell in result.cells:
        print(f"{cell.k:>2}  {GROUP_LABELS[cell.group]:<18} "
              + " ".join(f"{cell.rmse_um[t]:>12.2f}" for t in config.tests)
              + f" {cell.mean_rmse_um:>8.2f}")
    print(f"wrote {paths['readme']} and {len(paths) - 1} more files in {out_dir}")
    return 0


def _several(args: argparse.Namespace, config: study_config.StudyConfig, out_dir: Path,
             command: str) -> int:
    """Each target's comparison into ``out_dir/<target>``, then the joint selections."""
    import dataclasses

    from spindlebench.studies.paper.analysis import run_study
    from spindlebench.studies.paper.joint import write_joint
    from spindlebench.studies.paper.paper_report import check_out_dir, write_outputs

    results = {}
    for target in config.targets:
        own = dataclasses.replace(config, target=target, targets=())
        check_out_dir(out_dir / target)
        results[target] = run_study(args.recordings, own)
        paths = write_outputs(results[target], out_dir / target, command)
        print(f"target {target}: wrote {paths['readme']} and {len(paths) - 1} more files")
    readme = write_joint(results, out_dir, command, joint_of(args))
    print(f"joint selections of {', '.join(config.targets)}: {readme}")
    return 0
