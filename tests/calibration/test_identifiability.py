"""The fit-set variants of ``calibration.identifiability`` decided from the training fit alone:
which estimates count as at a bound, the noise a refit is weighted with, the nested choice."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from spindlebench.calibration import identifiability
from spindlebench.calibration.series import Channel, Series


class _Bounds:
    fit = ("a", "b", "c", "d")

    def log_bounds(self):
        return np.log(np.full(4, 0.1)), np.log(np.array([10.0, 10.0, 10.0, 2.0]))


def test_at_bound_finds_estimates_at_either_bound_of_their_own_range():
    # a at x0.1, b inside, c a factor 1.02 below x10 (inside), d at its narrowed bound x2
    fit = SimpleNamespace(log_factors=np.log([0.1, 1.5, 10.0 / 1.02, 2.0 * 0.999]))
    assert identifiability.at_bound(_Bounds(), fit) == ["a", "d"]


def _series(name: str, noises: list[float]) -> Series:
    values = np.zeros(3)
    channels = tuple(Channel(f"c{i}", f"T{i + 1}_C", "temperature", values, n)
                     for i, n in enumerate(noises))
    return Series(name=name, path=Path(f"{name}.csv"), sha256="", time_s=np.arange(3.0),
                  inputs=np.zeros((4, 3)), channels=channels, ambient_unknown=False,
                  ambient_knot_h=4.0)


def test_misfit_weighting_sets_each_channel_noise_to_its_rmse_never_below_the_stated():
    series = [_series("r1", [0.02, 0.5]), _series("r2", [0.02, 0.02])]
    fit = SimpleNamespace(channel_rmse=[
        {"recording": "r1", "column": "c0", "rmse": 1.5},
        {"recording": "r1", "column": "c1", "rmse": 0.1},  # below its stated noise: kept
        {"recording": "r2", "column": "c0", "rmse": 3.0},
        {"recording": "r2", "column": "c1", "rmse": 0.2}])
    weighted = identifiability.misfit_weighted(series, fit)
    assert [[c.noise for c in s.channels] for s in weighted] == [[1.5, 0.5], [3.0, 0.2]]
    assert [c.noise for c in series[0].channels] == [0.02, 0.5]  # the input is not changed


def test_nested_choice_is_the_lowest_inner_error_and_refuses_unknown_variants():
    assert identifiability.nested_choice({"full": 27.8, "no-capacities": 32.2,
                                          "pruned": 42.2}) == "full"
    assert identifiability.nested_choice({"full": 3.0, "pruned": 3.0}) == "full"
    with pytest.raises(ValueError, match="unknown variant 'tied'"):
        identifiability.fit_variant("tied", None, [], 1)


@pytest.mark.slow
def test_tied_capacities_move_together_as_one_factor():
    """A tie (``Discretisation(ties=...)``) is the same model as fitting every tied parameter
    with the same log-factor: the step residual and the reported values agree."""
    from conftest import MODELS
    from spindlebench.calibration.problem import Discretisation
    from spindlebench.model.equations import explicit_ode

    ode = explicit_ode(MODELS, segments=2)
    first, *rest = identifiability.CAPACITIES
    tied = Discretisation(ode, [first], ode.parameter_vector(), ties={first: tuple(rest)})
    every = Discretisation(ode, list(identifiability.CAPACITIES), ode.parameter_vector())
    rng = np.random.default_rng(3)
    z0 = 20.0 + rng.random(tied.n_x)
    z1 = z0 + 0.1 * rng.random(tied.n_x)
    u, h, s = [3000.0, 0.0, 0.0, 21.0], 60.0, np.log(2.0)
    residual = np.asarray(tied.step(z0, z1, u, h, [s])).ravel()
    assert np.allclose(residual, np.asarray(every.step(z0, z1, u, h, [s] * 3)).ravel(),
                       rtol=1e-12, atol=1e-12)
    # and it is not the untied model with only the first moved
    alone = Discretisation(ode, [first], ode.parameter_vector())
    assert not np.allclose(residual, np.asarray(alone.step(z0, z1, u, h, [s])).ravel())
    values = tied.parameters(np.array([s]))
    defaults = dict(zip(ode.parameters, ode.parameter_vector(), strict=True))
    assert values == pytest.approx({n: 2.0 * defaults[n] for n in identifiability.CAPACITIES})
