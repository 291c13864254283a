"""A population of machines: seeded draws within the FMU's bounds, machine files, the study key,
and a population sweep that says on how many machines the claim holds."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
import pytest
from conftest import FMU, REPO
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import FINGERPRINT_KEYS
from spindlebench.machines.variants import PAPER_RUNS, load_machine
from spindlebench.studies.family import population as pop
from spindlebench.studies.family.family_file import load_study
from spindlebench.testbench.runner import inspect_fmu

TINY = REPO / "scenarios" / "studies" / "tiny_sweep.toml"


def variable(start: float, unit: str, low: float | None = 0.0, high: float | None = 1e9):
    return SimpleNamespace(start=str(start), unit=unit, min=None if low is None else str(low),
                           max=None if high is None else str(high))


KNOWN = {"a_C": variable(100.0, "J/K"), "b_G": variable(2.0, "W/K", high=2.1),
         "length_L": variable(0.5, "m"), "off_G": variable(0.0, "W/K"),
         "friction_f0": variable(1.0, "1")}


def population(**changes) -> pop.Population:
    fields = dict(size=5, base="default", seed=4, default_spread=0.3)
    fields.update(changes)
    return pop.Population(**fields)


def test_a_machine_is_its_seed_and_index_alone_and_stays_within_the_declared_bounds():
    base = load_machine()
    first = pop.draw_parameters(population(size=3), base, KNOWN, 2)
    again = pop.draw_parameters(population(size=50), base, KNOWN, 2)
    assert first == again  # machine 2 of 3 is machine 2 of 50
    assert first != pop.draw_parameters(population(), base, KNOWN, 3)
    draws = [pop.draw_parameters(population(), base, KNOWN, i) for i in range(1, 200)]
    assert all(d["b_G"] <= 2.1 for d in draws)  # clipped to the declared max
    assert any(d["b_G"] == 2.1 for d in draws)
    # geometry, switched-off paths and unitless factors are not spread by default
    assert all("length_L" not in d and "off_G" not in d and "friction_f0" not in d
               for d in draws)
    logs = [math.log(d["a_C"] / 100.0) for d in draws]
    mean = sum(logs) / len(logs)
    sd = math.sqrt(sum((x - mean) ** 2 for x in logs) / (len(logs) - 1))
    assert abs(mean) < 0.1 and 0.24 < sd < 0.36  # log-normal with the asked spread


def test_patterns_spread_what_they_name_and_zero_holds_a_parameter():
    base = load_machine()
    spec = population(default_spread=0.0, patterns=(("friction_*", 0.2), ("a_C", 0.0)))
    values = pop.draw_parameters(spec, base, KNOWN, 1)
    assert set(values) == {"friction_f0"}
    with pytest.raises(SpindlebenchError, match=r"spread\.nothing_\*': matches no parameter"):
        pop.check_patterns(population(patterns=(("nothing_*", 0.1),)), KNOWN, "s.toml")


def study_text(machines: str) -> str:
    text = TINY.read_text(encoding="utf-8")
    return text.replace('faults = ["none", "T1-stuck"]', f'faults = ["none"]\nmachines = {machines}'
                        ).replace('[faults.T1-stuck]\nsensor = "T1"\nkind = "stuck"\n'
                                  'start_h = 0.25\n', "")


def write(tmp_path: Path, machines: str) -> Path:
    path = tmp_path / "study.toml"
    path.write_text(study_text(machines), encoding="utf-8")
    return path


def test_the_study_key_reads_a_population_and_names_bad_keys(tmp_path):
    study = load_study(write(tmp_path, '{ population = 4, spread = { default = 0.1, '
                                       '"front_bearing_friction_f0" = 0.2 }, seed = 9 }'))
    assert study.population is not None and study.population.size == 4
    assert study.population.patterns == (("front_bearing_friction_f0", 0.2),)
    for bad, message in (("{ population = 0 }", "axes.machines.population'"),
                         ("{ population = 3, spread = 2.0 }", "axes.machines.spread'"),
                         ("{ population = 3, sread = 0.1 }", "unknown key"),
                         ("{ population = 3, base = \"nope\" }", "axes.machines.base'"),
                         ("{ population = 3, keep = \"some\" }", "axes.machines.keep'")):
        with pytest.raises(SpindlebenchError, match=message):
            load_study(write(tmp_path, bad))


def test_keep_targets_rejects_machines_that_miss_the_base_machines_targets(tmp_path,
                                                                          monkeypatch):
    import spindlebench.studies.fingerprint.machine_check as check

    calls = []

    def fingerprints(machine, fmu):  # odd draws miss best_raw_psi <= 0.95
        assert machine.targets  # checked against the base machine's targets
        calls.append(machine.name)
        psi = 0.99 if len(calls) % 2 else 0.9
        stats = dict.fromkeys(FINGERPRINT_KEYS, 0.5)  # every target but psi's is met by
        stats.update({"best_raw_psi": psi, "best_diff_psi": 0.99, "early_fraction": 0.6,
                      "overshoot": 1.1, "t63_fastest_ratio": 0.5})  # the default's targets
        runs = {run for t in machine.targets for run in t.runs} | set(PAPER_RUNS)
        return {run: dict(stats) for run in runs}

    monkeypatch.setattr(check, "machine_fingerprints", fingerprints)
    known = inspect_fmu(FMU).parameters
    spec = population(size=2, keep="targets", source=tmp_path / "s.toml")
    members = pop.draw_population(spec, known, FMU, tmp_path, "s")
    assert [m.kept for m in members] == [False, True, False, True]
    assert "best_raw_psi" in members[0].problems[0]
    table = pd.read_csv(tmp_path / pop.TABLE_FILE)
    assert table["kept"].tolist() == [False, True, False, True]
    assert load_machine(str(members[1].path)).name == "default-p002"


@pytest.mark.slow
def test_a_population_sweep_counts_the_machines_on_which_the_claim_holds(tmp_path):
    from spindlebench.commands.main import main

    study = write(tmp_path, "{ population = 2, spread = 0.15, seed = 5 }")
    out = tmp_path / "out"
    assert main(["sweep", str(study), "-o", str(out), "--workers", "1", "--no-progress"]) == 0
    readme = (out / "README.md").read_text(encoding="utf-8")
    verdicts = pd.read_csv(out / "population_verdict.csv")
    assert sorted(set(verdicts["machine"])) == ["default-p001", "default-p002"]
    for data, at in verdicts.groupby("data"):
        lower = int(at[at["k"] == 2]["lower"].sum())
        assert f"{data}, k = 2: *lower* on {lower} of 2 machines" in readme
    files = {p.name: p.read_bytes() for p in (out / "machines").iterdir()}
    table = (out / pop.TABLE_FILE).read_bytes()
    assert main(["sweep", str(study), "-o", str(out), "--workers", "1", "--no-progress"]) == 0
    assert {p.name: p.read_bytes() for p in (out / "machines").iterdir()} == files
    assert (out / pop.TABLE_FILE).read_bytes() == table
    for name in files:  # each drawn machine is a machine file the commands read
        machine = load_machine(str(out / "machines" / name))
        assert machine.parameters and (out / machine.name / "README.md").is_file()


def _with_population(source: Path, tmp_path: Path, machines: str,
                     **lines: str) -> Path:
    """A copy of a tiny study file with ``[axes] machines`` set to ``machines`` (and each
    ``key = ...`` line of ``lines`` replaced)."""
    text = source.read_text(encoding="utf-8").replace("[axes]\n",
                                                      f"[axes]\nmachines = {machines}\n", 1)
    for key, value in lines.items():
        text = "\n".join(f"{key} = {value}" if line.startswith(f"{key} =") else line
                         for line in text.splitlines()) + "\n"
    path = tmp_path / source.name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.slow
def test_a_population_placement_counts_the_machines_on_which_differences_help(tmp_path):
    from spindlebench.commands.main import main

    study = _with_population(REPO / "scenarios" / "studies" / "tiny_placement.toml", tmp_path,
                             "{ population = 2, spread = 0.15, seed = 5 }",
                             methods='["fuzzy", "greedy"]')  # the cheap searches only
    out = tmp_path / "out"
    assert main(["place", str(study), "-o", str(out), "--workers", "0", "--no-progress"]) == 0
    rows = pd.read_csv(out / "population_placements.csv")
    assert sorted(set(rows["machine"])) == ["default-p001", "default-p002"]
    assert set(rows["method"]) == {"fuzzy", "greedy"} and rows["gain_um"].notna().all()
    readme = (out / "README.md").read_text(encoding="utf-8")
    for (method, m), at in rows.groupby(["method", "m"]):
        own = pd.read_csv(out / at["machine"].iloc[0] / "placements.csv")
        score = own[(own["method"] == method) & (own["m"] == m)].set_index("differences")
        first = at.iloc[0]
        assert first["diff_helps"] == (score.loc[True, "test_mean_rmse_um"]
                                       < score.loc[False, "test_mean_rmse_um"])
        helps = int(at["diff_helps"].sum())
        assert f"| {method} | {m} | 2 | {helps} of 2 machines" in readme


@pytest.mark.slow
def test_a_population_compensation_runs_each_machine_and_counts_them(tmp_path):
    from spindlebench.commands.main import main

    study = _with_population(REPO / "scenarios" / "studies" / "tiny_compensate.toml", tmp_path,
                             "{ population = 2, spread = 0.15, seed = 5 }")
    out = tmp_path / "out"
    assert main(["compensate", str(study), "-o", str(out), "-q"]) == 0
    rows = pd.read_csv(out / "population_compensation.csv")
    assert sorted(set(rows["machine"])) == ["default-p001", "default-p002"]
    summaries = [pd.read_csv(out / name / "summary.csv") for name in sorted(set(rows["machine"]))]
    assert not summaries[0]["rms_um"].equals(summaries[1]["rms_um"])  # two different machines
    readme = (out / "README.md").read_text(encoding="utf-8")
    for rule, at in rows.groupby("retrain", sort=False):
        assert f"| {rule} | 2 | {int(at['diff_helps'].sum())} of 2 machines" in readme
    # --machine runs the one machine into the folder itself, as for every study command
    single = tmp_path / "single"
    assert main(["compensate", str(study), "-o", str(single), "-q", "--machine", "default"]) == 0
    assert (single / "summary.csv").is_file() and not (single / "machines").exists()
