"""Which columns of a recording are which direction of an ISO 230-3 report.

A synthetic five-probe recording (``[outputs] probes = true``) names its channels itself
(``drift_x_um``, ``drift_y_um``, ``drift_um``, ``tilt_a_urad``, ``tilt_b_urad`` and the raw
``probe_*_um``); a real recording gets a map, ``MAP.toml``:

```toml
air = "t10_C"                     # optional: the air temperature logged beside the probes
speed = "spindle_speed_rpm"       # optional: the spindle speed (finds the spindle-on phase)
probe_l_m = 0.1                   # distance between the two radial probe heights (tilts)
temperatures = ["t1_C", "t5_C"]   # temperature curves to draw beside the drift
others = ["ch5_um"]               # further displacement channels, recorded and drawn

[directions]                      # X, Y, Z: a column, or a radial pair at two heights
X = { upper = "ch1_um", lower = "ch2_um" }   # drift = lower probe, tilt B = (upper-lower)/l
Y = { upper = "ch3_um", lower = "ch4_um", sign = -1 }
Z = "ch5_um"                      # or { column = "ch5_um", sign = -1 }
```

A pair gives the direction's drift (the lower probe, nearer the tool) and its tilt: B from the
X pair, A from the Y pair. ``sign = -1`` turns a channel whose positive reading is the other
way round. Every key is checked; a bad one is one line naming the map and the key.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spindlebench.core.errors import SpindlebenchError
from spindlebench.formats.recording import DRIFT_COLUMN, SPEED_COLUMN, TIME_COLUMN
from spindlebench.formats.toml import Table, load_toml
from spindlebench.studies.iso230_3.evaluation import LINEAR, tilt_from_probes

#: A direction's pair gives this tilt (B from the X probes, A from the Y probes).
TILT_OF_PAIR = {"X": "B", "Y": "A"}
#: The synthetic five-probe recording's columns per direction and tilt.
SYNTHETIC_LINEAR = {"X": "drift_x_um", "Y": "drift_y_um", "Z": DRIFT_COLUMN}
SYNTHETIC_TILTS = {"A": "tilt_a_urad", "B": "tilt_b_urad"}
SYNTHETIC_PROBES = ("probe_X1_um", "probe_X2_um", "probe_Y1_um", "probe_Y2_um")
#: Temperatures a synthetic report draws: the air first (T10, the ambient probe).
SYNTHETIC_TEMPERATURES = {"T10": "air (T10)", "T1": "spindle front (T1)",
                          "T6": "headstock (T6)", "T8": "spindle motor (T8)",
                          "T12": "X nut (T12)"}


@dataclass
class TestData:
    """One run's series in the report's terms."""

    time_s: np.ndarray
    linear: dict[str, np.ndarray]          # X, Y, Z in µm
    tilts: dict[str, np.ndarray]           # A, B in µrad
    others: dict[str, np.ndarray]          # raw probe channels, µm
    temperatures: dict[str, np.ndarray]    # label -> °C
    air: str | None                        # label of the air temperature
    speed_rpm: np.ndarray | None
    sources: dict[str, str] = field(default_factory=dict)  # report name -> column(s)


def synthetic(frame) -> TestData:
    """The report's series of a five-probe synthetic recording (measured channels)."""
    missing = [c for c in (*SYNTHETIC_LINEAR.values(), *SYNTHETIC_TILTS.values())
               if c not in frame]
    if missing:
        raise SpindlebenchError(f"recording has no five-probe column(s) {', '.join(missing)} "
                                "(simulate the scenario with [outputs] probes = true)")
    return TestData(
        time_s=frame[TIME_COLUMN].to_numpy(float),
        linear={k: frame[c].to_numpy(float) for k, c in SYNTHETIC_LINEAR.items()},
        tilts={k: frame[c].to_numpy(float) for k, c in SYNTHETIC_TILTS.items()},
        others={c: frame[c].to_numpy(float) for c in SYNTHETIC_PROBES if c in frame},
        temperatures={label: frame[c].to_numpy(float)
                      for c, label in SYNTHETIC_TEMPERATURES.items() if c in frame},
        air=SYNTHETIC_TEMPERATURES["T10"],
        speed_rpm=frame[SPEED_COLUMN].to_numpy(float)
        if SPEED_COLUMN in frame else None,
        sources={**SYNTHETIC_LINEAR, **SYNTHETIC_TILTS},
    )


@dataclass(frozen=True)
class Direction:
    """One direction of a map: a single column or a radial pair, with its sign."""

    column: str | None = None
    upper: str | None = None
    lower: str | None = None
    sign: float = 1.0

    @property
    def columns(self) -> tuple[str, ...]:
        return tuple(c for c in (self.column, self.upper, self.lower) if c is not None)


@dataclass(frozen=True)
class RecordingMap:
    """A MAP.toml for ``iso230-3 --recording`` (module docstring)."""

    path: Path
    directions: dict[str, Direction]
    temperatures: tuple[str, ...] = ()
    others: tuple[str, ...] = ()
    air: str | None = None
    speed: str | None = None
    probe_l_m: float | None = None

    def columns(self) -> list[str]:
        names = [c for d in self.directions.values() for c in d.columns]
        names += [*self.temperatures, *self.others]
        names += [c for c in (self.air, self.speed) if c is not None]
        return list(dict.fromkeys(names))


def _direction(t: Table, name: str) -> Direction:
    raw = t.raw(name)
    if isinstance(raw, str):
        return Direction(column=raw)
    sub = t.table(name)
    sign = sub.number("sign", 1.0)
    if sign not in (1.0, -1.0):
        raise sub.error("sign", f"must be 1 or -1, got {sign:g}")
    if sub.has("column"):
        direction = Direction(column=sub.string("column"), sign=sign)
    else:
        if name not in TILT_OF_PAIR:
            raise sub.error("upper", f"direction {name} takes one column (no tilt pair)")
        direction = Direction(upper=sub.string("upper"), lower=sub.string("lower"), sign=sign)
    sub.finish()
    return direction


def load_map(path: str | Path) -> RecordingMap:
    """Read and check a MAP.toml; every problem is one line naming the file and key."""
    path = Path(path)
    top = Table(load_toml(path, "map"), path)
    d = top.table("directions")
    directions = {}
    for name in d.names():
        if name not in LINEAR:
            raise d.error(name, f"not a direction; use {', '.join(LINEAR)}")
        directions[name] = _direction(d, name)
    if not directions:
        raise top.error("directions", "names no direction (X, Y or Z)")
    d.finish()
    mapping = RecordingMap(
        path=path,
        directions=directions,
        temperatures=tuple(top.get_list("temperatures", str, [])),
        others=tuple(top.get_list("others", str, [])),
        air=top.string("air", None),
        speed=top.string("speed", None),
        probe_l_m=top.number("probe_l_m", None, minimum=1e-3, maximum=2.0, unit="m"),
    )
    if any(v.upper for v in directions.values()) and mapping.probe_l_m is None:
        raise top.error("probe_l_m", "a radial pair needs the distance between its probes")
    top.finish()
    return mapping


def from_map(frame, mapping: RecordingMap, recording: Path) -> TestData:
    """The report's series of a real recording through its map (channels re-zeroed at the
    first sample, like probes zeroed at the start of the test)."""
    missing = [c for c in mapping.columns() if c not in frame]
    if missing:
        raise SpindlebenchError(f"{recording}: no column(s) {', '.join(missing)} named in "
                                f"{mapping.path}")

    def zeroed(column: str, sign: float = 1.0) -> np.ndarray:
        values = frame[column].to_numpy(float)
        return sign * (values - values[0])

    linear, tilts, sources = {}, {}, {}
    for name, direction in mapping.directions.items():
        if direction.column is not None:
            linear[name] = zeroed(direction.column, direction.sign)
            sources[name] = direction.column if direction.sign > 0 else f"-{direction.column}"
        else:
            upper = zeroed(direction.upper, direction.sign)
            lower = zeroed(direction.lower, direction.sign)
            linear[name] = lower
            tilt = TILT_OF_PAIR[name]
            tilts[tilt] = tilt_from_probes(upper, lower, mapping.probe_l_m)
            prefix = "" if direction.sign > 0 else "-"
            sources[name] = f"{prefix}{direction.lower}"
            sources[tilt] = (f"{prefix}({direction.upper} - {direction.lower}) / "
                             f"{mapping.probe_l_m:g} m")
    others = {c: zeroed(c) for c in mapping.others}
    for d in mapping.directions.values():
        for c in d.columns:
            others.setdefault(c, zeroed(c))
    temperatures = {c: frame[c].to_numpy(float) for c in
                    ([mapping.air] if mapping.air else []) + list(mapping.temperatures)}
    return TestData(
        time_s=frame[TIME_COLUMN].to_numpy(float),
        linear={k: linear[k] for k in LINEAR if k in linear},
        tilts={k: tilts[k] for k in ("A", "B") if k in tilts},
        others=others,
        temperatures=temperatures,
        air=mapping.air,
        speed_rpm=frame[mapping.speed].to_numpy(float) if mapping.speed else None,
        sources=sources,
    )
