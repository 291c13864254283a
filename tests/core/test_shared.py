"""Shared helpers: atomic writes and provenance."""

import pytest
from spindlebench.core import atomic, provenance


def test_atomic_write_leaves_old_file_on_failure(tmp_path):
    target = tmp_path / "out.csv"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic.atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("crash mid-write")
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]


def test_atomic_write_text_replaces(tmp_path):
    target = tmp_path / "sub" / "a.txt"
    atomic.write_text(target, "new")
    assert target.read_text() == "new"


def test_provenance_has_versions_and_fields(tmp_path):
    f = tmp_path / "x.bin"
    f.write_bytes(b"abc")
    record = provenance.provenance(seed=3, input=provenance.file_entry(f))
    assert record["seed"] == 3
    assert record["input"]["sha256"].startswith("ba7816bf")
    assert record["package_versions"]["numpy"] != "not installed"


def test_atomic_write_has_default_permissions(tmp_path):
    import os

    mask = os.umask(0o022)
    try:
        target = tmp_path / "shared.txt"
        atomic.write_text(target, "x")
        assert target.stat().st_mode & 0o777 == 0o644
    finally:
        os.umask(mask)
