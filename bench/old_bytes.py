"""Issue 20's "old scenarios on ambient-following give the bytes they gave": where and why
today's recordings differ from those of commit 262d5e4 (docs/model.md, "Old recordings on
`ambient-following`"). Three measurements, none of them timed:

``compare OLD_DIR NEW_DIR``
    every recording (``*.csv``) of OLD_DIR against the one of the same name in NEW_DIR: header,
    measured columns (everything before the first ``true_*``) byte for byte, and the truth
    columns that differ, with the largest difference per unit (by the name's suffix).
``derivatives MODEL_DIR_A MODEL_DIR_B``
    the two Modelica sources' ``explicit_ode`` (this checkout's causaliser) evaluated at the
    same 20 points (states by name, the issue-20 mechanisms off as on ambient-following): how
    many derivatives of the states both have, and how many outputs both have, differ in a bit.
``reduced FMU OLD_CSV``
    ``scenarios/examples/quick.toml`` on ambient-following with CVode on every state but the
    five-probe model's (held at their start; FMPy's solver, patched here only), against the
    truth of OLD_CSV (the same scenario recorded at 262d5e4).
"""

from __future__ import annotations

import csv
import ctypes
import sys
import zlib
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
#: ambient-following's values where they differ from the FMU's defaults in the mechanisms.
MECHANISMS_OFF = {"front_preload_N_per_K": 0.0, "G_bearing_air_ref": 0.0, "column_C": 736000.0}


def _rows(path: Path) -> tuple[list[str], list[list[str]]]:
    with path.open(encoding="utf-8", newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], rows[1:]


def compare(old_dir: Path, new_dir: Path) -> None:
    for old_csv in sorted(old_dir.glob("*.csv")):
        header_old, old = _rows(old_csv)
        header_new, new = _rows(new_dir / old_csv.name)
        where = {name: i for i, name in enumerate(header_new)}
        first_true = next(i for i, n in enumerate(header_old) if n.startswith("true_"))
        measured = all(",".join(a[:first_true]) == ",".join(b[:first_true])
                       for a, b in zip(old, new, strict=True))
        differing, worst = 0, {}
        for j, name in enumerate(header_old[first_true:], start=first_true):
            if name not in where:
                continue
            k = where[name]
            d = [abs(float(a[j]) - float(b[k])) for a, b in zip(old, new, strict=True)
                 if a[j] != b[k]]
            if d:
                differing += 1
                unit = name.rsplit("_", 1)[-1]
                if max(d) > worst.get(unit, (0.0, ""))[0]:
                    worst[unit] = (max(d), name)
        extra = [n for n in header_new if n not in header_old]
        missing = [n for n in header_old if n not in header_new]
        print(f"{old_csv.name}: header {'same' if header_old == header_new else 'differs'}"
              f" (+{len(extra)} -{len(missing)} columns), measured columns "
              f"{'byte for byte the same' if measured else 'DIFFER'}, {differing} of "
              f"{len(header_old) - first_true} truth columns differ")
        for unit, (value, name) in sorted(worst.items()):
            print(f"    largest in {unit}: {value:.3g} ({name})")


def derivatives(model_a: Path, model_b: Path) -> None:
    from spindlebench.model.equations import explicit_ode

    odes = [explicit_ode(model) for model in (model_a, model_b)]
    values = []
    for ode in odes:
        p = np.array([MECHANISMS_OFF.get(n, v) for n, v in ode.parameters.items()])
        runs = []
        for k in range(20):
            x = ode.state_start + np.array([(zlib.crc32(f"{s}{k}".encode()) % 3000) / 100.0
                                            for s in ode.states])
            u = np.array([4000.0 * (k % 3), 1500.0, 1500.0, 20.0 + k])
            runs.append([np.array(v).ravel() for v in ode.ode(x, u, p)])
        values.append(runs)
    a, b = odes
    for part, (names_a, names_b) in enumerate(((a.states, b.states), (a.outputs, b.outputs))):
        shared = [n for n in names_a if n in names_b]
        ia, ib = {n: i for i, n in enumerate(names_a)}, {n: i for i, n in enumerate(names_b)}
        differ = sorted({n for ra, rb in zip(*values, strict=True) for n in shared
                         if ra[part][ia[n]] != rb[part][ib[n]]})
        what = "derivatives" if part == 0 else "outputs"
        print(f"{what}: {len(differ)} of the {len(shared)} both have differ in a bit at 20 "
              f"points{': ' + ', '.join(differ) if differ else ''}")
    print(f"CasADi instructions: {a.ode.n_instructions()} and {b.ode.n_instructions()}")


def reduced(fmu_path: Path, old_csv: Path) -> None:
    import fmpy.sundials as sundials
    from spindlebench.formats.recording import PROBE_NODES
    from spindlebench.testbench import runner
    from spindlebench.testbench.scenario import load_scenario, with_machine

    info = runner.inspect_fmu(fmu_path)
    n = len(info.state_names)
    held = [i for i, s in enumerate(info.state_names) if s.removesuffix("_T") in PROBE_NODES]
    kept = [i for i in range(n) if i not in held]
    full = (ctypes.c_double * n)()
    solver = sundials.CVodeSolver

    class Reduced(solver):  # CVode on the kept states; the FMU always gets all n
        def __init__(self, nx, nz, get_x, set_x, get_dx, get_z, get_nominals, **options):
            def gather(get):
                def callback(pointer, _size):
                    values = (ctypes.c_double * n)()
                    get(values, n)
                    for j, i in enumerate(kept):
                        pointer[j] = values[i]
                return callback

            def set_kept(pointer, _size):
                get_x(full, n)
                for j, i in enumerate(kept):
                    full[i] = pointer[j]
                set_x(full, n)

            super().__init__(nx - len(held), nz, gather(get_x), set_kept, gather(get_dx),
                             get_z, gather(get_nominals), **options)

    sundials.CVodeSolver = Reduced
    try:
        scenario = with_machine(load_scenario(REPO / "scenarios/examples/quick.toml"),
                                "ambient-following")
        simulation = runner.co_simulate(scenario, fmu_path, native_rhs=False)
    finally:
        sundials.CVodeSolver = solver
    header, rows = _rows(old_csv)
    truth = [(j, n) for j, n in enumerate(header) if n.startswith("true_")]
    differ = [n for j, n in truth if not np.array_equal(
        np.array([float(r[j]) for r in rows]), simulation.outputs[n.removeprefix("true_")])]
    print(f"CVode on {len(kept)} of {n} states ({', '.join(info.state_names[i] for i in held)} "
          f"held): {len(differ)} of {len(truth)} truth columns differ from {old_csv.name}")


if __name__ == "__main__":
    command, *paths = sys.argv[1:]
    {"compare": compare, "derivatives": derivatives, "reduced": reduced}[command](
        *map(Path, paths))
