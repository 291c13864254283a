"""What the paper comparison runs on: experiments, target, the three sensor groups, k values.

The defaults are the paper's set-up on the canonical synthetic recordings (``exp1`` … ``exp5``,
``T1`` … ``T20``, the six T1, T6, T8, T10, T13, T16, target ``drift_um``). A TOML file
(``--config``) or flags change any of it, so the same command runs on real data; flags win
over the file, the file over the defaults.

TOML keys (all optional)::

    title = "caiviac-fl-thermal, heating runs"
    target = "ch3_um"
    train = "run4_5000rpm"                 # recording stem in --recordings
    tests = ["run1_1250rpm", "run2_2500rpm"]
    sensors_all = ["t1_C", "t2_C"]          # reference group 1
    six = "auto"                           # or a list: reference group 2 and the base of
                                           # the difference group
    clusters = [2, 3, 4]
    similarity = "abs-pearson"             # or "literal"
    missing = "error"                      # or "drop-rows": drop samples with a missing
                                           # target/used sensor (sensor dropout), warned
    methods = ["closure", "kmeans+grey"]   # method labels (spindlebench methods), or "all";
                                           # every one runs on every group and k
    seed = 0                               # seed of fcm, kmeans and stability selection
    time_column = "time_s"                 # the time axis in seconds (the figures need it)
    exclude = ["dx [um]"]                  # columns (names or * ? patterns) never sensors
    allow_target_copy = false              # keep a sensor with |r| > 0.999 with the target
    delimiter = ";"                        # CSV dialect (default: detected), "tab" for a tab
    decimal = ","

``six = "auto"`` picks the subset by a rule that does not look at the thermal error (the paper
chose its six by location, one per region of the machine): cut the fuzzy equivalence hierarchy
of ``sensors_all`` on the training experiment into six clusters and keep, from each, the sensor
with the largest temperature range (the most active point of that thermal region).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.listflags import split_list_flag
from spindlebench.core.names import (
    DEFAULT_METHOD,
    DEFAULT_METHOD_SEED,
    DEFAULT_SIMILARITY,
    MISSING_MODES,
    PAPER_SIX,
    SENSORS,
    SIMILARITIES,
)
from spindlebench.formats.recording import DRIFT_COLUMN, TIME_COLUMN
from spindlebench.formats.toml import Table, load_toml
from spindlebench.selection.method_registry import method_names

AUTO_SIX = "auto"
#: A recordings folder's own study file (the CAIVIAC adapter writes one); ``spindlebench paper``
#: uses it when no --config is given.
CONFIG_NAME = "paper_study.toml"

_KEYS = ("title", "target", "targets", "train", "tests", "sensors_all", "six", "clusters",
         "similarity",
         "missing", "methods", "seed", "time_column", "exclude", "allow_target_copy",
         "delimiter", "decimal")
#: ``methods = "all"``: every selection method with its defaults (psi, ols).
ALL_METHODS = "all"


@dataclass(frozen=True)
class StudyConfig:
    """One comparison: train on ``train``, predict ``tests``, for each group and k."""

    title: str = "paper set-up (exp1 … exp5)"
    target: str = DRIFT_COLUMN
    #: ``targets = [...]``: several thermal-error columns, each compared on its own (its
    #: study in ``<out>/<target>/``) and the joint selections beside them; ``target`` is then
    #: the first. Empty: the one ``target``.
    targets: tuple[str, ...] = ()
    train: str = "exp1"
    tests: tuple[str, ...] = ("exp2", "exp3", "exp4", "exp5")
    sensors_all: tuple[str, ...] = SENSORS
    six: tuple[str, ...] | str = PAPER_SIX
    clusters: tuple[int, ...] = (2, 3, 4)
    similarity: str = DEFAULT_SIMILARITY
    missing: str = "error"
    #: Method labels (``selection.registry``); the first is the paper's, whose cells feed the
    #: paper's tables; the others add the "methods compared" tables.
    methods: tuple[str, ...] = (DEFAULT_METHOD,)
    seed: int = DEFAULT_METHOD_SEED
    #: Column roles (``formats.roles``): time axis, excluded columns, copies of the target,
    #: CSV dialect (None: detected).
    time_column: str = TIME_COLUMN
    exclude: tuple[str, ...] = ()
    allow_target_copy: bool = False
    delimiter: str | None = None
    decimal: str | None = None
    source: str = field(default="defaults", compare=False)

    @property
    def experiments(self) -> tuple[str, ...]:
        """Training experiment first, then the predicted ones."""
        return (self.train, *self.tests)

    def checked(self) -> StudyConfig:
        """Self, after checks that need no data; one-line errors naming the key."""
        where = self.source

        def fail(key: str, message: str) -> SpindlebenchError:
            return SpindlebenchError(f"{where}: key '{key}': {message}")

        for key, names in (("train", (self.train,)), ("tests", self.tests)):
            for name in names:
                if not _plain_name(name):
                    raise fail(key, f"{name!r} is not an experiment name (the stem of a CSV "
                                    "in --recordings: no folder separators, '.' or '..')")
        if self.targets:
            twice = sorted({t for t in self.targets if self.targets.count(t) > 1})
            if twice:
                raise fail("targets", f"{', '.join(twice)} given twice")
            for other in self.targets[1:]:
                replace(self, target=other, targets=()).checked()
            if self.target != self.targets[0]:
                return replace(self, target=self.targets[0]).checked()
        if self.target == self.time_column:
            raise fail("target", f"{self.time_column} is the time axis, not a thermal error")
        if self.time_column in self.sensors_all:
            raise fail("sensors_all", f"{self.time_column} is the time axis, not a sensor")
        from spindlebench.formats.roles import matches, parse_decimal, parse_delimiter

        parse_delimiter(self.delimiter, f"{where}: key 'delimiter'")
        parse_decimal(self.decimal, f"{where}: key 'decimal'")
        excluded = [s for s in self.sensors_all if matches(s, self.exclude)]
        if excluded:
            kept = tuple(s for s in self.sensors_all if s not in excluded)
            six = self.six if isinstance(self.six, str) else tuple(
                s for s in self.six if s not in excluded)
            return replace(self, sensors_all=kept, six=six, exclude=()).checked()
        if self.target in self.sensors_all:
            raise fail("target", f"{self.target!r} is also in sensors_all (a model would "
                                 "predict it from itself)")
        if not self.tests:
            raise fail("tests", "at least one experiment to predict")
        if self.train in self.tests:
            raise fail("tests", f"{self.train!r} is also the training run")
        if len(set(self.tests)) != len(self.tests):
            raise fail("tests", "an experiment is listed twice")
        if len(self.sensors_all) < 2 or len(set(self.sensors_all)) != len(self.sensors_all):
            raise fail("sensors_all", "need two or more distinct sensors")
        if isinstance(self.six, str):
            if self.six != AUTO_SIX:
                raise fail("six", f"{self.six!r} is neither a list nor 'auto'")
        else:
            if len(self.six) < 2 or len(set(self.six)) != len(self.six):
                raise fail("six", "need two or more distinct sensors")
            unknown = [s for s in self.six if s not in self.sensors_all]
            if unknown:
                raise fail("six", f"{', '.join(unknown)} not among sensors_all")
        if not self.clusters or any(k < 1 for k in self.clusters):
            raise fail("clusters", "need one or more integers >= 1")
        repeated = sorted({k for k in self.clusters if self.clusters.count(k) > 1})
        if repeated:
            raise fail("clusters", f"k = {repeated[0]} is listed twice")
        if self.similarity not in SIMILARITIES:
            raise fail("similarity",
                       f"{self.similarity!r} is not one of {', '.join(SIMILARITIES)}")
        if self.missing not in MISSING_MODES:
            raise fail("missing", f"{self.missing!r} is not one of {', '.join(MISSING_MODES)}")
        from spindlebench.selection.registry import check_labels

        labels = check_labels(self.methods, f"{where}: key 'methods'")
        if not labels:
            raise fail("methods", "need one or more method labels")
        from spindlebench.selection.registry import method_seed_problem

        if method_seed_problem(self.seed):
            raise fail("seed", method_seed_problem(self.seed))
        return replace(self, methods=labels)

    def to_dict(self) -> dict[str, Any]:
        """Plain values, for provenance and the README."""
        return {
            "title": self.title, "target": self.target, "train": self.train,
            "tests": list(self.tests), "sensors_all": list(self.sensors_all),
            "six": self.six if isinstance(self.six, str) else list(self.six),
            "clusters": list(self.clusters), "similarity": self.similarity,
            "missing": self.missing, "methods": list(self.methods), "seed": self.seed,
            "time_column": self.time_column, "allow_target_copy": self.allow_target_copy,
            "delimiter": self.delimiter, "decimal": self.decimal, "source": self.source,
            **({"targets": list(self.targets)} if self.targets else {}),
        }


def _plain_name(name: str) -> bool:
    """Whether ``name`` names a file directly in the recordings folder (no path out of it)."""
    return bool(name) and "/" not in name and "\\" not in name and name not in (".", "..")


def _split(table: Table, key: str, text: str) -> list[str]:
    """``"a, b,c"`` -> ``["a", "b", "c"]``; an empty item (``"2,,3"``) is an error."""
    return split_list_flag(f"{table.source}: key '{key}'", text) or []


def _names(table: Table, key: str) -> tuple[str, ...]:
    value = table.raw(key)
    if isinstance(value, str):
        return tuple(_split(table, key, value))
    if isinstance(value, list) and all(isinstance(item, str) and item.strip() for item in value):
        return tuple(value)
    raise table.error(key, "expected a list of non-empty names")


def _ints(table: Table, key: str) -> tuple[int, ...]:
    value = table.raw(key)
    if isinstance(value, str):
        try:
            return tuple(int(item) for item in _split(table, key, value))
        except ValueError:
            raise table.error(key, f"expected integers, got {value!r}") from None
    if isinstance(value, list) and all(isinstance(i, int) and not isinstance(i, bool)
                                       for i in value):
        return tuple(value)
    raise table.error(key, "expected a list of integers")


def updated(config: StudyConfig, table: Table) -> StudyConfig:
    """``config`` with the keys of ``table`` replaced (from TOML or flags), each checked."""
    changes: dict[str, Any] = {}
    for key in _KEYS:
        if table.raw(key, None) is None:
            continue
        if key == "allow_target_copy":
            value = table.raw(key)
            if not isinstance(value, bool):
                raise table.error(key, f"expected true or false, got {value!r}")
            changes[key] = value
        elif key in ("title", "target", "train", "similarity", "missing", "time_column",
                     "delimiter", "decimal"):
            value = table.raw(key)
            if not isinstance(value, str) or not value:
                raise table.error(key, "expected a non-empty string")
            changes[key] = value
        elif key in ("tests", "sensors_all", "exclude", "targets"):
            changes[key] = _names(table, key)
        elif key == "six":
            changes[key] = AUTO_SIX if table.raw(key) == AUTO_SIX else _names(table, key)
        elif key == "methods":
            names = _names(table, key)
            changes[key] = (method_names(budget=True, multi_output=False)
                            if names == (ALL_METHODS,) else names)
        elif key == "seed":
            value = table.raw(key)
            if isinstance(value, str) and value.isdigit():
                value = int(value)
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise table.error(key, f"expected an integer >= 0, got {value!r}")
            changes[key] = value
        else:
            changes[key] = _ints(table, key)
    table.finish()
    if not changes:
        return config
    where = table.source
    source = where if config.source == "defaults" else f"{config.source} + {where}"
    return replace(config, source=source, **changes)


def load(path: str | Path | None, overrides: dict[str, Any] | None = None) -> StudyConfig:
    """Defaults, then the TOML file (if any), then flag overrides; checked."""
    config = StudyConfig()
    if path is not None:
        config = updated(config, Table(load_toml(path, "config"), path))
    if overrides:
        config = updated(config, Table(overrides, "command line"))
    return config.checked()
