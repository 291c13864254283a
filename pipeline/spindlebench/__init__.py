"""spindlebench: a Modelica/FMU testbench for machine-tool thermal-error modelling.

Two halves: a synthetic machine (Modelica thermal network -> FMU -> co-simulated recordings)
and the temperature-sensitive point selection pipeline of Xu et al. (2023) that runs on any
recording, synthetic or real.

The public API is what this module names (``__all__``); README and notebooks use only it and
the commands. ``import spindlebench`` stays cheap: the functions below import their
implementation when called, and every other public name is imported from its home on first
use (PEP 562 ``__getattr__``, ``_HOMES``).

Examples
--------
>>> import spindlebench
>>> spindlebench.parse_method("kmeans+grey").label
'kmeans+grey'
>>> sorted(spindlebench.load_scenario(spindlebench.SCENARIOS_DIR / "paper" / "exp1.toml")
...        .__dataclass_fields__)[:3]
['ambient', 'cooling', 'description']
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    import pandas as pd
    from sklearn.pipeline import Pipeline

    from spindlebench.machines.variants import Machine
    from spindlebench.selection.evaluate import Evaluation
    from spindlebench.selection.registry import MethodChoice
    from spindlebench.testbench.scenario import Scenario

__version__ = "0.1.0"

#: The building blocks the course and the README show beside the functions below: each
#: public name and the module that defines it, imported on first use.
_HOMES: dict[str, str] = {
    "PAPER_SIX": "spindlebench.core.names",
    "SENSORS": "spindlebench.core.names",
    "SCENARIOS_DIR": "spindlebench.core.paths",
    "DEFAULT_FMU": "spindlebench.core.paths",
    "SpindlebenchError": "spindlebench.core.errors",
    "default_sensors": "spindlebench.formats.recording",
    "read_table": "spindlebench.formats.recording",
    "METHOD_REGISTRY": "spindlebench.selection.method_registry",
    "rises": "spindlebench.selection.regression",
    "correlation_with": "spindlebench.selection.similarity",
    "similarity_matrix": "spindlebench.selection.similarity",
    "transitive_closure": "spindlebench.selection.closure",
    "cut_for_clusters": "spindlebench.selection.cut",
    "with_differences": "spindlebench.selection.differences",
    "make_selection_pipeline": "spindlebench.selection.estimators",
    "linkage_from_similarity": "spindlebench.selection.hierarchy",
    "cut_height": "spindlebench.studies.paper.figures",
    "draw_machine": "spindlebench.studies.placement.schematic",
    "node_positions": "spindlebench.studies.placement.schematic",
}

__all__ = ["__version__", "load_scenario", "simulate", "read_recording", "write_recording",
           "evaluate", "make_pipeline", "parse_method", "load_machine", "fingerprint",
           *_HOMES]


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'spindlebench' has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_HOMES))


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Read and check a scenario TOML file.

    Parameters
    ----------
    path : str or path-like
        The scenario file (``scenarios/`` holds examples, e.g. ``paper/exp1.toml``).

    Returns
    -------
    testbench.scenario.Scenario
        Every key read and checked; a bad value raises ``SpindlebenchError`` naming the file
        and the key.

    Examples
    --------
    >>> from spindlebench import SCENARIOS_DIR, load_scenario
    >>> scenario = load_scenario(SCENARIOS_DIR / "paper" / "exp1.toml")
    >>> scenario.name, scenario.duration_s
    ('exp1', 21600.0)
    """
    from spindlebench.testbench.scenario import load_scenario as load

    return load(path)


def simulate(scenario: Scenario | str | os.PathLike[str], fmu: str | os.PathLike[str] | None = None,
             seed: int | None = None) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Co-simulate a scenario with the FMU and measure it; nothing is written.

    Parameters
    ----------
    scenario : Scenario or path
        A loaded scenario (``load_scenario``) or its file.
    fmu : path, optional
        The FMU (default ``fmus/SpindleBench.fmu``).
    seed : int, optional
        Replaces the scenario's sensor seed.

    Returns
    -------
    frame : pandas.DataFrame
        The recording (``time_s``, ``T1`` ... ``T20``, ``drift_um``, the driver inputs and the
        noise-free ``true_...`` columns).
    sidecar : dict
        Its provenance; ``write_recording(path, frame, sidecar)`` writes both.

    Examples
    --------
    >>> import dataclasses
    >>> from spindlebench import SCENARIOS_DIR, load_scenario, simulate
    >>> scenario = load_scenario(SCENARIOS_DIR / "paper" / "exp1.toml")
    >>> short = dataclasses.replace(scenario, duration_s=600.0, step_s=60.0,
    ...                             sample_interval_s=60.0)
    >>> frame, sidecar = simulate(short)
    >>> len(frame), float(frame["time_s"].iloc[-1])
    (11, 600.0)
    """
    from spindlebench.testbench.scenario import load_scenario as load
    from spindlebench.testbench.simulate import record

    if isinstance(scenario, (str, os.PathLike)):
        scenario = load(scenario)
    return record(scenario, fmu, seed)


def read_recording(path: str | os.PathLike[str], **options: Any) -> pd.DataFrame:
    """Read and check one recording CSV (real or synthetic); every column float64.

    Parameters
    ----------
    path : str or path-like
        The CSV file.
    **options
        ``allow_missing``, ``columns``, ``delimiter``, ``decimal`` of
        ``formats.recording.read_recording``.

    Returns
    -------
    pandas.DataFrame
        The recording; a bad cell raises ``SpindlebenchError`` naming file, line and column.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from spindlebench import read_recording
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "r.csv").write_text("time_s,T1,drift_um\\n0,20,0\\n60,20.5,1.5\\n")
    >>> read_recording(folder / "r.csv")["drift_um"].tolist()
    [0.0, 1.5]
    """
    from spindlebench.formats.recording import read_recording as read

    return read(path, **options)


def write_recording(path: str | os.PathLike[str], frame: pd.DataFrame,
                    sidecar: Mapping[str, Any]) -> Path:
    """Write a recording CSV and its JSON sidecar atomically; return the CSV's path.

    Parameters
    ----------
    path : str or path-like
        The CSV file; the sidecar is the same name with ``.json``.
    frame : pandas.DataFrame
        The recording (``simulate``'s frame, or your own columns).
    sidecar : mapping
        Provenance; the writer adds the CSV's SHA-256 as ``recording_sha256``.

    Examples
    --------
    >>> import json, tempfile, pathlib
    >>> import pandas as pd
    >>> from spindlebench import write_recording
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> frame = pd.DataFrame({"time_s": [0.0, 60.0], "T1": [20.0, 20.5]})
    >>> csv = write_recording(folder / "r.csv", frame, {"source": "example"})
    >>> sorted(json.loads(csv.with_suffix(".json").read_text()))
    ['recording_sha256', 'source']
    """
    from spindlebench.formats.recording import write_recording as write

    return write(path, frame, dict(sidecar))


def evaluate(train: Any, tests: Any, target: str, **options: Any) -> Evaluation:
    """Select sensors on a training recording, fit, and score on held-out recordings.

    Parameters
    ----------
    train : path, DataFrame or RecordingTable
        The training experiment.
    tests : one of those, a sequence or a mapping name -> one of those
        The held-out experiments.
    target : str
        The error column (e.g. ``drift_um``).
    **options
        ``sensors``, ``k``, ``differences``, ``similarity``, ``method`` (a label such as
        ``"kmeans+grey+ridge"``), ``seed`` ... of ``selection.evaluate.evaluate``.

    Returns
    -------
    selection.evaluate.Evaluation
        ``selected``, ``rmse_um``, ``predictions``; ``to_dict()`` is ``evaluate --json``'s shape.

    Examples
    --------
    >>> import numpy as np, pandas as pd
    >>> from spindlebench import evaluate
    >>> t = np.arange(0.0, 3600.0, 60.0)
    >>> def run(a):
    ...     heat = a * (1 - np.exp(-t / 900))
    ...     return pd.DataFrame({"time_s": t, "T1": 20 + heat, "T2": 20 + 0.1 * np.sin(t),
    ...                          "drift_um": 4 * heat})
    >>> result = evaluate(run(1.0), {"b": run(2.0)}, "drift_um", sensors=["T1", "T2"], k=1)
    >>> result.selected, round(result.rmse_um["b"], 6)
    (['T1'], 0.0)
    """
    from spindlebench.selection.evaluate import evaluate as run

    return run(train, tests, target, **options)


def parse_method(label: str) -> MethodChoice:
    """A method label ``method[+within][+regressor]`` as a checked ``MethodChoice``.

    Parameters
    ----------
    label : str
        E.g. ``closure`` (the paper's), ``kmeans+grey``, ``lasso+ridge``;
        ``spindlebench methods`` lists the names.

    Returns
    -------
    selection.registry.MethodChoice

    Examples
    --------
    >>> from spindlebench import parse_method
    >>> choice = parse_method("ward+grey+pls")
    >>> choice.method, choice.within, choice.regressor, choice.clustered
    ('ward', 'grey', 'pls', True)
    """
    from spindlebench.selection.registry import parse_method as parse

    return parse(label)


def make_pipeline(method: str | MethodChoice | None = None, k: int = 2, *,
                  differences: bool = False, **options: Any) -> Pipeline:
    """The scikit-learn ``Pipeline`` of a method: (differences) -> selector -> regressor.

    Parameters
    ----------
    method : str or MethodChoice, optional
        A label (``parse_method``) or a parsed choice; default the paper's method.
    k : int
        How many candidates the selector keeps.
    differences : bool
        Whether pairwise differences of the inputs are candidates too.
    **options
        ``similarity``, ``random_state`` of ``selection.registry.make_pipeline``.

    Returns
    -------
    sklearn.pipeline.Pipeline
        Feed it rises (``rises(X)``), not raw temperatures.

    Examples
    --------
    >>> from spindlebench import make_pipeline
    >>> list(make_pipeline("kmeans+grey+pls", k=2, differences=True).named_steps)
    ['differences', 'select', 'regress']
    """
    from spindlebench.selection.registry import MethodChoice
    from spindlebench.selection.registry import make_pipeline as make
    from spindlebench.selection.registry import parse_method as parse

    if method is None:
        choice = MethodChoice()
    else:
        choice = method if isinstance(method, MethodChoice) else parse(method)
    return make(choice, k, differences=differences, **options)


def load_machine(name: str = "default", source: str | os.PathLike[str] | None = None) -> Machine:
    """A machine variant by name (``scenarios/machines/NAME.toml``) or path.

    Parameters
    ----------
    name : str
        A shipped variant's name or a machine file's path.
    source : path, optional
        The file that names it (relative paths are read from its folder; errors name it).

    Returns
    -------
    machines.variants.Machine
        Its parameter values (``parameters``) and fingerprint targets.

    Examples
    --------
    >>> from spindlebench import load_machine
    >>> load_machine().name
    'default'
    """
    from spindlebench.machines.variants import load_machine as load

    return load(name, source)


def fingerprint(time_s: np.ndarray | Sequence[float], temperatures: Any,
                error: Any) -> dict[str, float]:
    """The thermal fingerprint statistics of one recording.

    Parameters
    ----------
    time_s : array (n,)
        Sample times in seconds.
    temperatures : array (n, m)
        Temperatures in any offset unit (°C or K).
    error : array (n,)
        The thermal error in any length unit.

    Returns
    -------
    dict
        The statistics under ``core.names.FINGERPRINT_KEYS`` (``spindlebench fingerprint
        --json``'s keys).

    Examples
    --------
    >>> import numpy as np
    >>> from spindlebench import fingerprint
    >>> t = np.arange(100.0)
    >>> stats = fingerprint(t, np.column_stack([1 - np.exp(-t / 10), t / 100]),
    ...                     1 - np.exp(-t / 10))
    >>> round(stats["best_raw_psi"], 6)
    1.0
    """
    from spindlebench.studies.fingerprint.statistics import fingerprint as statistics

    return statistics(time_s, temperatures, error)
