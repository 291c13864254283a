"""Several targets in study files (issue 21 item 4): ``[study] targets`` read once, the runs
record the five probes, the placement's joint sets are one set scored for every target (the
sweep's and the compensation's several targets: test_multi_target_sweep.py and
test_multi_target_compensation.py)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from conftest import REPO
from spindlebench.core.errors import SpindlebenchError

TINY = REPO / "scenarios" / "studies" / "tiny_placement.toml"
TARGETS = ["drift_um", "drift_y_um", "tilt_a_urad"]


def with_targets(tmp_path, targets: str, source=TINY):
    text = source.read_text().replace('climate = "chongqing"',
                                      f'climate = "chongqing"\ntargets = {targets}', 1)
    path = tmp_path / "study.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    from spindlebench.studies.placement.placement_file import load_placement_study

    return load_placement_study(with_targets(tmp_path_factory.mktemp("study"), str(TARGETS)))


def test_study_targets_are_read_once_and_make_the_runs_record_the_probes(study, tmp_path):
    from spindlebench.studies.family.experiments import experiments, scenario_for
    from spindlebench.studies.family.family_file import load_study

    assert study.family.targets == tuple(TARGETS) and study.family.probes
    first = experiments(study.family)[0]
    assert scenario_for(study.family, 1, first).probes
    plain = load_study(TINY, extra_tables=("placement",))
    assert plain.targets == ("drift_um",) and not scenario_for(plain, 1, first).probes
    with pytest.raises(SpindlebenchError, match=r"study.targets.*tilt_c_urad"):
        load_study(with_targets(tmp_path, '["tilt_c_urad"]'), extra_tables=("placement",))


def _runs(study, rng, weights, n_runs):
    """Synthetic runs: independent node rises (random walks, so a refit recovers the
    weights), each target linear in its own nodes plus noise."""
    from spindlebench.studies.family.experiments import experiments
    from spindlebench.studies.placement.candidates import Run

    n = len(study.nodes)
    out = {t: [] for t in weights}
    for _, experiment in zip(range(n_runs), experiments(study.family), strict=False):
        nodes = np.cumsum(0.1 * rng.standard_normal((60, n)), axis=0)
        nodes -= nodes[0]
        for target, w in weights.items():
            y = nodes @ w + 0.02 * rng.standard_normal(len(nodes))
            out[target].append(Run(1, experiment, nodes, y, y))
    return out


def test_joint_placements_are_one_set_scored_for_every_target(study):
    from spindlebench.selection import CandidateSet
    from spindlebench.studies.placement.joint import joint_placements, joint_table
    from spindlebench.studies.placement.placements import _placement, score_placement

    rng = np.random.default_rng(2)
    n = len(study.nodes)
    weights = {}
    for number, target in enumerate(TARGETS):
        w = np.zeros(n)
        w[[number, 10 + number]] = [2.0, -1.0]
        weights[target] = w
    design = _runs(study, rng, weights, 4)
    test = _runs(study, rng, weights, 4)
    candidates = CandidateSet(tuple(study.nodes), False)
    outcomes = {}
    for number, target in enumerate(TARGETS):
        own = [_placement("greedy", False, 2, candidates, [number, 10 + number], 0.0, 0.0)]
        outcomes[target] = SimpleNamespace(
            placements=own, runs={study.design_replica: (design[target][:1], design[target][1:]),
                                  **{r: (test[target][:1], test[target][1:])
                                     for r in study.test_replicas}})
    study_only = study.__class__(**{**study.__dict__, "budgets": (2,),
                                    "with_differences": (False,)})
    work = SimpleNamespace(study=study_only)
    joint = joint_placements(work, outcomes)
    union = next(p for p in joint if p.label == "union:greedy")
    assert union.columns == (0, 1, 2, 10, 11, 12)
    lasso = next(p for p in joint if p.label == "mtlasso")
    from spindlebench.selection.multi_output import MultiTaskLassoSelector

    train_X = design[TARGETS[0]][0].node_rises  # the design replica's training run
    train_Y = np.column_stack([design[t][0].drift_um for t in TARGETS])
    assert lasso.columns == tuple(MultiTaskLassoSelector(2).fit(train_X, train_Y).selected_)
    table = joint_table(work, outcomes, joint)
    row = table[table["label"] == "union:greedy"].iloc[0]
    for target in TARGETS:  # the union holds each target's own nodes: it predicts each
        scores = [r["rmse_um"] for replica in study.test_replicas
                  for r in score_placement(study, union, *outcomes[target].runs[replica])]
        assert row[f"test_mean_rmse_{target}"] == pytest.approx(np.mean(scores))
        assert row[f"test_mean_rmse_{target}"] < 0.1


def test_a_population_study_with_several_targets_is_one_line(tmp_path):
    from spindlebench.studies.family.family_file import load_study

    source = REPO / "scenarios" / "studies" / "population_stable_room.toml"
    text = source.read_text().replace("[study]\n", f"[study]\ntargets = {TARGETS}\n", 1)
    path = tmp_path / "population.toml"
    path.write_text(text)
    with pytest.raises(SpindlebenchError, match=r"key 'study\.targets': a population study"):
        load_study(path)
    load_study(source)  # one target: as before
