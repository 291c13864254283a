"""The five-probe drift of the model (issue 21): each physical effect on the committed FMU.

A warm front half of the column tilts the head as the bending geometry says; a screw warmed
uniformly by ΔT puts the table off by α ΔT x at target x; an idle machine in a constant room
does not drift; scenarios without ``[outputs] probes`` keep their columns.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import FMU, QUICK
from fmpy import simulate_fmu
from spindlebench.formats.recording import PROBE_OUTPUTS, is_probe_output
from spindlebench.testbench.scenario import load_scenario
from spindlebench.testbench.simulate import record

OUTPUTS = [*PROBE_OUTPUTS, "drift_um"]
ALPHA_IRON = 1.05e-5
ALPHA_STEEL = 1.15e-5


def _first_outputs(start_values: dict[str, float]) -> dict[str, float]:
    """The outputs right after initialisation from the given start values (spindle off)."""
    result = simulate_fmu(str(FMU), start_values=start_values, stop_time=1.0,
                          output_interval=1.0, output=OUTPUTS)
    return {name: float(result[name][0]) for name in OUTPUTS}


def test_a_warm_column_front_tilts_the_head_forward_as_the_geometry_says():
    # front half of the column 1 K above the mean: delta_T = 2 K across 0.35 m of section
    y = _first_outputs({"T_start": 293.15, "ambient_C": 20.0, "column_front_T": 294.15})
    kappa = ALPHA_IRON * 2.0 / (0.7 / 2.0)          # 1/m, the front grows longer
    z_c = 0.7 * 1.42                                # carriages above the column foot
    # the column bends back (+Y, towards itself): the mandrel's upper end leans further back
    # than its lower end, so the head nods forward, tilt A = kappa z_c > 0
    assert y["tilt_a_urad"] == pytest.approx(1e6 * kappa * z_c, rel=1e-6)
    assert y["probe_Y1_um"] > y["probe_Y2_um"]
    assert y["drift_y_um"] == pytest.approx(1e6 * kappa * z_c * (0.54 - z_c / 2.0), rel=1e-6)
    assert abs(y["tilt_b_urad"]) < 1e-9 and abs(y["drift_x_um"]) < 1e-9
    assert abs(y["drift_um"]) < 1e-9  # the Z loop sees the mean temperature only


def test_a_warm_headstock_side_moves_the_tool_to_the_cool_side():
    y = _first_outputs({"T_start": 293.15, "ambient_C": 20.0, "housing_right_T": 293.65})
    kappa = ALPHA_IRON * 1.0 / (0.4 / 2.0)
    hang, seat_to_end = 0.4167 * 0.6, 0.22 * 0.55 + 0.2
    assert y["drift_x_um"] == pytest.approx(-1e6 * kappa * hang * (hang / 2 + seat_to_end),
                                            rel=1e-6)
    assert y["tilt_b_urad"] == pytest.approx(1e6 * kappa * hang, rel=1e-6)


def test_a_uniformly_warm_screw_grows_alpha_dt_x_at_the_target():
    dt = 5.0
    y = _first_outputs({"T_start": 293.15 + dt, "ambient_C": 20.0 + dt,
                        "x_target_m": 0.6, "y_target_m": 0.3})
    # the table is carried alpha dT x away from the fixed bearing: the tool, relative to it,
    # the other way; a uniform temperature bends nothing
    assert y["drift_x_um"] == pytest.approx(-1e6 * ALPHA_STEEL * dt * 0.6, rel=1e-9)
    assert y["drift_y_um"] == pytest.approx(-1e6 * ALPHA_STEEL * dt * 0.3, rel=1e-9)
    assert y["probe_X1_um"] == pytest.approx(y["probe_X2_um"], abs=1e-9)
    assert abs(y["tilt_a_urad"]) < 1e-9 and abs(y["tilt_b_urad"]) < 1e-9


def _scenario(tmp_path, text: str, name: str = "s.toml"):
    path = tmp_path / name
    path.write_text(text)
    return load_scenario(path)


IDLE = """\
duration_s = 7200
step_s = 60.0
sample_interval_s = 600
[speed]
kind = "constant"
rpm = 0
[feed]
kind = "constant"
x_mm_per_min = 0
y_mm_per_min = 0
[ambient]
kind = "constant"
temperature_C = 20.0
[parameters]
P_x_motor_idle = 0.0
P_y_motor_idle = 0.0
P_z_motor_idle = 0.0
x_target_m = 0.8
y_target_m = 0.5
[outputs]
probes = true
"""


def test_an_idle_machine_in_a_constant_room_does_not_drift(tmp_path):
    frame, _ = record(_scenario(tmp_path, IDLE))
    for name in PROBE_OUTPUTS:
        truth = frame[f"true_{name}"].to_numpy()
        assert np.abs(truth).max() < 1e-9, name


def test_probe_columns_only_when_the_scenario_asks(tmp_path):
    plain, _ = record(_scenario(tmp_path, QUICK, "plain.toml"))
    assert not [c for c in plain.columns if is_probe_output(c.removeprefix("true_"))]
    asked, _ = record(_scenario(tmp_path, QUICK + "[outputs]\nprobes = true\n", "p.toml"))
    for name in PROBE_OUTPUTS:
        assert f"true_{name}" in asked
    # measured radial probes zeroed at the start; tilt from them with l = 0.1 m
    assert asked["probe_Y1_um"].iloc[0] == 0.0
    np.testing.assert_allclose(asked["tilt_a_urad"],
                               (asked["probe_Y1_um"] - asked["probe_Y2_um"]) / 0.1)
    # the old columns and their values are unchanged by asking for the probes
    assert list(asked.columns[:len(plain.columns)]) != [] and \
        set(plain.columns) <= set(asked.columns)
    np.testing.assert_array_equal(asked["drift_um"], plain["drift_um"])


@pytest.mark.slow
@pytest.mark.parametrize("good, bad", [
    ("curvature = alpha * delta_T / (depth / 2.0);", "curvature = alpha * delta_T;"),
    ("x_screw_error = alpha_steel * (x_drive.x_screw.T - T_ref) * x_target_m;",
     "x_screw_error = alpha_steel * (x_drive.x_screw.T - T_ref);"),
    ("tilt_a_urad = (probe_Y1_um - probe_Y2_um) / probe_l;",
     "tilt_a_urad = probe_Y1_um - probe_Y2_um;"),
])
def test_the_unit_check_covers_the_five_probe_equations(tmp_path, good, bad):
    from conftest import MODELS
    from spindlebench.core.errors import SpindlebenchError
    from spindlebench.model.frontend import translate

    text = (MODELS / "SpindleBench.mo").read_text(encoding="utf-8")
    assert good in text
    (tmp_path / "SpindleBench.mo").write_text(text.replace(good, bad), encoding="utf-8")
    line = text[:text.index(good)].count("\n") + 1
    with pytest.raises(SpindlebenchError, match=rf"SpindleBench.mo:{line}:"):
        translate(tmp_path, 2)
