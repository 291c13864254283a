"""Which parameters a calibration should fit when the data cannot separate them all.

On a real machine with unknown sensor places and no room channel (CAIVIAC) the 13 fitted
parameters of the default set include pairs the data do not separate (the housing's heat
capacity against the rear bearing's friction, r = +0.84) and estimates that run to a bound
of the factor range: the fit then buys a better training error with a structure that does not
carry to other speeds. Three ways to fit fewer effective parameters, each decided from the
training data alone (``VARIANTS``):

- ``no-capacities``: the ten parameters of the set before the heat capacities (issue 22);
- ``tied-capacities``: the full set with the three heat capacities moved by one common
  factor (one time scale of the whole machine instead of three that can trade against each
  other and against the heat inputs);
- ``regularised``: the full set, refitted with every channel's noise set to the misfit the
  first fit left on it (its RMSE, at least its stated noise). The stated noise (the
  sample-to-sample scatter, 0.02 K) is 25-350 times smaller than what any fit leaves on a real
  machine, so the log-factors' priors (``fitset.PRIOR_SD_LN``: a factor e) weigh nothing
  against 10^4 data; with the noise at the misfit a direction the data hardly see is pulled to
  the engineering value instead of a bound (the noise-scale estimate of empirical Bayes, two
  passes);
- ``pruned``: the full set, then every parameter whose estimate sits at a bound of its
  factor range is left at its start value and the rest refitted (a bound is where the fit
  compensates for structure, not where it measures).

How the variant is chosen without looking at the held-out runs is ``nested_choice``: the same
fold one level down (train on all training runs but the last, predict the last).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from spindlebench.calibration import problem
from spindlebench.calibration.problem import Discretisation, Fit, calibrate
from spindlebench.calibration.series import Series

#: The heat capacities of the default set (``fitset.DEFAULT_FIT``), which ``no-capacities``
#: leaves out.
CAPACITIES = ("spindle_shaft_C", "housing_C", "column_C")


@dataclass(frozen=True)
class VariantFit:
    """One variant's calibration: its discretisation (its own fit set) and fit."""

    variant: str
    discretisation: Discretisation
    fit: Fit
    #: Parameters the variant left at their start value (at a bound in the first pass, or
    #: the capacities for ``no-capacities``).
    fixed: tuple[str, ...] = ()
    #: Model evaluations of every pass together.
    evaluations: int = 0
    seconds: float = 0.0


def at_bound(d: Discretisation, fit: Fit) -> list[str]:
    """The fitted parameters whose estimate sits at a bound of its factor range."""
    return problem.at_bound(d, fit.log_factors)


def misfit_weighted(series_list: Sequence[Series], fit: Fit) -> list[Series]:
    """The recordings with each channel's noise set to what ``fit`` left on it (its RMSE),
    never below the stated noise."""
    rmse = {(r["recording"], r["column"]): r["rmse"] for r in fit.channel_rmse}
    return [replace(series, channels=tuple(
        replace(c, noise=max(c.noise, rmse.get((series.name, c.column), c.noise)))
        for c in series.channels)) for series in series_list]


def fit_variant(variant: str, d: Discretisation, train: Sequence[Series], max_iter: int,
                first: Fit | None = None) -> VariantFit:
    """Calibrate ``train`` by ``variant`` (one of ``VARIANTS``) from ``d``'s fit set;
    ``first``: the full set's fit on ``train`` if already made (the first pass)."""
    if variant not in VARIANTS:
        raise ValueError(f"unknown variant {variant!r} (have {', '.join(VARIANTS)})")
    if variant == "tied-capacities":
        fitted = [n for n in d.fit if n not in CAPACITIES[1:]]
        tied = Discretisation(d.ode, fitted, d.base,
                              ties={CAPACITIES[0]: CAPACITIES[1:]})
        only = calibrate(tied, train, max_iter=max_iter)
        return VariantFit(variant, tied, only, (), only.evaluations, only.seconds)
    if variant == "no-capacities":
        fixed = tuple(name for name in d.fit if name in CAPACITIES)
        reduced = Discretisation(d.ode, [n for n in d.fit if n not in fixed], d.base)
        only = calibrate(reduced, train, max_iter=max_iter)
        return VariantFit(variant, reduced, only, fixed, only.evaluations, only.seconds)
    first = first or calibrate(d, train, max_iter=max_iter)
    if variant == "full":
        return VariantFit(variant, d, first, (), first.evaluations, first.seconds)
    if variant == "regularised":
        second = calibrate(d, misfit_weighted(train, first), max_iter=max_iter)
        return VariantFit(variant, d, second, (), first.evaluations + second.evaluations,
                          first.seconds + second.seconds)
    fixed = tuple(at_bound(d, first))
    if not fixed:
        return VariantFit(variant, d, first, (), first.evaluations, first.seconds)
    reduced = Discretisation(d.ode, [n for n in d.fit if n not in fixed], d.base)
    second = calibrate(reduced, train, max_iter=max_iter)
    return VariantFit(variant, reduced, second, fixed,
                      first.evaluations + second.evaluations, first.seconds + second.seconds)


#: The variants compared, in the order of the tables; ``full`` is the default set as it is.
VARIANTS = ("full", "no-capacities", "tied-capacities", "regularised", "pruned")


def nested_choice(scores: dict[str, float]) -> str:
    """The variant with the lowest inner held-out RMSE (ties: the earlier in ``VARIANTS``)."""
    return min(scores, key=lambda v: (scores[v], VARIANTS.index(v)))


def evaluate_variants(d: Discretisation, train: Sequence[Series], max_iter: int,
                      score: Callable[[VariantFit], list[float]],
                      variants: Sequence[str] = VARIANTS, first: Fit | None = None
                      ) -> dict[str, tuple[VariantFit, list[float]]]:
    """Every variant fitted on ``train`` and scored by ``score`` (held-out RMSE per run);
    ``first``: the full set's fit on ``train`` if already made."""
    results: dict[str, tuple[VariantFit, list[float]]] = {}
    for variant in variants:
        result = fit_variant(variant, d, train, max_iter, first)
        if variant == "full":
            first = result.fit
        results[variant] = (result, score(result))
    return results

