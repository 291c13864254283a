"""Where the paper's 20 sensors sit: the machine part of each, and the node its probe touches.

One home for "which part is T7 on", so the recording plot (one colour family per part), the
sensor map and the notebooks say the same thing. The first field of ``LOCATIONS`` is what
the probe is connected to in ``models/SpindleBench.mo`` (``connect(sensor_Tk.port, X)``, X a
sub-assembly's port, joined inside the assembly to a lumped node, named here by its component
name, or to a port of a segmented part, named ``part.port_k``; a test reads the model and
checks this table against it). The ambient probe T10 hangs in the air.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SensorPart:
    """A group of sensors on one part of the machine, drawn in one colour family."""

    name: str
    sensors: tuple[str, ...]
    colormap: str  # a sequential matplotlib colormap: the part's colour family
    panel: str  # "spindle" (spindle and headstock) or "axes" (feed axes and the air)


PARTS: tuple[SensorPart, ...] = (
    SensorPart("spindle front", ("T1", "T2", "T3", "T4", "T5"), "Reds", "spindle"),
    SensorPart("headstock", ("T6", "T7", "T8", "T9"), "Purples", "spindle"),
    SensorPart("X axis", ("T11", "T12", "T13", "T14", "T15"), "Blues", "axes"),
    SensorPart("Y axis", ("T16", "T17", "T18", "T19", "T20"), "Greens", "axes"),
    SensorPart("ambient air", ("T10",), "Greys", "axes"),
)

#: The paper's ambient air probe: a reference, not a machine temperature.
AMBIENT_SENSOR = "T10"

#: Sensor (``names.SENSORS``) → (what its probe is connected to in the model, where it is
#: on the machine: the paper's Table 1, in more detail).
LOCATIONS: dict[str, tuple[str, str]] = {
    "T1": ("front_cap", "front bearing cap"),
    "T2": ("housing.port_a", "housing flange at the bearing seat"),
    "T3": ("front_cap", "labyrinth ring (poor contact)"),
    "T4": ("housing.port_3", "housing side above the seat"),
    "T5": ("front_cap", "bearing seat sleeve, inside the cavity"),
    "T6": ("housing.port_1", "housing side at the Z carriages"),
    "T7": ("drawbar_cylinder", "drawbar cylinder base"),
    "T8": ("spindle_motor", "spindle motor housing"),
    "T9": ("inner_cavity", "air probe in the headstock cavity"),
    "T10": ("ambient", "ambient air probe on the column"),
    "T11": ("x_bearing_seat", "X screw bearing seat"),
    "T12": ("x_nut", "X nut flange"),
    "T13": ("x_motor", "X motor housing"),
    "T14": ("x_nut", "X nut bracket (towards the table)"),
    "T15": ("x_motor", "X motor flange (towards the seat)"),
    "T16": ("y_motor", "Y motor housing"),
    "T17": ("y_motor", "Y motor flange (towards the seat)"),
    "T18": ("y_nut", "Y nut flange"),
    "T19": ("y_nut", "Y nut bracket (towards the saddle)"),
    "T20": ("y_bearing_seat", "Y screw bearing seat"),
}


def part_of(sensor: str) -> SensorPart | None:
    """The part a sensor sits on, or ``None`` for a column this table does not know."""
    for part in PARTS:
        if sensor in part.sensors:
            return part
    return None


def part_colour(part: SensorPart) -> tuple[float, float, float, float]:
    """The part's colour in a legend: its family's middle shade (the darkest shades of two
    families, a red and a purple, are hard to tell apart)."""
    from matplotlib import colormaps

    return colormaps[part.colormap](0.7)


def sensor_colours(part: SensorPart) -> dict[str, tuple[float, float, float, float]]:
    """One shade of the part's colour family per sensor, light to dark, none too pale."""
    from matplotlib import colormaps

    cmap = colormaps[part.colormap]
    n = len(part.sensors)
    if n == 1:
        return {part.sensors[0]: cmap(0.85)}
    return {s: cmap(0.45 + 0.5 * i / (n - 1)) for i, s in enumerate(part.sensors)}
