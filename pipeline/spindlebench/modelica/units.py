"""Dimensional check of the Modelica model from its declared ``unit=`` strings, with pint.

Every ``unit="…"`` in the source must be a unit pint knows (Modelica's syntax, ``W/(m2.K)``,
``N.m``, ``rev/min``, is turned into pint's first); an unknown one is ``file:line``. Then
both sides of every flattened equation are given a dimension: a variable has its declared
unit, ``der(x)`` is x's unit per second, products and quotients multiply dimensions, and
the operands of ``+``, ``-``, ``min``, ``max`` and the two sides of ``=`` must agree
(``T - 273.15 + port.Q_flow`` adds a temperature and a power). A literal number adopts the
dimension of what it is added to (Modelica's numbers carry no unit); a variable without a
unit, a fractional power of a dimensioned quantity (an empirical fit such as Palmgren's
``(nu n)^(2/3) dm^3``, whose coefficient hides the units) and exp/log of one (Walther's
``log(log(nu + 0.7))`` on the number of mm2/s) are not checked. Degrees Celsius and kelvin
share the dimension temperature.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

from spindlebench.errors import SpindlebenchError

#: Marker for a literal number (dimension not fixed) and for "unknown, not checked".
LITERAL = "literal"
UNKNOWN = None
#: Functions of a dimensionless argument (dimensionless result); of a dimensioned one: unchecked.
_TRANSCENDENTAL = {"exp", "log", "log10", "sin", "cos", "tan", "asin", "acos", "atan",
                   "sinh", "cosh", "tanh"}
#: Functions whose result has their (first) argument's dimension.
_SAME = {"abs", "sum", "pre", "noEvent", "smooth", "homotopy"}
_UNIT = re.compile(r'\bunit\s*=\s*"([^"]*)"')


@functools.cache
def registry() -> Any:
    import pint

    units = pint.UnitRegistry()
    units.define("rev = revolution")  # Modelica's rev/min
    return units


def pint_unit(modelica: str) -> str:
    """A Modelica unit string in pint's syntax: ``W/(m2.K)`` -> ``W/(m**2*K)``, ``1`` ->
    dimensionless."""
    text = modelica.strip()
    if text in ("", "1"):
        return "dimensionless"
    text = re.sub(r"(?<=[A-Za-z)])\.(?=[A-Za-z(])", "*", text)
    return re.sub(r"([A-Za-z]+)(-?\d+)", r"\1**\2", text)


def dimension_of(modelica: str) -> Any:
    """The pint dimensionality of a Modelica unit string (raises pint's error if unknown)."""
    return registry().parse_units(pint_unit(modelica)).dimensionality


def check_declared_units(path: Path) -> None:
    """Every ``unit="…"`` of the source is a unit pint knows, or one line ``file:line``."""
    import pint

    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        for match in _UNIT.finditer(line.split("//", 1)[0]):
            try:
                dimension_of(match.group(1))
            except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError,
                    AttributeError, TypeError, ValueError) as exc:
                raise SpindlebenchError(f"{path}:{number}: unknown unit {match.group(1)!r} "
                                        f"(pint: {exc})") from None


class _MismatchError(Exception):
    def __init__(self, what: str) -> None:
        super().__init__(what)
        self.what = what


def check_equations(flat_class: Any, path: Path) -> None:
    """Both sides of every equation of the flattened class agree in dimension, or one line
    ``file:line`` naming the equation's left-hand variable and the two dimensions."""
    import pymoca.ast as ast

    units = {}
    for name, symbol in flat_class.symbols.items():
        unit = getattr(symbol.unit, "value", None)
        if isinstance(unit, str) and unit:
            units[name] = dimension_of(unit)

    def show(dim: Any) -> str:
        return "dimensionless" if not dim else str(dim)

    def same(a: Any, b: Any, what: str) -> Any:
        if a is UNKNOWN or b is UNKNOWN:
            return UNKNOWN
        if a == LITERAL:
            return b
        if b == LITERAL:
            return a
        if a != b:
            raise _MismatchError(f"{what} of {show(a)} and {show(b)}")
        return a

    def plain(a: Any) -> Any:
        return registry().parse_units("dimensionless").dimensionality if a == LITERAL else a

    def dim(node: Any) -> Any:
        if isinstance(node, ast.Primary):
            return LITERAL if isinstance(node.value, int | float) else UNKNOWN
        if isinstance(node, ast.ComponentRef):
            return units.get(_name(node), UNKNOWN)
        if not isinstance(node, ast.Expression):
            return UNKNOWN
        op = str(getattr(node.operator, "name", node.operator))
        args = [dim(o) for o in node.operands]
        if op in ("+", "-") and len(args) == 2:
            return same(args[0], args[1], "a sum" if op == "+" else "a difference")
        if op == "-" and len(args) == 1:
            return args[0]
        if op in ("*", "/") and len(args) == 2:
            if UNKNOWN in args:
                return UNKNOWN
            if args[0] == LITERAL and args[1] == LITERAL:
                return LITERAL
            a, b = plain(args[0]), plain(args[1])
            return a * b if op == "*" else a / b
        if op == "^" and len(args) == 2:
            if args[0] in (UNKNOWN, LITERAL):
                return args[0]
            power = _constant(node.operands[1])
            if power is None or not float(power).is_integer():
                return UNKNOWN  # a fractional power: an empirical fit, not tracked
            return args[0] ** int(power)
        if op == "der" and len(args) == 1:
            return UNKNOWN if args[0] in (UNKNOWN, LITERAL) else \
                args[0] / registry().parse_units("s").dimensionality
        if op in ("min", "max"):
            result = args[0]
            for other in args[1:]:
                result = same(result, other, f"{op}()")
            return result
        if op in _SAME and args:
            return args[0]
        if op == "sqrt" and len(args) == 1:
            return UNKNOWN if args[0] in (UNKNOWN, LITERAL) else args[0] ** 0.5
        if op in _TRANSCENDENTAL and len(args) == 1:
            # log(nu + 0.7) of a viscosity in mm2/s: an empirical law on numerical values
            return LITERAL if args[0] == LITERAL or args[0] == {} else UNKNOWN
        return UNKNOWN

    def equations(items: list[Any]) -> Any:
        for item in items:
            if isinstance(item, ast.ForEquation):
                yield from equations(item.equations)
            elif isinstance(item, ast.Equation):
                yield item

    for equation in equations(flat_class.equations):
        try:
            left, right = dim(equation.left), dim(equation.right)
            same(left, right, "an equation between")
        except _MismatchError as exc:
            name = _name(equation.left) if isinstance(equation.left, ast.ComponentRef) else ""
            raise SpindlebenchError(f"{_where(path, name)}: unit error in the equation of "
                                    f"{name or 'an expression'}: {exc.what}") from None


def _constant(node: Any) -> float | None:
    """The value of an expression of literal numbers (``2.0 / 3.0``), else None."""
    import pymoca.ast as ast

    if isinstance(node, ast.Primary):
        return float(node.value) if isinstance(node.value, int | float) else None
    if isinstance(node, ast.Expression) and str(node.operator) in "+-*/" and node.operands:
        values = [_constant(o) for o in node.operands]
        if None in values:
            return None
        if len(values) == 1:
            return -values[0] if str(node.operator) == "-" else values[0]
        a, b = values[0], values[1]
        op = str(node.operator)
        if op == "/" and b == 0:
            return None
        return {"+": a + b, "-": a - b, "*": a * b, "/": a / b if b else 0.0}[op]
    return None


def _name(ref: Any) -> str:
    """The flattened name of a component reference (``a.b.c``), without indices."""
    parts = [ref.name]
    while getattr(ref, "child", None):
        ref = ref.child[0]
        parts.append(ref.name)
    return ".".join(parts)


def _where(path: Path, name: str) -> str:
    """``file:line`` of the first equation line that assigns ``name`` (its last part, as the
    component class writes it), or the file."""
    last = name.split(".")[-1]
    if last:
        pattern = re.compile(rf"(?<![\w.]){re.escape(last)}(\[[^\]]*\])?\s*=(?!=)")
        in_equations = False
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            code = line.split("//", 1)[0].strip()
            if re.match(r"^(initial\s+)?equation\b", code):
                in_equations = True
            elif re.match(r"^(end\b|model\b|block\b|connector\b|package\b|public\b|"
                          r"protected\b)", code):
                in_equations = False
            elif in_equations and pattern.search(re.sub(r'"[^"]*"', '""', code)):
                return f"{path}:{number}"
    return str(path)
