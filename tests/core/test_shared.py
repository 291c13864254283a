"""Shared helpers: atomic writes and provenance."""

import os

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


def test_a_kept_file_hash_is_redone_once_the_file_changes(tmp_path, monkeypatch):
    """``sha256_unchanged`` keeps a settled file's hash while its status is the same: a
    rewrite (here of the same size, its times set apart as a later tick would) is hashed
    anew, and a file changed just now is not kept at all (its next change could share the
    timestamp)."""
    path = tmp_path / "machine.toml"
    path.write_text("a = 1\n")
    assert provenance.sha256_unchanged(path) == provenance.sha256_file(path)
    assert not any(key[0] == str(path) for key in provenance._unchanged)  # changed just now
    monkeypatch.setattr(provenance, "_SETTLED_NS", -1)  # as if it had been there for long
    first = provenance.sha256_unchanged(path)
    assert any(key[0] == str(path) for key in provenance._unchanged)  # kept now
    path.write_text("a = 2\n")
    stamp = path.stat().st_mtime_ns + 10_000_000
    os.utime(path, ns=(stamp, stamp))
    assert provenance.sha256_unchanged(path) == provenance.sha256_file(path) != first
