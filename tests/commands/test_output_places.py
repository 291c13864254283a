"""Issue 25: commands write only where they are told, or into the per-user cache.

The fingerprint reference (4.2 MB) and the soak states went into ``./results/`` of whatever
folder a command ran in (the checkout, under ``make test``); the course emptied ``work/NN``
there.
"""

from __future__ import annotations

from spindlebench.core import paths
from spindlebench.studies.fingerprint.reference import default_cache
from spindlebench.testbench import soak


def test_the_per_user_cache_is_never_the_current_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv(paths.CACHE_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert paths.user_cache_dir() == tmp_path / "xdg" / "spindlebench"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert paths.user_cache_dir() == tmp_path / "home" / ".cache" / "spindlebench"
    assert paths.user_cache_dir().is_absolute()


def test_the_fingerprint_reference_and_soak_caches_live_in_the_user_cache(tmp_path,
                                                                         monkeypatch):
    monkeypatch.setenv(paths.CACHE_ENV, str(tmp_path / "c"))
    monkeypatch.delenv(soak.CACHE_ENV, raising=False)
    assert default_cache() == tmp_path / "c" / "fingerprint_reference"
    assert soak.cache_dir() == tmp_path / "c" / "soak"
