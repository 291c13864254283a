"""The placement study file: a sweep's experiment family plus a ``[placement]`` table.

The experiments (climate, months, speeds, programmes, cooling, the run length, the training
rule, the instruments' noise level) are read by the season sweep's own loader, so both
studies describe their machine days in the same words. ``[placement]`` adds what is
specific to placement:

- ``budgets``: numbers m of model variables (sensors, or differences of two sensors) to place.
- ``methods``: ``fuzzy`` (the paper's selection on the training run, k = m clusters),
  ``greedy`` (forward selection by validation RMSE; refused over
  ``placements.FORWARD_SEARCH_MAX_VALUES`` candidate values), ``exhaustive`` (every m-subset, when
  C(n, m) <= ``exhaustive_limit``), or any other label of ``spindlebench methods``
  (``kmeans``, ``ward+grey``, ``lasso``, ...: that method on the training run(s), m inputs,
  its regressor ignored since every placement is scored by the same OLS refit).
- ``with_differences``: false, true, or [false, true] for both candidate sets (nodes alone;
  nodes and every pairwise node difference).
- ``measured``: read the node temperatures through the study's noise level (default) or use
  the noise-free field.
- ``exclude_nodes``: nodes where no sensor can go (names as in the FMU, without ``node_``).
- ``rotating_nodes``: false (default) leaves out the nodes of parts that turn
  (``ROTATING_PARTS``: the spindle shaft, the tool with its holder, the ball screws): a
  probe cannot be glued there; true keeps them, for a telemetry study (a sensor in the
  rotor sending by radio or slip ring). The results README lists the candidates.
- ``similarity``: the fuzzy similarity, as for the sweep.

Replica 1 is the *design* day set (placements are chosen on it); every further replica is a
*test* day set (fresh weather and noise) on which each placement is refit and scored.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fmpy import read_model_description

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import DEFAULT_SIMILARITY, SIMILARITIES
from spindlebench.formats.recording import PROBE_NODES, node_of_output
from spindlebench.formats.toml import Table, in_range, load_toml, one_of
from spindlebench.studies.family.family_file import NO_FAULT, SweepStudy, check_fmu, load_study

METHODS = ("fuzzy", "greedy", "exhaustive")
#: Parts that rotate in service (node names ``<part>`` or ``<part>_<i>``): the spindle shaft,
#: the tool holder with its test mandrel, and the ball screws (the nut is what stands).
ROTATING_PARTS = ("spindle_shaft", "tool", "x_screw", "y_screw", "z_screw")


def is_rotating(node: str) -> bool:
    """Whether a node belongs to a part of ``ROTATING_PARTS``."""
    return any(node == part or (node.startswith(part + "_") and
                                node[len(part) + 1:].isdigit()) for part in ROTATING_PARTS)
DEFAULT_EXHAUSTIVE_LIMIT = 500_000
MAX_EXHAUSTIVE_LIMIT = 10**9
MAX_BUDGET = 10


def _placement_method(name: str) -> str | None:
    """``fuzzy``, ``greedy``, ``exhaustive`` or a selection method label (not ``closure``:
    that is ``fuzzy`` here)."""
    if name in METHODS:
        return None
    from spindlebench.selection.registry import parse_method

    try:
        choice = parse_method(name)
    except SpindlebenchError as exc:
        return f"must be one of {', '.join(METHODS)} or a method label; {exc}"
    if choice.is_paper:
        return "the paper's closure is 'fuzzy' in a placement study"
    return None


@dataclass(frozen=True)
class PlacementStudy:
    """A validated placement study: its experiment family and the placement settings."""

    family: SweepStudy
    budgets: tuple[int, ...]
    methods: tuple[str, ...]
    with_differences: tuple[bool, ...]
    measured: bool
    exhaustive_limit: int
    similarity: str
    nodes: tuple[str, ...]  # candidate nodes (FMU order, exclusions removed)
    excluded: tuple[str, ...]
    rotating_nodes: bool = False  #: whether nodes of rotating parts are candidates
    rotating_excluded: tuple[str, ...] = ()  #: the rotating nodes left out by default

    @property
    def path(self) -> Path:
        return self.family.path

    @property
    def name(self) -> str:
        return self.family.name

    @property
    def design_replica(self) -> int:
        return 1

    @property
    def test_replicas(self) -> tuple[int, ...]:
        """Replicas that test the placements; the design replica if there is no other."""
        return tuple(range(2, self.family.replicas + 1)) or (1,)


def fmu_nodes(fmu: Path) -> list[str]:
    """Node names of the FMU's temperature field (``node_housing_3_C`` → ``housing_3``), but
    the five-probe model's half-section nodes: a study's recordings do not carry them (they
    are recorded with the probe outputs only), so the candidates stay what they were."""
    try:
        description = read_model_description(str(fmu), validate=False)
    except Exception as exc:
        raise SpindlebenchError(f"{fmu}: not a readable FMU: {exc}") from None
    nodes = [node_of_output(v.name) for v in description.modelVariables
             if v.causality == "output"]
    return [node for node in nodes if node is not None and node not in PROBE_NODES]


def _bool_or_list(table: Table, name: str) -> tuple[bool, ...]:
    raw = table.raw(name, default=False)
    values = raw if isinstance(raw, list) else [raw]
    if not values or not all(isinstance(v, bool) for v in values):
        raise table.error(name, f"must be true, false or a list of them, got {raw!r}")
    if len(set(values)) != len(values):
        raise table.error(name, "lists a value twice")
    return tuple(values)


def _reject_sweep_only(data: dict[str, Any], family: SweepStudy) -> None:
    source = family.path
    if "methods" in data:
        raise SpindlebenchError(f"{source}: key 'methods': a placement study sets its methods "
                                "in [placement] (the sweep's [methods] table does not apply)")
    if len(family.noise) != 1:
        raise SpindlebenchError(f"{source}: key 'axes.noise': a placement study measures with "
                                f"one noise level, got {len(family.noise)}")
    if any(fault is not None for fault in family.faults):
        raise SpindlebenchError(f"{source}: key 'axes.faults': a placement study has no fault "
                                f"conditions; leave faults out or set [\"{NO_FAULT}\"]")


def load_placement_study(path: str | Path, machine: str | None = None) -> PlacementStudy:
    """Read and validate a placement study; every error names the file and the key.
    ``machine`` (``--machine``) replaces the study's machine."""
    path = Path(path)
    family = load_study(path, extra_tables=("placement",), machine=machine)
    data = load_toml(path, "study")
    _reject_sweep_only(data, family)
    if not isinstance(data.get("placement"), dict):
        raise SpindlebenchError(f"{path}: key 'placement': missing table (required)")
    table = Table(data["placement"], path, "placement")
    budgets = tuple(sorted(table.get_list(
        "budgets", int, default=[2, 3, 4, 5, 6],
        check=in_range(1, MAX_BUDGET))))
    methods = tuple(table.get_list(
        "methods", str, default=list(METHODS), check=_placement_method))
    with_differences = _bool_or_list(table, "with_differences")
    measured = table.get("measured", bool, default=True)
    limit = table.get("exhaustive_limit", int, default=DEFAULT_EXHAUSTIVE_LIMIT,
                      check=in_range(0, MAX_EXHAUSTIVE_LIMIT))
    similarity = table.get("similarity", str, default=DEFAULT_SIMILARITY,
                           check=lambda v: one_of(v, SIMILARITIES))
    excluded = table.get_list("exclude_nodes", str, default=[], allow_empty=True)
    rotating = table.get("rotating_nodes", bool, default=False)
    table.finish()

    nodes = fmu_nodes(check_fmu(family))
    if not nodes:
        raise SpindlebenchError(f"{family.fmu}: the FMU has no node_*_C outputs (no "
                                "temperature field to place sensors in)")
    unknown = [name for name in excluded if name not in nodes]
    if unknown:
        raise table.error("exclude_nodes", f"no node named '{unknown[0]}' in the FMU (nodes: "
                                           f"{', '.join(nodes[:6])}, ...)")
    turning = () if rotating else tuple(n for n in nodes if is_rotating(n) and
                                        n not in excluded)
    candidates = tuple(name for name in nodes if name not in excluded and name not in turning)
    if len(candidates) < max(budgets):
        raise table.error("budgets", f"budget {max(budgets)} exceeds the {len(candidates)} "
                                     "candidate nodes")
    return PlacementStudy(family=family, budgets=budgets, methods=methods,
                          with_differences=with_differences, measured=measured,
                          exhaustive_limit=limit, similarity=similarity, nodes=candidates,
                          excluded=tuple(excluded), rotating_nodes=rotating,
                          rotating_excluded=turning)


def describe(study: PlacementStudy) -> dict[str, Any]:
    """JSON-ready settings of the study (for provenance and the README)."""
    from spindlebench.studies.family.family_file import describe as describe_family

    out = describe_family(study.family)
    out.pop("faults", None)
    out.update(budgets=list(study.budgets), methods=list(study.methods),
               with_differences=list(study.with_differences), measured=study.measured,
               exhaustive_limit=study.exhaustive_limit, similarity=study.similarity,
               candidate_nodes=len(study.nodes), excluded_nodes=list(study.excluded),
               rotating_nodes=study.rotating_nodes,
               rotating_excluded=list(study.rotating_excluded),
               design_replica=study.design_replica, test_replicas=list(study.test_replicas))
    return out
