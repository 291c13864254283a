"""The numbers of an ISO 230-3 report, from time series alone (no files, no FMU).

The standard's text was not available to us; what follows the common practice of its users
rather than its wording is marked here and in docs/iso230-3.md:

- a direction's **range** is max − min of its reading over the evaluated span (the drift
  starts at 0: the probes are zeroed at the start);
- **ETVE** (environmental temperature variation error) per direction is that range over the
  whole idle test, beside the range of the air temperature;
- the spindle test's **stability criterion**: at time t (at least one hour into the spindle-on
  phase) the machine is thermally stable when, in every linear direction, the change of the
  reading over the last hour is at most ``STABILITY_FRACTION`` (15 %) of the largest change
  from the start seen in the first hour, with a floor ``STABILITY_FLOOR_UM`` so that a
  direction that hardly moves (a few probe quanta) does not hold the test up.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The stability criterion's share of the first hour's largest change (common practice).
STABILITY_FRACTION = 0.15
#: The criterion's window: the change over the last hour, compared with the first hour.
STABILITY_WINDOW_S = 3600.0
#: Below this change (µm) a direction counts as stable whatever its first hour did.
STABILITY_FLOOR_UM = 0.5
#: Linear directions (µm) and tilts (µrad) of a five-probe report, in the report's order.
LINEAR = ("X", "Y", "Z")
TILTS = ("A", "B")


@dataclass(frozen=True)
class Stability:
    """When the stability criterion was first met (None: not within the phase)."""

    met_at_s: float | None
    phase_end_s: float
    #: When each direction alone first met it (None: not within the phase).
    per_direction_s: dict[str, float | None] = field(default_factory=dict)
    window_s: float = STABILITY_WINDOW_S
    fraction: float = STABILITY_FRACTION
    floor_um: float = STABILITY_FLOOR_UM

    def to_dict(self) -> dict[str, object]:
        return {
            "criterion": (f"change over the last {self.window_s / 3600:g} h <= "
                          f"{self.fraction:.0%} of the largest change in the first hour "
                          f"(floor {self.floor_um:g} um), every linear direction; common "
                          "practice, not the standard's wording"),
            "met_at_h": None if self.met_at_s is None else round(self.met_at_s / 3600.0, 4),
            "met": self.met_at_s is not None,
            "time_limit_h": round(self.phase_end_s / 3600.0, 4),
            "per_direction_met_at_h": {k: None if v is None else round(v / 3600.0, 4)
                                       for k, v in self.per_direction_s.items()},
        }


def channel_range(values: np.ndarray) -> dict[str, float]:
    """Range (max − min), max, min and last value of one channel."""
    values = np.asarray(values, dtype=float)
    return {
        "range": float(values.max() - values.min()),
        "max": float(values.max()),
        "min": float(values.min()),
        "final": float(values[-1]),
        "at_max_h": float(np.argmax(values)),  # replaced by the caller's time (index here)
    }


def ranges(time_s: np.ndarray, channels: dict[str, np.ndarray],
           span: slice = slice(None)) -> dict[str, dict[str, float]]:
    """``channel_range`` of every channel over ``span``, with the time of the maximum in h."""
    out = {}
    t = np.asarray(time_s, dtype=float)[span]
    for name, values in channels.items():
        v = np.asarray(values, dtype=float)[span]
        entry = channel_range(v)
        entry["at_max_h"] = float(t[int(np.argmax(v))] / 3600.0)
        out[name] = entry
    return out


def stability(time_s: np.ndarray, linear: dict[str, np.ndarray], phase_end_s: float,
              window_s: float = STABILITY_WINDOW_S, fraction: float = STABILITY_FRACTION,
              floor_um: float = STABILITY_FLOOR_UM) -> Stability:
    """The first time within ``[window_s, phase_end_s]`` the criterion holds (module doc)."""
    t = np.asarray(time_s, dtype=float)
    first_hour = t <= t[0] + window_s
    in_phase = (t >= t[0] + window_s) & (t <= phase_end_s)

    def first(mask: np.ndarray) -> float | None:
        candidates = in_phase & mask
        return float(t[np.argmax(candidates)]) if candidates.any() else None

    ok = np.ones(t.size, dtype=bool)
    per_direction: dict[str, float | None] = {}
    for name, values in linear.items():
        v = np.asarray(values, dtype=float)
        reference = np.max(np.abs(v[first_hour] - v[0]))
        allowed = max(fraction * reference, floor_um)
        # reading one window earlier, interpolated on the time axis
        earlier = np.interp(t - window_s, t, v)
        stable = np.abs(v - earlier) <= allowed
        per_direction[name] = first(stable)
        ok &= stable
    return Stability(met_at_s=first(ok), phase_end_s=float(phase_end_s),
                     per_direction_s=per_direction, window_s=window_s, fraction=fraction,
                     floor_um=floor_um)


def spindle_on_end_s(time_s: np.ndarray, speed_rpm: np.ndarray | None) -> float:
    """End of the first spindle-on phase (the time of the first sample after it stops), or
    the end of the record when the spindle never stops (or no speed is known)."""
    t = np.asarray(time_s, dtype=float)
    if speed_rpm is None:
        return float(t[-1])
    on = np.asarray(speed_rpm, dtype=float) > 0
    if not on.any():
        return float(t[-1])
    first_on = int(np.argmax(on))
    off_after = np.flatnonzero(~on[first_on:])
    return float(t[first_on + off_after[0]]) if off_after.size else float(t[-1])


def tilt_from_probes(upper: np.ndarray, lower: np.ndarray, probe_l_m: float) -> np.ndarray:
    """Tilt (µrad) from two radial probes (µm) ``probe_l_m`` apart: (upper − lower) / l."""
    return (np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)) / probe_l_m
