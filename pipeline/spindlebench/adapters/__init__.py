"""Converters from real data sets to canonical recordings (one CSV per run + JSON sidecar).

Real recordings live outside the repository, in ``../shared/recordings/`` seen from the
repository root (``spindlebench.core.paths.shared_recordings_dir``); they are read from there,
never copied in.
"""
