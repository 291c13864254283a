"""Provenance records: every output says which inputs, FMU, seed and packages made it."""

from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path
from typing import Any

import spindlebench

TRACKED_PACKAGES = (
    "numpy", "scipy", "pandas", "matplotlib", "casadi", "pymoca", "fmpy", "scikit-learn",
)


def sha256_file(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


#: A file changed less than this long before it was hashed may change again unseen within
#: the file system's timestamp granularity (a few ms on Linux): its hash is not kept.
_SETTLED_NS = 2_000_000_000
#: Hashes of settled files by (path, device, inode, size, mtime, ctime) (``sha256_unchanged``).
_unchanged: dict[tuple[str, int, int, int, int, int], str] = {}


def sha256_unchanged(path: str | os.PathLike[str]) -> str:
    """``sha256_file(path)``, kept for as long as the file's status (inode, size, modification
    and change times) is the same: a study builds a scenario per run, and each read its
    machine file again to hash it (a thousand times in a 1 008-experiment sweep).

    Any write, rename onto it, ``touch`` or ``chmod`` changes the change time, so an edited
    file is hashed anew; a file changed within ``_SETTLED_NS`` of being hashed is not kept
    (its next change could fall in the same timestamp tick, as git's "racy" entries)."""
    import time

    info = os.stat(path)
    key = (os.fspath(path), info.st_dev, info.st_ino, info.st_size, info.st_mtime_ns,
           info.st_ctime_ns)
    known = _unchanged.get(key)
    if known is not None:
        return known
    digest = sha256_file(path)
    if time.time_ns() - max(info.st_mtime_ns, info.st_ctime_ns) > _SETTLED_NS:
        _unchanged[key] = digest
    return digest


def sha256_written(path: str | os.PathLike[str], data: bytes | None) -> str:
    """Hex SHA-256 of a file just written: of ``data``, its bytes, where the writer kept
    them (not read back from disk), else of the file."""
    return sha256_file(path) if data is None else hashlib.sha256(data).hexdigest()


def source_sha256(*modules: str) -> str:
    """One SHA-256 over the source files of ``modules`` (dotted names) and the tracked package
    versions: a cache of computed results keyed by it is redone when the code that computed
    them, or a numerical library under it, changes."""
    import importlib.util

    digest = hashlib.sha256()
    for name in modules:
        spec = importlib.util.find_spec(name)
        if spec is None or spec.origin is None:
            raise ModuleNotFoundError(name)
        digest.update(name.encode())
        digest.update(Path(spec.origin).read_bytes())
    for package, version in sorted(package_versions().items()):
        digest.update(f"{package}={version}".encode())
    return digest.hexdigest()


def package_versions() -> dict[str, str]:
    """Installed versions of the packages whose behaviour shapes the numbers (a fresh dict;
    looked up once per process: each lookup scans the installed distributions, ~18 ms)."""
    return dict(_package_versions())


@functools.cache
def _package_versions() -> tuple[tuple[str, str], ...]:
    import platform  # here: with importlib.metadata ~50 ms of the start-up of every command
    from importlib import metadata  # that never writes provenance (a sha256 is all it uses)

    versions = {"python": platform.python_version(), "spindlebench": spindlebench.__version__}
    for name in TRACKED_PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return tuple(versions.items())


def provenance(**fields: Any) -> dict[str, Any]:
    """A provenance dict: the caller's fields plus package versions.

    No creation time and no wall-clock durations: the same inputs and seed give the same
    bytes in every output (a timestamp would make every rerun differ); a file's time is in
    the file system, timings are printed to the log.
    """
    record: dict[str, Any] = dict(fields)
    record["package_versions"] = package_versions()
    return record


def file_entry(path: str | os.PathLike[str]) -> dict[str, str]:
    """Name and hash of an input file, for a provenance record."""
    return {"path": str(Path(path)), "sha256": sha256_file(path)}
