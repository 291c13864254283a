"""The Modelica Examples: each simulated through the build's pymoca/CasADi path, compared with
its committed reference result and, where there is one, with the analytical solution."""

import math

import numpy as np
import pytest
from conftest import MODELS
from spindlebench.core.errors import SpindlebenchError
from spindlebench.model.examples import (
    TIME,
    example_names,
    experiment,
    read_reference,
    simulate,
)

pytestmark = pytest.mark.slow  # three translations and integrations: about 10 s

EXAMPLES = ("TwoSegmentRod", "BearingAtSpeed", "ProbeOnPlate")


@pytest.fixture(scope="module")
def results() -> dict[str, dict[str, np.ndarray]]:
    return {name: simulate(name, MODELS) for name in EXAMPLES}


def test_every_example_has_an_experiment_and_a_reference():
    assert example_names(MODELS) == list(EXAMPLES)
    for name in EXAMPLES:
        run = experiment(name, MODELS)
        assert run.stop_s > run.start_s and run.interval_s > 0 and run.tolerance <= 1e-6
        assert len(read_reference(name, MODELS)[TIME]) == len(run.times)


@pytest.mark.parametrize("name", EXAMPLES)
def test_an_example_reproduces_its_reference(results, name):
    reference, result = read_reference(name, MODELS), results[name]
    assert list(result) == list(reference)
    for column, expected in reference.items():
        np.testing.assert_allclose(result[column], expected, rtol=1e-7, atol=1e-7,
                                   err_msg=f"{name}: {column}")


def test_the_rod_ends_in_the_linear_profile(results):
    rod = results["TwoSegmentRod"]
    warm, cool, conductance, alpha, length = 40.0, 20.0, 5.0, 1.15e-5, 0.5
    # segment centres at x = 1/4 and 3/4 of a linear profile; the heat is G * (T_a - T_b)
    assert rod["T1_C"][-1] == pytest.approx(warm - (warm - cool) / 4, abs=1e-3)
    assert rod["T2_C"][-1] == pytest.approx(cool + (warm - cool) / 4, abs=1e-3)
    assert rod["Q_W"][-1] == pytest.approx(conductance * (warm - cool), rel=1e-4)
    mean_rise = (rod["T1_C"][-1] + rod["T2_C"][-1]) / 2 - 20.0
    assert rod["dL_um"][-1] == pytest.approx(1e6 * alpha * length * mean_rise, rel=1e-9)


def test_the_probe_lags_with_its_first_order_time_constant(results):
    probe = results["ProbeOnPlate"]
    capacity, contact, env, plate, air = 10.0, 0.5, 0.02, 40.0, 20.0
    tau = capacity / (contact + env)
    final = (contact * plate + env * air) / (contact + env)
    exact = final + (air - final) * np.exp(-probe[TIME] / tau)
    np.testing.assert_allclose(probe["T_probe_C"], exact, atol=1e-4)  # BDF at rtol 1e-8: 8e-6 K


def test_the_bearing_settles_where_its_friction_heat_leaves_through_the_seat(results):
    bearing = results["BearingAtSpeed"]
    assert bearing["Q_friction_W"][-1] == pytest.approx(bearing["Q_seat_W"][-1], rel=1e-5)
    assert bearing["Q_seat_W"][-1] == pytest.approx(15.0 * (bearing["T_rings_C"][-1] - 20.0))
    # the oil thins as the rings warm: less friction heat than at the cold start
    assert bearing["Q_friction_W"][-1] < 0.6 * bearing["Q_friction_W"][0]
    assert math.isclose(bearing["T_rings_C"][0], 20.0)


def test_an_unknown_example_is_one_line():
    with pytest.raises(SpindlebenchError, match=r"no example SpindleBench\.Examples\.Nope$"):
        experiment("Nope", MODELS)
