"""Physics of the thermal network, checked on its explicit equations (no FMU needed)."""


import numpy as np
import pytest
from conftest import MODELS
from scipy.integrate import solve_ivp
from scipy.optimize import root
from spindlebench.model.equations import explicit_ode

SOURCES = (
    "Q_front_bearing_W",
    "Q_rear_bearing_W",
    "Q_spindle_motor_W",
    "Q_x_feed_W",
    "Q_y_feed_W",
    "Q_z_feed_W",
)


@pytest.fixture(scope="module")
def ode():
    return explicit_ode(MODELS, segments=4)


def inputs(speed=4000.0, feed=1500.0, ambient=20.0):
    return np.array([speed, feed, feed, ambient])


def evaluate(ode, x, u, p):
    xdot, y = ode.ode(x, u, p)
    return np.array(xdot).ravel(), dict(zip(ode.outputs, np.array(y).ravel(), strict=True))


def uniform(ode, celsius):
    return np.full(len(ode.states), celsius + 273.15)


def steady_state(ode, u, p):
    jac = ode.state_jacobian()
    solution = root(
        lambda s: evaluate(ode, s, u, p)[0],
        uniform(ode, u[3] + 10.0),
        jac=lambda s: np.array(jac(s, u, p)),
        method="hybr",
        tol=1e-12,
    )
    assert solution.success
    return solution.x


def test_interface_names_follow_the_contract(ode):
    assert ode.inputs == [
        "spindle_speed_rpm",
        "feed_x_mm_per_min",
        "feed_y_mm_per_min",
        "ambient_C",
    ]
    assert [f"T{i}_C" for i in range(1, 21)] == ode.outputs[:20]
    assert "drift_um" in ode.outputs
    for state in ode.node_states:
        assert state.endswith("_T")
        assert f"node_{state.removesuffix('_T')}_C" in ode.outputs
    assert "node_spindle_shaft_3_C" in ode.outputs
    for name in (
        "cooling_enabled",
        "cooling_follows_ambient",
        "cooling_setpoint_C",
        "T_ref",
        "housing_C",
        "fb_housing_G",
        "housing_L",
    ):
        assert name in ode.parameters
    assert "nSeg" not in ode.parameters  # structural, fixed at build time
    # roughly 50-100 field nodes at the default; 5 parts x 4 segments + 21 lumped here, + the
    # four half-section nodes of the five-probe model (column and headstock, front and right)
    assert len(ode.node_states) == 5 * 4 + 21 + 4
    assert len(ode.states) == len(ode.node_states) + 20


def test_idle_machine_at_ambient_is_in_equilibrium(ode):
    p = ode.parameter_vector(P_x_motor_idle=0.0, P_y_motor_idle=0.0, P_z_motor_idle=0.0)
    xdot, y = evaluate(ode, uniform(ode, 17.0), inputs(speed=0.0, feed=0.0, ambient=17.0), p)
    assert np.abs(xdot).max() < 1e-12
    assert y["T1_C"] == pytest.approx(17.0)
    assert y["Q_to_ambient_W"] == pytest.approx(0.0, abs=1e-9)


def test_heat_released_equals_heat_removed_in_steady_state(ode):
    p = ode.parameter_vector(
        cooling_enabled=1.0, cooling_follows_ambient=1.0, cooling_setpoint_C=-2.0
    )
    u = inputs(speed=3000.0, ambient=22.0)
    x = steady_state(ode, u, p)
    _, y = evaluate(ode, x, u, p)
    released = sum(y[name] for name in SOURCES)
    assert released > 100.0
    assert y["Q_cooling_W"] > 10.0
    assert y["Q_to_ambient_W"] + y["Q_cooling_W"] == pytest.approx(released, rel=1e-9)


def test_bearing_friction_grows_with_speed_and_with_cold_oil(ode):
    p = ode.parameter_vector()
    q = {}
    for speed in (2000.0, 4000.0):
        for celsius in (5.0, 30.0):
            q[speed, celsius] = evaluate(ode, uniform(ode, celsius), inputs(speed=speed), p)[1][
                "Q_front_bearing_W"
            ]
    assert q[4000.0, 5.0] > 1.2 * q[4000.0, 30.0]  # colder oil, more viscous, more friction
    assert 2.2 < q[4000.0, 30.0] / q[2000.0, 30.0] < 3.5  # Palmgren: M0 ~ n^(2/3), Q ~ n^(5/3)
    assert 60.0 < q[4000.0, 30.0] < 250.0


def test_drift_of_a_uniform_warming_is_the_loop_of_expansion_lengths(ode):
    p = ode.parameter_vector()
    par = ode.parameters
    t_ref = par["T_ref"] - 273.15
    _, at_ref = evaluate(ode, uniform(ode, t_ref), inputs(speed=0.0, ambient=t_ref), p)
    _, warmer = evaluate(ode, uniform(ode, t_ref + 1.0), inputs(speed=0.0, ambient=t_ref), p)
    assert at_ref["drift_um"] == pytest.approx(0.0, abs=1e-9)
    expected_m = (
        par["alpha_steel"]
        * par["spindle_shaft_L"]
        * (par["spindle_shaft_x_hi"] - par["spindle_shaft_x_lo"])
        + par["alpha_steel"] * (par["tool_L"] + par["z_screw_L"])
        + par["alpha_fixture"] * par["fixture_L"]
        + par["alpha_iron"] * par["housing_L"] * (par["housing_x_hi"] - par["housing_x_lo"])
        - par["alpha_iron"] * par["column_L"] * (par["column_x_hi"] - par["column_x_lo"])
        + par["alpha_iron"] * par["table_L"] * (par["table_x_hi"] - par["table_x_lo"])
    )
    assert warmer["drift_um"] == pytest.approx(1e6 * expected_m, rel=1e-9)


def test_cooling_unit_limits_the_spindle_warm_up(ode):
    u = inputs(speed=4000.0, ambient=20.0)

    def t1_after_two_hours(**parameters):
        p = ode.parameter_vector(**parameters)
        sol = solve_ivp(
            lambda t, x: evaluate(ode, x, u, p)[0],
            (0.0, 7200.0),
            uniform(ode, 20.0),
            method="LSODA",
            rtol=1e-6,
            atol=1e-6,
        )
        return evaluate(ode, sol.y[:, -1], u, p)[1]

    free = t1_after_two_hours()
    cooled = t1_after_two_hours(
        cooling_enabled=1.0, cooling_follows_ambient=1.0, cooling_setpoint_C=0.0
    )
    assert free["Q_cooling_W"] == pytest.approx(0.0, abs=1e-9)
    assert cooled["Q_cooling_W"] > 20.0
    assert cooled["T1_C"] < free["T1_C"] - 2.0


def test_cooling_setpoint_is_absolute_or_follows_the_ambient(ode):
    x = uniform(ode, 25.0)

    def q_cooling(ambient, **parameters):
        p = ode.parameter_vector(cooling_enabled=1.0, **parameters)
        return evaluate(ode, x, inputs(speed=0.0, ambient=ambient), p)[1]["Q_cooling_W"]

    absolute = q_cooling(25.0, cooling_follows_ambient=0.0, cooling_setpoint_C=15.0)
    assert absolute > 10.0  # coolant at 15 degC takes heat from a machine at 25 degC
    assert q_cooling(10.0, cooling_follows_ambient=0.0, cooling_setpoint_C=15.0) == pytest.approx(
        absolute
    )
    assert q_cooling(25.0, cooling_follows_ambient=1.0, cooling_setpoint_C=-10.0) == pytest.approx(
        absolute
    )
    assert q_cooling(25.0, cooling_follows_ambient=1.0, cooling_setpoint_C=0.0) == pytest.approx(
        0.0, abs=1e-9
    )


def walther_viscosity(nu_40, nu_100, kelvin):
    """ASTM D341: log10(log10(nu + 0.7)) is linear in log10(T) through (313.15 K, nu_40) and
    (373.15 K, nu_100)."""
    ll = [np.log10(np.log10(nu + 0.7)) for nu in (nu_40, nu_100)]
    slope = (ll[1] - ll[0]) / (np.log10(373.15) - np.log10(313.15))
    return 10 ** (10 ** (ll[0] + slope * (np.log10(kelvin) - np.log10(313.15)))) - 0.7


def test_front_bearing_friction_follows_palmgren_with_walther_viscosity(ode):
    par = ode.parameters
    nu_40, nu_100 = par["front_bearing_friction_nu_40"], par["front_bearing_friction_nu_100"]
    assert walther_viscosity(nu_40, nu_100, 293.15) == pytest.approx(54.3, abs=0.5)  # VG 22
    assert walther_viscosity(nu_40, nu_100, 278.15) == pytest.approx(132, abs=2)
    speed = 4000.0
    omega = speed * 2 * np.pi / 60
    z, f0 = par["front_bearing_friction_z"], par["front_bearing_friction_f0"]
    dm_mm = 1000 * par["front_bearing_friction_dm"]
    load_part = z * par["front_bearing_friction_f1"] * par["front_bearing_friction_P1"] * (
        par["front_bearing_friction_dm"]
    ) * omega
    p = ode.parameter_vector()
    for celsius in (5.0, 20.0, 40.0):
        # the friction heat reads the rings' viscosity: every node at the same temperature
        q = evaluate(ode, uniform(ode, celsius), inputs(speed=speed), p)[1]["Q_front_bearing_W"]
        nu = walther_viscosity(nu_40, nu_100, celsius + 273.15)
        speed_part = z * 1e-10 * f0 * (nu * speed) ** (2 / 3) * dm_mm**3 * omega
        assert q == pytest.approx(speed_part + load_part, rel=1e-9)
