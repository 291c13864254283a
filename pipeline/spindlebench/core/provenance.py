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
