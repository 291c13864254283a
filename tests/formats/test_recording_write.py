"""Writing a recording pair: the CSV moves into place before its sidecar, directories refused."""

import json
import os

import pandas as pd
import pytest
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.provenance import sha256_file
from spindlebench.formats.recording import write_recording

FRAME = pd.DataFrame({"time_s": [0.0, 60.0], "T1": [20.0, 20.5]})


def test_pair_is_written_with_the_csv_hash(tmp_path):
    csv = write_recording(tmp_path / "r.csv", FRAME, {"kind": "test"})
    sidecar = json.loads((tmp_path / "r.json").read_text())
    assert sidecar["recording_sha256"] == sha256_file(csv)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv", "r.json"]


@pytest.mark.parametrize("directory", ["r.csv", "r.json"])
def test_an_existing_directory_in_the_way_is_refused_before_writing(tmp_path, directory):
    (tmp_path / directory).mkdir()
    with pytest.raises(SpindlebenchError, match="is a directory"):
        write_recording(tmp_path / "r.csv", FRAME, {"kind": "test"})
    assert sorted(p.name for p in tmp_path.iterdir()) == [directory]


def test_a_failed_csv_move_leaves_the_old_pair_alone(tmp_path, monkeypatch):
    """The CSV is moved first: when that fails, the old sidecar still matches the old CSV."""
    write_recording(tmp_path / "r.csv", FRAME, {"kind": "old"})
    real_replace = os.replace

    def failing_replace(src, dst):
        if str(dst).endswith(".csv"):
            raise OSError("disk full")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", failing_replace)  # atomic_path's final move
    with pytest.raises(OSError, match="disk full"):
        write_recording(tmp_path / "r.csv", FRAME * 2, {"kind": "new"})
    sidecar = json.loads((tmp_path / "r.json").read_text())
    assert sidecar["kind"] == "old"
    assert sidecar["recording_sha256"] == sha256_file(tmp_path / "r.csv")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv", "r.json"]
