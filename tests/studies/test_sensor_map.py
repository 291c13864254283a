"""The sensor map: T1–T20 on the front and side views of the schematic."""

import itertools
import math

from spindlebench.studies.placement.sensor_map import FRONT, side_positions, write_sensor_map
from spindlebench.testbench.sensor_parts import LOCATIONS


def test_every_sensor_is_on_both_views_and_no_two_markers_overlap():
    side = side_positions()
    for view in (FRONT, side):
        assert set(view) == set(LOCATIONS)
        for (a, pa), (b, pb) in itertools.combinations(view.items(), 2):
            assert math.dist(pa, pb) >= 0.1, (a, b)


def test_the_side_view_puts_each_probe_next_to_its_model_node():
    side = side_positions()
    assert side["T1"][1] < side["T7"][1]  # the bearing cap is below the drawbar cylinder
    assert side["T13"][0] < side["T12"][0]  # X motor nearer the operator than the nut, as drawn
    assert side["T2"][0] == side["T4"][0] == side["T6"][0]  # three ports on the housing axis


def test_write_sensor_map_writes_a_png(tmp_path):
    out = write_sensor_map(tmp_path / "map.png")
    assert out.read_bytes()[:4] == b"\x89PNG" and out.stat().st_size > 50_000


def test_port_fractions_come_from_the_model_source():
    from spindlebench.studies.placement.sensor_map import port_fractions

    source = 'SegmentedSolid housing(n = 4, x1 = 0.25,\n  x3 = 0.1) "Headstock";'
    assert port_fractions("housing", source) == {"port_a": 0.0, "port_b": 1.0, "port_1": 0.25,
                                                 "port_2": 0.5, "port_3": 0.1}
    assert 0.0 < port_fractions("housing")["port_3"] < port_fractions("housing")["port_1"]
