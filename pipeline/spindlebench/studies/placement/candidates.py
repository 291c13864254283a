"""From simulated recordings to candidate rises: the virtual sensors a placement can use.

A candidate is a node of the model's temperature field (recording column
``true_node_<node>_C``) or, with differences, ``A-B`` of two nodes, exactly as the selection
pipeline builds them (``selection.CandidateSet``: raw columns, then every pair in order).

Virtual sensors are measured like real ones: with ``measured = true`` the node temperatures go
through the study's noise level (white noise and the logger's quantisation, the testbench's
``measure``), seeded per replica and run; the drift is the recording's probe reading. A
placement chosen on noise-free temperatures would trust differences of nodes a few
millikelvin apart, which no real sensor resolves.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.recording import DRIFT_COLUMN, TIME_COLUMN, node_column, true_column
from spindlebench.selection import CandidateSet
from spindlebench.selection.differences import pair_indices
from spindlebench.selection.pairs import PairCandidates
from spindlebench.selection.regression import rises
from spindlebench.studies.family.experiments import Experiment, sensor_model
from spindlebench.studies.family.seeds import derive_seed
from spindlebench.studies.placement.placement_file import PlacementStudy
from spindlebench.studies.placement.search import Block
from spindlebench.testbench.sensors import measure

TARGET = DRIFT_COLUMN


@dataclass(frozen=True)
class Run:
    """One experiment on one replica's day, as the placement's instruments see it.

    The node readings are kept as rises in an array (samples x nodes, ``study.nodes``
    order), not as a DataFrame: the searches and the scoring take a few candidate columns
    of every run many times, and gathering them from a frame by name cost more than the
    arithmetic.
    """

    replica: int
    experiment: Experiment
    node_rises: np.ndarray  # node rises (K, measured or true), zero at the first sample
    #: The target's probe reading, zeroed at the first sample (``drift_um`` unless the
    #: study's ``targets`` name another; a tilt is in µrad).
    drift_um: np.ndarray
    true_drift_um: np.ndarray  # the target's true rise

    @property
    def key(self) -> tuple[int, str]:
        return (self.replica, self.experiment.id)

    def __len__(self) -> int:
        return self.node_rises.shape[0]


def node_seed(study: PlacementStudy, replica: int, experiment: Experiment) -> int:
    return derive_seed(study.family.seed, "placement-nodes", replica, experiment.id)


def prepare_run(study: PlacementStudy, replica: int, experiment: Experiment,
                frame: pd.DataFrame, target: str = TARGET) -> Run:
    """The run's candidate nodes (measured or true), the target's probe reading and true
    rise. The nodes are measured with the node seed alone, so every target of a study sees
    the same node readings."""
    columns = [node_column(node) for node in study.nodes]
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise SpindlebenchError(f"recording of {experiment.id} (replica {replica}) lacks "
                                f"{missing[0]}: was it made by another FMU?")
    true_C = frame.loc[:, columns].to_numpy(dtype=float)
    true_drift = frame[true_column(DRIFT_COLUMN)].to_numpy(dtype=float)
    if target not in frame.columns:
        raise SpindlebenchError(f"recording of {experiment.id} (replica {replica}) lacks the "
                                f"target {target}: was it simulated without the probes?")
    if study.measured:
        model = sensor_model(study.family.noise[0], None)
        values, _ = measure(model, frame[TIME_COLUMN].to_numpy(float), true_C, true_drift,
                            tuple(study.nodes), node_seed(study, replica, experiment))
    else:
        values = true_C
    true_target = true_drift if target == DRIFT_COLUMN else \
        frame[true_column(target)].to_numpy(dtype=float)
    return Run(replica, experiment, rises(values), frame[target].to_numpy(dtype=float),
               true_target - true_target[0])


def candidate_set(study: PlacementStudy, differences: bool) -> CandidateSet:
    return CandidateSet(tuple(study.nodes), differences)


def candidate_columns(run_rises: np.ndarray, differences: bool,
                      columns: Sequence[int] | None = None) -> np.ndarray:
    """Values of candidates ``columns`` (default: every one) of node rises ``run_rises``:
    the nodes, then (with ``differences``) every ``A-B``, bit for bit the columns
    ``CandidateSet.matrix`` forms from the same readings (same subtraction)."""
    n = run_rises.shape[1]
    n_candidates = n * (n + 1) // 2 if differences else n
    wanted = np.arange(n_candidates) if columns is None else np.asarray(columns, dtype=np.intp)
    if wanted.size and (wanted.min() < 0 or wanted.max() >= n_candidates):
        raise SpindlebenchError(f"candidate index out of range 0..{n_candidates - 1}")
    if not differences:
        return np.ascontiguousarray(run_rises[:, wanted])
    return PairCandidates(run_rises).columns(wanted)


def stacked_rises(runs: Sequence[Run]) -> np.ndarray:
    """The node rises of ``runs``, stacked run by run (samples x nodes)."""
    if not runs:
        raise SpindlebenchError("no runs to build candidates from")
    return np.vstack([run.node_rises for run in runs])


def block(runs: Sequence[Run], differences: bool,
          columns: Sequence[int] | None = None, truth: bool = False) -> Block:
    """Rises of candidates ``columns`` (default: every candidate) of ``runs``, stacked run
    by run. Every candidate is n(n+1)/2 columns with differences: ask for the few a fit or a
    score needs.

    ``truth`` puts the true drift rise into ``y`` instead of the probe reading.
    """
    X = candidate_columns(stacked_rises(runs), differences, columns)
    y = np.concatenate([run.true_drift_um if truth else run.drift_um for run in runs])
    lengths = np.array([len(run) for run in runs])
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.intp)
    return Block(X, y, starts)


def physical_nodes(candidates: CandidateSet, columns: Sequence[int]) -> list[str]:
    """The nodes that carry a sensor for ``columns`` (a difference needs both of its nodes)."""
    n = len(candidates.sensors)
    first, second = pair_indices(n)
    out: list[str] = []
    for column in map(int, columns):
        if column < n:
            parts = [candidates.sensors[column]]
        else:
            pair = column - n
            parts = [candidates.sensors[first[pair]], candidates.sensors[second[pair]]]
        out.extend(part for part in parts if part not in out)
    return out
