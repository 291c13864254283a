"""What a calibration writes: the machine file, its report (JSON) and the measured-vs-model figure.

The machine file is the format of ``spindlebench.machines.variants`` (``name``, ``description``,
``[parameters]``): a calibrated machine runs through ``simulate``/``sweep``/``place`` like a
shipped one. It cannot hold other tables, so its provenance (recordings and their SHA-256,
model, fit) is in its header comment and, in full, in ``<name>.calibration.json`` beside it.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from spindlebench.calibration.problem import Fit
from spindlebench.core import atomic
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.formats.recording import AMBIENT_COLUMN, TIME_COLUMN


def _beside(machine_file: Path, suffix: str) -> Path:
    """``NAME<suffix>`` in the machine file's folder (``NAME.toml`` → ``NAME.state.json``)."""
    stem = machine_file.with_suffix("")
    return stem.with_name(stem.name + suffix)


def state_path(machine_file: Path) -> Path:
    """The fitted states written beside ``machine_file``: ``NAME.state.json``."""
    return _beside(machine_file, ".state.json")


def state_record(fit: Fit, series_list: Sequence, provenance: Mapping[str, Any]
                 ) -> dict[str, Any]:
    """The fitted initial and end states of the last recording, in the sidecar format
    (``formats.recording.sidecar_record``): a ``continue`` scenario naming this file in
    ``[initial] from`` starts the calibrated machine (``simulate --machine NAME.toml``) where
    the recording ended, instead of cold. The last recording, because a continuation
    continues the latest one; each recording's states are in the report too.

    Why a sidecar and not a table of the machine file: the machine file is a parameter set
    that many scenarios share, while a state belongs to one recording's end; the sidecar is
    what ``continue`` already reads (one home for saved states)."""
    from spindlebench.formats.recording import sidecar_record

    last = len(series_list) - 1
    series = series_list[last]
    record = sidecar_record(
        provenance={**provenance, "state_of": series.name},
        initial_state_K=_kelvin(fit.state_names, fit.initial_states[last]),
        end_time_s=float(series.time_s[-1] - series.time_s[0]),
        end_state_K=_kelvin(fit.state_names, fit.end_states[last]))
    return record


def _kelvin(names: Sequence[str], state_C: np.ndarray) -> dict[str, float]:
    return {name: float(value) + KELVIN_OFFSET for name, value in zip(names, state_C,
                                                                      strict=True)}


def report_paths(machine_file: Path) -> tuple[Path, Path]:
    """The report (JSON) and the figure (PNG) written beside ``machine_file``."""
    return _beside(machine_file, ".calibration.json"), _beside(machine_file, ".calibration.png")


def _toml_string(text: str) -> str:
    return json.dumps(text, ensure_ascii=False)  # a JSON string is a TOML basic string


def machine_text(name: str, description: str, parameters: Mapping[str, float],
                 fit: Fit, provenance: Mapping[str, Any]) -> str:
    """The machine file: fitted values (with their 95 % intervals as comments) over the base."""
    intervals = fit.interval95()
    lines = [
        f"# Calibrated by 'spindlebench calibrate' ({fit.method}, reduced chi-square "
        f"{fit.chi2_reduced:.3g}); full report: {report_paths(Path(name + '.toml'))[0].name}",
        f"# fitted states at the start and end of the last recording: "
        f"{state_path(Path(name + '.toml')).name} (a continuation: [initial] kind = "
        f"\"continue\", from = that file)",
    ]
    for recording in provenance["recordings"]:
        lines.append(f"# recording {recording['path']} sha256 {recording['sha256']}")
    lines += [f"# model {provenance['model']['path']} sha256 {provenance['model']['sha256']}, "
              f"{provenance['segments']} segments", ""]
    lines += [f"name = {_toml_string(name)}", f"description = {_toml_string(description)}", "",
              "[parameters]"]
    for key in sorted(parameters):
        value = parameters[key]
        note = ""
        if key in intervals:
            lo, hi = intervals[key]
            note = (f"  # fitted, 95 % interval [{lo:.4g}, {hi:.4g}], "
                    f"start {fit.start_values[key]:.4g}")
        lines.append(f"{key} = {value!r}{note}")
    return "\n".join(lines) + "\n"


def report_dict(fit: Fit, provenance: Mapping[str, Any], ignored: Mapping[str, Sequence[str]]
                ) -> dict[str, Any]:
    """The calibration report: estimates, intervals, correlations, residuals, provenance."""
    intervals = fit.interval95()
    return {
        "provenance": dict(provenance),
        "method": fit.method,
        "status": fit.status,
        "evaluations": fit.evaluations,
        "seconds": round(fit.seconds, 1),
        "chi2_reduced": fit.chi2_reduced,
        "parameters": [
            {"name": name, "start": fit.start_values[name], "estimate": fit.values[name],
             "ci95": list(intervals[name]), "sd_ln": float(sd)}
            for name, sd in zip(fit.fit, fit.sd_ln, strict=True)
        ],
        "at_bound": list(fit.at_bound),
        "correlation": {"names": fit.fit, "matrix": np.round(fit.correlation, 4).tolist()},
        "residuals": fit.channel_rmse,
        AMBIENT_COLUMN: [np.round(t[AMBIENT_COLUMN], 3).tolist() for t in fit.trajectories],
        "ignored_columns": {k: list(v) for k, v in ignored.items()},
        "fitted_states_K": [
            {"recording": t["recording"], "initial": _kelvin(fit.state_names, start),
             "end": _kelvin(fit.state_names, end)}
            for t, start, end in zip(fit.trajectories, fit.initial_states, fit.end_states,
                                     strict=True)],
    }


def write_report(path: Path, report: Mapping[str, Any]) -> None:
    atomic.write_text(path, json.dumps(report, indent=1, sort_keys=False) + "\n")


def figure(fit: Fit, path: Path, title: str = "") -> Path:
    """Measured vs calibrated: temperatures (top) and error (bottom), one column a recording."""
    count = len(fit.trajectories)
    fig = Figure(figsize=(5.5 * count + 1, 7.5))
    axes = fig.subplots(2, count, squeeze=False, sharex="col")
    colours = [f"C{i}" for i in range(10)]
    for column, curves in enumerate(fit.trajectories):
        hours = (curves[TIME_COLUMN] - curves[TIME_COLUMN][0]) / 3600.0
        top, bottom = axes[0, column], axes[1, column]
        temperatures = [c for c in curves["channels"] if c["kind"] == "temperature"]
        for i, channel in enumerate(temperatures):
            colour = colours[i % len(colours)]
            top.plot(hours, channel["measured"], ".", ms=1.5, color=colour, alpha=0.5)
            top.plot(hours, channel["model"], "-", lw=1.0, color=colour,
                     label=f"{channel['column']} → {channel['output'].removesuffix('_C')}")
        top.plot(hours, curves[AMBIENT_COLUMN], "--", color="grey", lw=1.0, label="ambient")
        top.set_ylabel("temperature (°C)")
        top.set_title(curves["recording"])
        if temperatures:
            top.legend(fontsize=6, ncol=2, loc="upper right")
        for channel in curves["channels"]:
            if channel["kind"] == "error":
                bottom.plot(hours, channel["measured"], ".", ms=1.5, color="k", alpha=0.5,
                            label=f"measured {channel['column']}")
                bottom.plot(hours, channel["model"], "-", color="C3", lw=1.2,
                            label="calibrated model")
                bottom.legend(fontsize=7)
        bottom.set_ylabel("thermal error (µm)")
        bottom.set_xlabel("time (h)")
    fig.suptitle(title or "measured (dots) vs calibrated model (lines)", fontsize=10)
    with atomic.atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png")
    return path
