"""The results store's pinning: what counts as a different study, and how a refusal reads."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pandas as pd
import pytest
from spindlebench.core.errors import SpindlebenchError
from spindlebench.studies.running.store import (
    DamagedResultWarning,
    ResultStore,
    canonical,
    content_sha256,
    differences,
)

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


# ----------------------------------------------------------------- issue 25: resume integrity


def stored_study(root: Path) -> ResultStore:
    """A study folder as a sweep leaves it: state, one recording with its sidecar, one
    evaluation; returned as a fresh store (a new process resuming)."""
    store = ResultStore(root)
    store.claim(STUDY, {"fmu_sha256": "a" * 64}, command="sweep")
    store.write_recording("runs/r001/Jan.csv", pd.DataFrame({"time_s": [0.0, 60.0],
                                                            "T1_C": [20.0, 20.5]}), {"run": 1})
    store.write_frame("evals/r001/lab/Jan.csv", pd.DataFrame({"k": [2], "rmse_um": [1.5]}))
    store.unlock()
    return ResultStore(root)


def edit(path: Path) -> None:
    path.write_text(path.read_text(encoding="utf-8").replace("1.5", "0.1"), encoding="utf-8")


@pytest.mark.parametrize("manifest", ["deleted", "truncated", "a list"])
def test_a_lost_manifest_redoes_what_only_it_vouched_for_and_keeps_the_recordings(
        tmp_path, manifest):
    """Deleted, truncated or replaced manifest and an edited evaluation: the evaluation was
    resumed as if valid. Recordings keep their own checksum (their sidecar's) and are kept:
    they are the expensive part."""
    store = stored_study(tmp_path)
    path = tmp_path / "manifest.json"
    if manifest == "deleted":
        path.unlink()
    elif manifest == "truncated":
        path.write_text(path.read_text(encoding="utf-8")[:40], encoding="utf-8")
    else:
        path.write_text("[1, 2]\n", encoding="utf-8")
    edit(tmp_path / "evals/r001/lab/Jan.csv")
    with pytest.warns(DamagedResultWarning) as warned:
        assert store.claim(STUDY, {"fmu_sha256": "a" * 64}, command="sweep") is True
        assert not store.exists("evals/r001/lab/Jan.csv")
        assert store.has_recording("runs/r001/Jan.csv")
    assert [str(w.message).split(":")[0] for w in warned] == [str(path)]  # said once
    assert ("is missing" if manifest == "deleted" else "is damaged") in str(warned[0].message)


def test_a_piece_the_manifest_does_not_name_or_an_edited_sidecar_is_redone(tmp_path):
    stored_study(tmp_path)
    (tmp_path / "evals/r001/lab/Feb.csv").write_text("k,rmse_um\n2,0.1\n", encoding="utf-8")
    sidecar = tmp_path / "runs/r001/Jan.json"
    sidecar.write_text(sidecar.read_text(encoding="utf-8").replace('"run": 1', '"run": 2'),
                       encoding="utf-8")
    store = ResultStore(tmp_path)
    with pytest.warns(DamagedResultWarning, match=r"Feb\.csv: not in manifest\.json"):
        assert not store.exists("evals/r001/lab/Feb.csv")
    with pytest.warns(DamagedResultWarning, match=r"Jan\.json: damaged \(sha256"):
        assert not store.has_recording("runs/r001/Jan.csv")
    assert store.exists("evals/r001/lab/Jan.csv")


@pytest.mark.parametrize("text", ["[" * 100_000 + "]" * 100_000, "[1]", '"x"', "null", "7",
                                  '{"inputs": {"study_content_sha256": "0"}, "content": {}}'])
def test_a_hostile_state_file_is_one_line_and_leaves_nothing(tmp_path, text):
    (tmp_path / "state.json").write_text(text, encoding="utf-8")
    with pytest.raises(SpindlebenchError) as refused:
        ResultStore(tmp_path).claim(STUDY, {})
    assert str(refused.value).startswith(f"{tmp_path / 'state.json'}: ")
    assert "\n" not in str(refused.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["state.json"]  # no lock file left


def test_a_deeply_nested_manifest_is_damaged_not_a_traceback(tmp_path):
    store = stored_study(tmp_path)
    (tmp_path / "manifest.json").write_text("{" * 50_000, encoding="utf-8")
    with pytest.warns(DamagedResultWarning, match="is damaged"):
        assert not store.exists("evals/r001/lab/Jan.csv")


def test_another_commands_folder_is_refused_naming_both(tmp_path):
    store = stored_study(tmp_path)
    with pytest.raises(SpindlebenchError, match=r"holds the results of 'spindlebench sweep', "
                                                r"not of 'place'; use a new output folder"):
        store.claim(STUDY, {"fmu_sha256": "a" * 64}, command="place")


def test_a_sidecar_missing_from_the_manifest_is_recorded_as_a_whole_run_would(tmp_path):
    """A run stopped between a recording and the manifest write: resumed, its manifest had
    one entry fewer than an uninterrupted run's."""
    stored_study(tmp_path)
    path = tmp_path / "manifest.json"
    whole = path.read_bytes()
    entries = json.loads(whole)
    del entries["runs/r001/Jan.json"]
    path.write_text(json.dumps(entries, indent=1) + "\n", encoding="utf-8")
    assert ResultStore(tmp_path).has_recording("runs/r001/Jan.csv")
    assert path.read_bytes() == whole


def test_the_manifest_text_is_the_json_of_the_sorted_hashes_after_writes_and_removes(tmp_path):
    """Its entries' lines are encoded once and reused: after writes, rewrites and removes
    (names that JSON escapes among them) the file is still ``json.dumps(sorted, indent=1)``."""
    store = ResultStore(tmp_path)
    frame = pd.DataFrame({"a": [1.0, 2.0], "b": [3.0, 4.0]})
    names = ["evals/b.csv", 'evals/q"uote.csv', "evals/é.csv", "a.csv", "evals/c.csv"]
    for step, name in enumerate(names):
        store.write_frame(name, frame + step)
    store.write_frame("a.csv", frame * 10)  # rewritten: a new hash
    store.remove("evals/c.csv")
    text = (tmp_path / "manifest.json").read_text(encoding="utf-8")
    manifest = json.loads(text)
    assert sorted(manifest) == sorted(set(names) - {"evals/c.csv"})
    assert text == json.dumps(dict(sorted(manifest.items())), indent=1) + "\n"
    resumed = ResultStore(tmp_path)  # a new process: its first change is a remove
    resumed.remove("evals/b.csv")
    del manifest["evals/b.csv"]
    assert (tmp_path / "manifest.json").read_text(encoding="utf-8") == json.dumps(
        dict(sorted(manifest.items())), indent=1) + "\n"
    for name in ("a.csv", 'evals/q"uote.csv', "evals/é.csv"):
        resumed.remove(name)
    assert (tmp_path / "manifest.json").read_text(encoding="utf-8") == "{}\n"


def test_read_frames_reads_the_tables_as_concatenating_each_one_read_alone(tmp_path):
    """Tables of one header are parsed as one text; others each alone: the same values and
    CSV text as ``pd.concat`` of ``pd.read_csv`` per file, empty cells and text columns
    included; only a column empty in one file and text in another is str, not object."""
    store = ResultStore(tmp_path)
    shared = [pd.DataFrame({"replica": [1, 2], "k": pd.array([2, None], dtype="Int64"),
                            "rmse_um": [0.1 + 0.2, 1e-5], "selected": ["T1;T9", ""],
                            "error": ["", ""]}),
              pd.DataFrame({"replica": [3], "k": pd.array([4], dtype="Int64"),
                            "rmse_um": [float("nan")], "selected": ["a, b"],
                            "error": ["evaluation failed: x"]})]
    failed = pd.DataFrame({"replica": [4], "error": ["evaluation failed: y"]})
    for tables in (shared, [*shared, failed]):
        names = [f"t{number}.csv" for number in range(len(tables))]
        for name, table in zip(names, tables, strict=True):
            store.write_frame(name, table)
        expected = pd.concat([pd.read_csv(tmp_path / name) for name in names],
                             ignore_index=True)
        read = store.read_frames(names)
        pd.testing.assert_frame_equal(read, expected, check_exact=True, check_dtype=False)
        assert [str(a) for a, b in zip(read.dtypes, expected.dtypes, strict=True) if a != b] \
            in ([], ["str"])
        store.write_frame("read.csv", read)
        store.write_frame("expected.csv", expected)
        assert (tmp_path / "read.csv").read_bytes() == (tmp_path / "expected.csv").read_bytes()


def test_read_frames_parses_the_bytes_as_the_utf8_text_read_would(tmp_path):
    """The bytes are parsed with their line ends as reading the text translates them (a
    ``\\r`` in a quoted cell, ``\\r\\n`` line ends), and text pandas reads as missing
    ("NA", "None", "nan") is missing as it was: the same frames as parsing the text."""
    store = ResultStore(tmp_path)
    texts = ['replica,selected,error\r\n1,"T1;\r\nT2",NA\r\n2,None,"évaluation, \r failed"\n',
             "replica,selected,error\n3,nan,\n4,,N/A\n"]
    for number, text in enumerate(texts):
        (tmp_path / f"t{number}.csv").write_bytes(text.encode("utf-8"))
    for names in (["t0.csv"], ["t0.csv", "t1.csv"], ["t1.csv", "t1.csv"]):
        read = store.read_frames(names)
        expected = pd.concat([pd.read_csv(io.StringIO((tmp_path / name).read_text(
            encoding="utf-8"))) for name in names], ignore_index=True)
        pd.testing.assert_frame_equal(read, expected, check_exact=True, check_dtype=False)
    assert store.read_frames(["t0.csv"])["error"].iloc[1] == "évaluation, \n failed"


def test_one_manifest_save_records_the_blocks_pieces_at_its_end(tmp_path):
    """An evaluation job's files are recorded with one save; a recording's sidecar with the
    next save or when the folder is released, its CSV vouching for it meanwhile (a resume
    records it: ``test_a_sidecar_missing_from_the_manifest_is_recorded_as_a_whole_run_would``)."""
    store = ResultStore(tmp_path)
    store.claim(STUDY, {"fmu_sha256": "a" * 64}, command="sweep")
    path = tmp_path / "manifest.json"
    before = path.read_bytes()
    frame = pd.DataFrame({"k": [2], "rmse_um": [1.5]})
    with store.one_manifest_save():
        store.write_frame("evals/a.csv", frame)
        store.write_frame("evals/b.csv", frame)
        store.remove("evals/a.error.csv")
        assert path.read_bytes() == before
    assert {"evals/a.csv", "evals/b.csv"} <= set(json.loads(path.read_bytes()))
    store.write_recording("runs/r001/Jan.csv", pd.DataFrame({"time_s": [0.0, 60.0],
                                                            "T1_C": [20.0, 20.5]}), {"run": 1})
    assert "runs/r001/Jan.json" not in json.loads(path.read_bytes())
    store.unlock()
    manifest = json.loads(path.read_bytes())
    assert "runs/r001/Jan.json" in manifest
    assert path.read_text(encoding="utf-8") == json.dumps(dict(sorted(manifest.items())),
                                                          indent=1) + "\n"


@pytest.mark.parametrize("frame", [
    pd.DataFrame({"a": [1.0, 2.5e-7], "b": [3.0, 4.0]}),  # row by row
    pd.DataFrame({"a": [1, 2], "b": ["x,y", 'q"']}),  # column by column
    pd.DataFrame({"a": [1.0, 2.0]}),  # pandas writes it
])
def test_the_manifest_hash_of_a_table_is_the_hash_of_the_file_on_disk(tmp_path, frame):
    """The store hashes a table's bytes as written, not read back: they must be the file's."""
    from spindlebench.core.provenance import sha256_file

    store = ResultStore(tmp_path)
    store.write_frame("evals/t.csv", frame)
    assert store.manifest()["evals/t.csv"] == sha256_file(tmp_path / "evals" / "t.csv")
    assert ResultStore(tmp_path).exists("evals/t.csv")
