"""The results store's pinning: what counts as a different study, and how a refusal reads."""

from __future__ import annotations

import json

import pytest
from spindlebench.core.errors import SpindlebenchError
from spindlebench.studies.running.store import ResultStore, canonical, content_sha256, differences

STUDY = {"study file": {"study": {"seed": 7, "replicas": 2}, "axes": {"speeds_rpm": [2000.0]}},
         "climate file": {"months": {"Jan": {"low_C": 5.8, "high_C": 9.8}}}}


def test_content_hash_ignores_key_order_and_number_spelling():
    reordered = {"climate file": STUDY["climate file"],
                 "study file": {"axes": {"speeds_rpm": [2000]},
                                "study": {"replicas": 2, "seed": 7}}}
    assert content_sha256(reordered) == content_sha256(STUDY)
    assert canonical({"a": (1.0, 1.5, True)}) == {"a": [1, 1.5, True]}
    changed = json.loads(json.dumps(STUDY))
    changed["study file"]["study"]["seed"] = 8
    assert content_sha256(changed) != content_sha256(STUDY)


def test_differences_name_section_key_and_values():
    new = json.loads(json.dumps(STUDY))
    new["study file"]["study"]["seed"] = 8
    del new["study file"]["study"]["replicas"]
    new["climate file"]["months"]["Jan"]["low_C"] = 6.0
    assert differences(STUDY, new) == [
        "climate file key 'months.Jan.low_C': 5.8 → 6.0",
        "study file key 'study.replicas': 2 → (absent)",
        "study file key 'study.seed': 7 → 8",
    ]


def test_claim_resumes_same_content_and_refuses_other(tmp_path):
    store = ResultStore(tmp_path / "out")
    assert store.claim(STUDY, {"fmu_sha256": "a" * 64}) is False
    assert store.claim(STUDY, {"fmu_sha256": "a" * 64}) is True
    many = json.loads(json.dumps(STUDY))
    many["study file"]["study"].update(seed=1, replicas=3, name="x", climate="y")
    with pytest.raises(SpindlebenchError, match=r"different study \(study file key "
                       r"'study.climate': \(absent\) → \"y\"; .*; and 1 more\); use a new"):
        store.claim(many, {"fmu_sha256": "a" * 64})
    with pytest.raises(SpindlebenchError, match=r"different FMU \(sha256 aaaaaaaaaaaa… vs "
                                                r"bbbbbbbbbbbb…\)"):
        store.claim(STUDY, {"fmu_sha256": "b" * 64})


def test_a_broken_state_file_is_one_line(tmp_path):
    (tmp_path / "state.json").write_text('{"inputs": [1]}')
    with pytest.raises(SpindlebenchError, match=r"state\.json: not a study state file"):
        ResultStore(tmp_path).claim(STUDY, {})
