"""Converters from real data sets to canonical recordings (one CSV per run + JSON sidecar).

Real recordings live outside the repository, in ``../shared/recordings/`` seen from the
repository root; they are read from there, never copied in.
"""

from __future__ import annotations

from pathlib import Path

import spindlebench


def repo_root() -> Path:
    """The repository root (the folder holding ``pipeline/``), for an editable install."""
    return Path(spindlebench.__file__).resolve().parents[2]


def shared_recordings_dir() -> Path:
    """``../shared/recordings`` relative to the repository root."""
    return repo_root().parent / "shared" / "recordings"
