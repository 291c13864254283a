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


def test_the_first_write_into_a_folder_removes_every_stale_part_file(tmp_path):
    """Killed writers' part files go at this process's first write there, whatever target
    they were for; a live writer's and other dot files stay."""
    import os

    stale = [tmp_path / ".a.csv.999999999.k2j4_x8q.part", tmp_path / ".b.999999998.abcdefgh.part"]
    kept = [tmp_path / f".c.csv.{os.getpid()}.abcdefgh.part", tmp_path / ".notes.part",
            tmp_path / ".d.999999999.part"]
    for path in stale + kept:
        path.write_text("x")
    atomic.write_text(tmp_path / "new.txt", "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["new.txt", *(p.name for p in kept)])


def test_a_folder_removed_after_a_write_is_made_again(tmp_path):
    import shutil

    target = tmp_path / "sub" / "a.txt"
    atomic.write_text(target, "one")
    shutil.rmtree(target.parent)
    atomic.write_text(target, "two")
    assert target.read_text() == "two"
