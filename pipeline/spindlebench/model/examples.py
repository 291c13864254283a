"""The ``SpindleBench.Examples`` models: simulated through the build's own path, kept as references.

Each example is translated and causalised exactly as the machine is for its FMU (pymoca →
CasADi → ``ExplicitOde``) and integrated directly with SciPy's BDF over its ``experiment``
annotation: what an example checks is the Modelica components and that path, and an FMU per
example would add only a compile. Its reference result (every output, one row per
``Interval``) sits beside the model, as in the Modelica Standard Library, and is written once by::

    python -m spindlebench.model.examples --write-references

``tests/model/test_model_examples.py`` simulates each example again, compares it with its reference
and, where there is one, with the analytical solution.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spindlebench.core.atomic import atomic_path
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import MODELS_DIR, allow_shipped
from spindlebench.formats.recording import TIME_COLUMN
from spindlebench.model import MODEL_FILE

#: The package of the examples inside ``SpindleBench.mo``.
EXAMPLES_PACKAGE = "SpindleBench.Examples"
#: Where the reference results live, under the model folder (the MSL's layout).
REFERENCE_DIR = Path("Resources") / "Reference" / "SpindleBench" / "Examples"
#: The time column of a reference file.
TIME = TIME_COLUMN


@dataclass(frozen=True)
class Experiment:
    """An example's ``annotation(experiment(...))``: the run the reference is made of."""

    start_s: float
    stop_s: float
    interval_s: float
    tolerance: float

    @property
    def times(self) -> np.ndarray:
        count = round((self.stop_s - self.start_s) / self.interval_s)
        return self.start_s + self.interval_s * np.arange(count + 1)


def example_names(model_dir: str | Path = MODELS_DIR) -> list[str]:
    """The examples' class names, in the order of the source."""
    return list(_examples(model_dir).classes)


def experiment(name: str, model_dir: str | Path = MODELS_DIR) -> Experiment:
    """The ``experiment`` annotation of example ``name`` (all four entries are required)."""
    cls = _examples(model_dir).classes.get(name)
    path = Path(model_dir) / MODEL_FILE
    if cls is None:
        raise SpindlebenchError(f"{path}: no example {EXAMPLES_PACKAGE}.{name}")
    entries: dict[str, float] = {}
    for argument in getattr(cls.annotation, "arguments", []):
        modification = argument.value
        if str(modification.component) != "experiment":
            continue
        for inner in modification.modifications[0].arguments:
            entries[str(inner.value.component)] = float(inner.value.modifications[0].value)
    keys = ("StartTime", "StopTime", "Interval", "Tolerance")
    missing = [key for key in keys if key not in entries]
    if missing:
        raise SpindlebenchError(f"{path}: example {name}: experiment annotation needs "
                                f"{', '.join(missing)}")
    return Experiment(*(entries[key] for key in keys))


def simulate(name: str, model_dir: str | Path = MODELS_DIR) -> dict[str, np.ndarray]:
    """Every output of example ``name`` on its experiment's time grid (``TIME`` first)."""
    import casadi as ca
    from scipy.integrate import solve_ivp

    from spindlebench.model.equations import explicit_ode

    run = experiment(name, model_dir)
    ode = explicit_ode(model_dir, model_class=f"{EXAMPLES_PACKAGE}.{name}")
    x, u, p = ode.symbols
    xdot, y = ode.ode(x, u, p)
    inputs, params = ca.DM(ode.input_start), ca.DM(ode.parameter_vector())
    rhs = ca.Function("rhs", [x], [ca.substitute([xdot], [u, p], [inputs, params])[0]])
    jac = ca.Function("rhs_x", [x], [ca.jacobian(rhs(x), x)])
    out = ca.Function("out", [x], [ca.substitute([y], [u, p], [inputs, params])[0]])
    times = run.times
    solution = solve_ivp(lambda _, s: np.asarray(rhs(s)).ravel(), (run.start_s, run.stop_s),
                         ode.state_start, method="BDF", t_eval=times,
                         jac=lambda _, s: np.asarray(jac(s)), rtol=run.tolerance,
                         atol=run.tolerance)
    if not solution.success:
        raise SpindlebenchError(f"example {name}: integration failed: {solution.message}")
    values = np.column_stack([np.asarray(out(solution.y[:, k])).ravel()
                              for k in range(len(times))])
    return {TIME: times} | {output: values[i] for i, output in enumerate(ode.outputs)}


def reference_path(name: str, model_dir: str | Path = MODELS_DIR) -> Path:
    return Path(model_dir) / REFERENCE_DIR / f"{name}.csv"


def write_reference(name: str, model_dir: str | Path = MODELS_DIR) -> Path:
    """Simulate example ``name`` and write its reference CSV (17 significant digits)."""
    result = simulate(name, model_dir)
    path = reference_path(name, model_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [",".join(result)]
    rows = np.column_stack(list(result.values()))
    lines += [",".join(f"{value:.17g}" for value in row) for row in rows]
    with allow_shipped(path), atomic_path(path) as temporary:  # the command's one purpose
        Path(temporary).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def read_reference(name: str, model_dir: str | Path = MODELS_DIR) -> dict[str, np.ndarray]:
    """The reference CSV of example ``name``: column → values."""
    path = reference_path(name, model_dir)
    if not path.is_file():
        raise SpindlebenchError(f"{path}: no reference result (write it with python -m "
                                "spindlebench.model.examples --write-references)")
    header, *rows = path.read_text(encoding="utf-8").splitlines()
    table = np.array([[float(cell) for cell in row.split(",")] for row in rows])
    return {column: table[:, i] for i, column in enumerate(header.split(","))}


def _examples(model_dir: str | Path):
    import pymoca.parser

    from spindlebench.model.frontend import model_source

    tree = pymoca.parser.parse(model_source(model_dir).read_text(encoding="utf-8"))
    package = tree
    for part in EXAMPLES_PACKAGE.split("."):
        package = getattr(package, "classes", {}).get(part)
        if package is None:
            raise SpindlebenchError(f"{Path(model_dir) / MODEL_FILE}: no package "
                                    f"{EXAMPLES_PACKAGE}")
    return package


def main(argv: list[str]) -> int:
    if argv != ["--write-references"]:
        print("usage: python -m spindlebench.model.examples --write-references", file=sys.stderr)
        return 2
    for name in example_names():
        print(write_reference(name))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
