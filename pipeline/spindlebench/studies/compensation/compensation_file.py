"""The compensation study file: a sweep's experiment family plus a ``[compensate]`` table.

The days are the sweep's experiments (climate, months, speeds, programmes, the run length,
the instruments), read by the sweep's own loader: day 1 is the ``[training]`` experiment of
replica 1, the model is trained on it, and the controller then runs every other experiment of
every replica, replica by replica, in the order of the axes. ``[compensate]``::

    models = ["all_raw", "six_raw", "six_diff", "all_raw:greedy"]   # sweep method names
    k = 3                              # clusters / inputs of every model
    update_interval_s = 10             # the controller reads the sensors this often
    rate_limit_um_per_s = 0.5          # optional: fastest change of the applied offset
    dead_band_um = 1.0                 # offset changes smaller than this are not applied
    tolerance_um = 5.0                 # "within tolerance" band of the residual
    fault = "T1-stuck"                 # optional: a [faults] table, on every day from ...
    fault_from_day = 8                 # ... this day on (never on the training day)
    retrain = "never"                  # or "weekly" (on the previous day) or "after-fault",
                                       # or a list of them: each runs on the same days
    retrain_every_days = 7             # the "weekly" interval
    stuck_window_min = 30              # fault monitor: a reading constant this long is stuck
    jump_C = 0.5                       # fault monitor: a step larger than this is a fault
    seed = 0                           # seed of fcm, kmeans and stability selection
    days = "continuous"                # one machine day after day (default), or
                                       # "cold-starts": every day a separate cold start
    off_h = 16                         # continuous: hours the machine stands between two
                                       # working days (default 24 h minus the day's length)

``update_interval_s`` must be a multiple of the study's ``sample_interval_s`` (the controller
sees the readings the logger makes). ``days = "continuous"`` is
``studies.compensation.continuous``: one simulation, the machine's state carried from each day (and
its night) to the next, and a fault that starts on ``fault_from_day`` stays to the end;
``"cold-starts"`` simulates every day on its own from the family's start state and applies
the fault from ``start_h`` into every day from ``fault_from_day`` on.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import DEFAULT_METHOD_SEED, GROUPS
from spindlebench.formats.toml import Table, in_range, load_toml, non_negative, one_of
from spindlebench.studies.compensation.controller import ControllerSettings, FaultMonitor
from spindlebench.studies.family.experiments import experiments
from spindlebench.studies.family.family_file import Fault, SweepStudy, load_study

RETRAIN_RULES = ("never", "weekly", "after-fault")
DAY_MODES = ("continuous", "cold-starts")
#: Days between two retrainings under ``retrain = "weekly"``.
WEEK_DAYS = 7


@dataclass(frozen=True)
class CompensationStudy:
    family: SweepStudy
    models: tuple[str, ...]
    k: int
    controller: ControllerSettings
    tolerance_um: float
    fault: Fault | None
    fault_from_day: int
    retrain: tuple[str, ...]  #: retraining rules, each run on the same simulated days
    seed: int
    retrain_every_days: int = WEEK_DAYS
    monitor: FaultMonitor = field(default_factory=FaultMonitor)
    days: str = "continuous"  #: DAY_MODES
    off_h: float = 16.0  #: continuous: hours standing between two working days

    @property
    def name(self) -> str:
        return self.family.name


def _check_model(name: str) -> str | None:
    from spindlebench.studies.family.methods import MethodSpec

    spec = MethodSpec(name, 2)
    if spec.group is None:
        return f"must be a group ({', '.join(GROUPS)}) or group:method, got {name!r}"
    try:
        spec.choice  # noqa: B018 - parses the label
    except SpindlebenchError as exc:
        return str(exc)
    return None


def load_compensation(path, machine: str | None = None) -> CompensationStudy:
    """Read and check a compensation study (one-line errors naming file and key);
    ``machine`` (``--machine``, or a drawn machine of the study's population) replaces the
    study's machine."""
    family = load_study(path, extra_tables=("compensate",), machine=machine)
    root = Table(load_toml(path, "study"), path)
    t = root.table("compensate")
    models = tuple(t.get_list("models", str, check=_check_model))
    if len(set(models)) != len(models):
        raise t.error("models", "a model is listed twice")
    k = t.get("k", int, default=3, check=in_range(1, 10))
    update = t.get("update_interval_s", float, default=family.sample_interval_s,
                   check=in_range(positive=True, unit=" s"))
    ratio = update / family.sample_interval_s
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise t.error("update_interval_s", f"{update:g} s is not a multiple of "
                      f"experiment.sample_interval_s ({family.sample_interval_s:g} s)")
    rate = t.get("rate_limit_um_per_s", float, default=None,
                 check=in_range(positive=True, unit=" um/s")) if t.has("rate_limit_um_per_s") \
        else None
    dead_band = t.get("dead_band_um", float, default=0.0, check=non_negative)
    tolerance = t.get("tolerance_um", float, default=5.0, check=in_range(positive=True))
    fault_name = t.get("fault", str, default="")
    fault = None
    if fault_name:
        known = {f.name: f for f in family.faults if f is not None}
        if fault_name not in known:
            raise t.error("fault", f"no fault {fault_name!r} in [faults] / axes.faults "
                          f"(have: {', '.join(known) or 'none'})")
        fault = known[fault_name]
    last_day = family.replicas * len(experiments(family))  # compensation.loop.plan_days
    from_day = t.get("fault_from_day", int, default=2, check=in_range(2, None))
    if from_day > last_day and (fault is not None or t.has("fault_from_day")):
        raise t.error("fault_from_day", f"day {from_day} is after the study's last day "
                      f"({last_day}: {family.replicas} replica(s) × {last_day // family.replicas}"
                      " experiment(s)); the fault would never happen")
    if isinstance(t.raw("retrain", None), list):
        retrain = tuple(t.get_list("retrain", str, check=lambda v: one_of(v, RETRAIN_RULES)))
        if len(set(retrain)) != len(retrain):
            raise t.error("retrain", "a rule is listed twice")
    else:
        retrain = (t.get("retrain", str, default="never",
                         check=lambda v: one_of(v, RETRAIN_RULES)),)
    every = t.get("retrain_every_days", int, default=WEEK_DAYS, check=in_range(1, None))
    window_min = t.get("stuck_window_min", float, default=30.0,
                       check=in_range(positive=True, unit=" min"))
    jump = t.get("jump_C", float, default=0.5, check=in_range(positive=True, unit=" K"))
    seed = t.get("seed", int, default=DEFAULT_METHOD_SEED, check=non_negative)
    days = t.get("days", str, default="continuous", check=lambda v: one_of(v, DAY_MODES))
    off_h = t.get("off_h", float, default=max(24.0 - family.duration_s / 3600.0, 0.0),
                  check=in_range(0.0, None, unit=" h"))
    if t.has("off_h") and days != "continuous":
        raise t.error("off_h", "only a \"continuous\" run has nights between its days")
    t.finish()
    if "after-fault" in retrain and fault is None:
        raise t.error("retrain", "'after-fault' needs a fault to detect (set 'fault')")
    return CompensationStudy(family, models, k, ControllerSettings(update, rate, dead_band),
                             tolerance, fault, from_day, retrain, seed, every,
                             FaultMonitor(window_min * 60.0, jump), days, off_h)
