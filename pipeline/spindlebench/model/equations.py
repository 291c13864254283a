"""The machine as an explicit ODE ``xdot, y = ode(x, u, p)``: what the FMU contains.

pymoca gives implicit residuals over arrays; here they become scalar CasADi SX expressions,
parameters are split into tunable ones (numeric defaults), dependent ones (bindings to other
parameters, substituted) and structural integers (array sizes, fixed at build time), and the
equations are causalised. The FMU export and the ``solve_ivp`` baseline of ``bench/`` both use
this object, so they integrate exactly the same equations.

Naming (the FMU interface in docs/contracts.md): the sub-assembly level is dropped
(``spindle_unit.front_bearing.C`` is ``front_bearing_C``: the FMU names were fixed before the
machine was split into sub-assemblies, and recordings and machine files use them), then dots
become underscores; element ``i`` of an array state ``a.T`` is the state ``a_i_T``; every state
except the sensor probes' (``sensor_*``) is a node of the temperature field with an output
``node_<a_i>_C``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.formats.recording import node_of_output, node_output
from spindlebench.model import DEFAULT_SEGMENTS, MODEL_CLASS
from spindlebench.model.causalise import solve_explicitly
from spindlebench.model.frontend import TranslatedModel

SENSOR_PREFIX = "sensor_"
#: A temperature state's FMU name ends in this (``housing_3_T``).
STATE_SUFFIX = "_T"


@dataclass
class ExplicitOde:
    """Explicit equations of the machine with the names and defaults of every quantity."""

    ode: ca.Function
    states: list[str]
    state_start: np.ndarray
    inputs: list[str]
    input_start: np.ndarray
    parameters: dict[str, float]
    outputs: list[str]
    segments: int
    symbols: tuple[ca.SX, ca.SX, ca.SX] = field(repr=False)  # x, u, p of ``ode``
    units: dict[str, str] = field(default_factory=dict)
    descriptions: dict[str, str] = field(default_factory=dict)
    #: Declared ``(min, max)`` of tunable parameters and inputs (None where not declared).
    bounds: dict[str, tuple[float | None, float | None]] = field(default_factory=dict)

    def state_jacobian(self) -> ca.Function:
        """``jac(x, u, p) -> d xdot / d x`` (sparse), for implicit integrators."""
        x, u, p = self.symbols
        xdot = self.ode(x, u, p)[0]
        return ca.Function(
            "xdot_jacobian", [x, u, p], [ca.jacobian(xdot, x)], ["x", "u", "p"], ["J"]
        )

    @property
    def node_states(self) -> list[str]:
        """States that are nodes of the temperature field (sensor probes excluded)."""
        return [name for name in self.states if not name.startswith(SENSOR_PREFIX)]

    def parameter_vector(self, **overrides: float) -> np.ndarray:
        """Parameter values in ``ode`` order: defaults, with ``overrides`` by name."""
        unknown = set(overrides) - set(self.parameters)
        if unknown:
            raise SpindlebenchError(f"unknown parameter(s): {', '.join(sorted(unknown))}")
        return np.array([overrides.get(name, value) for name, value in self.parameters.items()])


def flat_name(path: str, index: int | None = None, assemblies: frozenset[str] = frozenset()) -> str:
    """FMU name of a Modelica variable: ``a.b.T`` → ``a_b_T``, ``a.T[3]`` → ``a_3_T``; a first
    part that is one of the machine's ``assemblies`` is dropped (``headstock.housing.T[3]`` →
    ``housing_3_T``)."""
    parts = path.split(".")
    if len(parts) > 2 and parts[0] in assemblies:
        parts = parts[1:]
    if index is not None:
        parts.insert(len(parts) - 1, str(index))
    return "_".join(parts)


def node_output_name(state_name: str) -> str:
    """Output with a node's temperature in degC: ``housing_3_T`` → ``node_housing_3_C``."""
    return node_output(state_name.removesuffix(STATE_SUFFIX))


@dataclass
class _Group:
    """Scalar SX symbols standing for one group of pymoca's (array) variables."""

    mx: list[ca.MX]
    sx: ca.SX
    names: list[str]  # Modelica element names, e.g. ``housing.T[3]``
    flat: list[str]  # FMU names, e.g. ``housing_3_T``
    bases: list[str]  # declared variable of each element, e.g. ``housing.T``


def _group(variables: list, assemblies: frozenset[str] = frozenset()) -> _Group:
    mx, names, flat, bases = [], [], [], []
    for variable in variables:
        symbol = variable.symbol
        size = symbol.numel()
        base = symbol.name()
        mx.append(symbol)
        if size == 1 and symbol.shape == (1, 1):
            names.append(base)
            flat.append(flat_name(base, assemblies=assemblies))
            bases.append(base)
        else:
            for i in range(1, size + 1):
                names.append(f"{base}[{i}]")
                flat.append(flat_name(base, i, assemblies))
                bases.append(base)
    sx = ca.vertcat(*[ca.SX.sym(name) for name in names]) if names else ca.SX(0, 1)
    return _Group(mx=mx, sx=sx, names=names, flat=flat, bases=bases)


def _mx_vector(symbols: list[ca.MX]) -> ca.MX:
    return ca.veccat(*symbols) if symbols else ca.MX(0, 1)


def _numeric(value: object) -> float | None:
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, int | float | np.floating | np.integer):
        return float(value)
    if isinstance(value, ca.MX | ca.SX | ca.DM) and value.is_constant():
        return float(ca.DM(value))
    return None


def _resolve_parameters(model, group: _Group) -> tuple[ca.SX, dict[str, float], list[int]]:
    """SX values of all parameters in terms of the tunable ones; tunable names and defaults."""
    count = group.sx.numel()
    values: list[ca.SX | None] = [None] * count
    tunable: dict[str, float] = {}
    tunable_index: list[int] = []
    dependent: list[int] = []
    for i, variable in enumerate(model.parameters):
        if variable.symbol.numel() != 1:
            raise SpindlebenchError(f"parameter {group.names[i]}: array parameters unsupported")
        number = _numeric(variable.value)
        structural = variable.python_type in (int, bool)
        if number is not None and not structural:
            values[i] = group.sx[i]
            tunable[group.flat[i]] = number
            tunable_index.append(i)
        elif number is not None:
            values[i] = ca.SX(number)
        elif isinstance(variable.value, ca.MX):
            dependent.append(i)
        else:
            raise SpindlebenchError(f"parameter {group.names[i]} has no value")
    if dependent:
        bindings = ca.Function(
            "bindings",
            [_mx_vector(group.mx)],
            [ca.veccat(*[model.parameters[i].value for i in dependent])],
        ).expand()
        current = ca.vertcat(
            *[values[i] if values[i] is not None else group.sx[i] for i in range(count)]
        )
        dependent_symbols = ca.vertcat(*[group.sx[i] for i in dependent])
        for _ in range(50):
            bound = bindings(current)
            for k, i in enumerate(dependent):
                current[i] = bound[k]
            if not ca.depends_on(current, dependent_symbols):
                break
        else:
            circular = [
                group.names[i] for i in dependent if ca.depends_on(current[i], dependent_symbols)
            ]
            raise SpindlebenchError(f"parameter bindings are circular: {', '.join(circular[:5])}")
        values = [current[i] for i in range(count)]
    for i, variable in enumerate(model.parameters):
        if variable.python_type in (int, bool) and not values[i].is_constant():
            raise SpindlebenchError(
                f"structural parameter {group.names[i]} must not depend on tunable parameters"
            )
    return ca.vertcat(*values), tunable, tunable_index


def build_explicit_ode(translated: TranslatedModel) -> ExplicitOde:
    """Causalise a translated model into an :class:`ExplicitOde`."""
    model = translated.model
    assemblies = translated.assemblies
    states, derivatives, algebraics, inputs, params = (
        _group(group, assemblies) for group in (
            model.states, model.der_states, model.alg_states, model.inputs, model.parameters)
    )

    residual_function = ca.Function(
        "residuals",
        [_mx_vector(g.mx) for g in (states, derivatives, algebraics, inputs, params)],
        [ca.veccat(*model.equations)],
    ).expand()
    parameter_values, tunable, tunable_index = _resolve_parameters(model, params)
    residuals = residual_function(
        states.sx, derivatives.sx, algebraics.sx, inputs.sx, parameter_values
    )
    unknowns = ca.vertcat(derivatives.sx, algebraics.sx)
    try:
        solution, _ = solve_explicitly(residuals, unknowns, derivatives.names + algebraics.names)
    except SpindlebenchError as exc:
        raise SpindlebenchError(f"{translated.source}: {exc}") from None
    n_x = states.sx.numel()
    xdot = solution[:n_x]
    algebraic_values = dict(
        zip(
            algebraics.names, [solution[n_x + i] for i in range(algebraics.sx.numel())], strict=True
        )
    )

    output_names: list[str] = []
    output_values: list[ca.SX] = []
    for name in model.outputs:
        if "." in name or name not in algebraic_values:
            continue
        output_names.append(name)
        output_values.append(algebraic_values[name])
    for i, state in enumerate(states.flat):
        if not state.startswith(SENSOR_PREFIX):
            output_names.append(node_output_name(state))
            output_values.append(states.sx[i] - KELVIN_OFFSET)

    tunable_sx = ca.vertcat(*[params.sx[i] for i in tunable_index])
    y = ca.vertcat(*output_values)
    ode = ca.Function(
        "ode", [states.sx, inputs.sx, tunable_sx], [xdot, y], ["x", "u", "p"], ["xdot", "y"]
    )
    exported = list(states.flat) + list(inputs.flat) + list(tunable) + output_names
    duplicates = {n for n in exported if exported.count(n) > 1}
    if duplicates:
        raise SpindlebenchError(f"FMU names collide: {', '.join(sorted(duplicates))}")

    units, descriptions = _annotations(
        translated, states, inputs, params, tunable_index, output_names
    )
    bounds = _bounds(translated, inputs, params, tunable_index)
    return ExplicitOde(
        ode=ode,
        states=list(states.flat),
        state_start=_starts(model.states, states),
        inputs=list(inputs.flat),
        input_start=_starts(model.inputs, inputs),
        parameters=tunable,
        outputs=output_names,
        segments=translated.segments,
        units=units,
        descriptions=descriptions,
        bounds=bounds,
        symbols=(states.sx, inputs.sx, tunable_sx),
    )


def _starts(variables: list, group: _Group) -> np.ndarray:
    starts: list[float] = []
    for variable in variables:
        start = _numeric(variable.start)
        if start is None:
            raise SpindlebenchError(f"{variable.symbol.name()}: start value must be a number")
        starts.extend([start] * variable.symbol.numel())
    return np.array(starts, dtype=float)


def _annotations(translated, states, inputs, params, tunable_index, output_names):
    """Units and one-line descriptions of every exported name, from the Modelica declarations.

    A component's own description (e.g. the housing's) is appended to its variables', so a
    tunable ``housing_C`` reads "Total heat capacity (Headstock housing, ...)".
    """
    symbols = translated.symbols
    owners = translated.component_descriptions
    units: dict[str, str] = {}
    descriptions: dict[str, str] = {}

    def owner_of(base: str) -> str:
        parts = base.split(".")
        if len(parts) > 2 and parts[0] in translated.assemblies:
            parts = parts[1:]
        return owners.get(parts[0], "") if len(parts) > 1 else ""

    def declared(flat: str, base: str) -> None:
        info = symbols.get(base)
        units[flat] = info.unit if info else ""
        owner = owner_of(base)
        text = info.description if info else ""
        descriptions[flat] = f"{text} ({owner})" if owner and text else text or owner

    counts = {base: states.bases.count(base) for base in set(states.bases)}
    for flat, base, element in zip(states.flat, states.bases, states.names, strict=True):
        units[flat] = symbols[base].unit if base in symbols and symbols[base].unit else "K"
        where = owner_of(base) or base
        if element != base:
            index = element[len(base) + 1 : -1]
            where = f"segment {index} of {counts[base]} of {where}"
        descriptions[flat] = f"Temperature of {where}"
    for flat, base in zip(inputs.flat, inputs.bases, strict=True):
        declared(flat, base)
    for i in tunable_index:
        declared(params.flat[i], params.bases[i])
    for name in output_names:
        node = node_of_output(name)
        if node is not None:
            state = node + STATE_SUFFIX
            units[name] = "degC"
            descriptions[name] = descriptions[state]
        else:
            declared(name, name)
    return units, descriptions


def _bounds(translated, inputs, params, tunable_index) -> dict:
    """Declared bounds of the inputs and tunable parameters, by FMU name."""
    symbols = translated.symbols
    pairs = list(zip(inputs.flat, inputs.bases, strict=True))
    pairs += [(params.flat[i], params.bases[i]) for i in tunable_index]
    bounds = {}
    for flat, base in pairs:
        info = symbols.get(base)
        if info is not None and (info.minimum is not None or info.maximum is not None):
            bounds[flat] = (info.minimum, info.maximum)
    return bounds


def explicit_ode(model_dir: str | Path = "models", segments: int = DEFAULT_SEGMENTS,
                 model_class: str = MODEL_CLASS) -> ExplicitOde:
    """The explicit ODE of ``model_dir``'s Modelica package (its machine, or ``model_class``):
    translated once per source and kept on disk (``model.ode_cache``)."""
    from spindlebench.model.ode_cache import cached_explicit_ode  # imports this module

    return cached_explicit_ode(model_dir, segments, model_class)
