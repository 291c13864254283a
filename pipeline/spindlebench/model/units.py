"""Dimensional check of the Modelica model from its declared ``unit=`` strings, with pint.

Every ``unit="…"`` in the source must be a unit pint knows (Modelica's syntax, ``W/(m2.K)``,
``N.m``, ``rev/min``, is turned into pint's first); an unknown one is ``file:line``. Every
``Real`` declares a unit (``"1"`` for a pure number); one without is ``file:line`` of its
declaration. Then every flattened equation is given dimensions from the declared units:
``der(x)`` is x's unit per second, ``time`` is seconds, products, quotients and powers
(also fractional ones, ``x ^ (2/3)``, ``sqrt``) combine dimensions, Integers and Booleans
are dimensionless, and

- the operands of ``+``, ``-``, ``min``, ``max``, the branches of ``if … then … else``, both
  sides of a comparison (``<``, ``>=``, ``==`` …) and both sides of ``=`` must agree
  (``T - 273.15 + port.Q_flow`` adds a temperature and a power);
- the argument of ``exp``, ``log``, ``log10``, ``sin``, ``cos``, ``tan``, their inverses and
  hyperbolic forms must be dimensionless, and a power of a dimensioned quantity needs a
  constant exponent;
- ``connect(a, b)`` must join connectors of the same type: the same variables with the same
  units and the same ``flow`` prefixes (a heat port to a heat port), ``file:line`` of the
  connect clause otherwise (:func:`check_connections`, on the parsed source).

A literal number adopts the dimension of what it is added to or compared with (Modelica's
numbers carry no unit). An empirical law written on the numbers of given units (Walther's
``log(log(nu + 0.7))`` on mm2/s and K, Palmgren's ``(nu n)^(2/3) dm^3`` whose coefficient
hides the units) says so in its equation's description string, which must start with
:data:`EMPIRICAL` and say on which units' numbers it works; only such equations are
skipped. Degrees Celsius and kelvin share the dimension temperature.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

from spindlebench.core.errors import SpindlebenchError

#: Markers for a literal number (dimension adopted from its partner), a truth value (a
#: comparison's result) and "unknown, not checked" (an array, an unknown function).
LITERAL = "literal"
BOOLEAN = "boolean"
UNKNOWN = None
#: The start of the description string of an equation that is exempt (an empirical law on
#: numbers of stated units): ``nu = … "unit check: empirical: Walther's law on mm2/s and K";``
EMPIRICAL = "unit check: empirical"
#: Functions of a dimensionless argument, with a dimensionless result.
_TRANSCENDENTAL = {"exp", "log", "log10", "sin", "cos", "tan", "asin", "acos", "atan",
                   "sinh", "cosh", "tanh"}
#: Functions whose result has their (first) argument's dimension.
_SAME = {"abs", "sum", "pre", "noEvent", "homotopy", "delay"}
_COMPARISONS = {"<", "<=", ">", ">=", "==", "<>"}
_LOGICAL = {"and", "or", "not"}
_NUMBERS = ("Integer", "Boolean")  # types without a unit: counts and truth values
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
    """Every equation of the flattened class is dimensionally consistent (see the module
    docstring), or one line ``file:line`` naming the equation's left-hand variable and the
    dimensions that disagree; a ``Real`` without a unit is ``file:line`` of its declaration."""
    import pymoca.ast as ast

    dimensionless = registry().parse_units("dimensionless").dimensionality
    seconds = registry().parse_units("s").dimensionality
    units: dict[str, Any] = {"time": seconds}
    for name, symbol in flat_class.symbols.items():
        unit = getattr(symbol.unit, "value", None)
        kind = str(symbol.type)
        if isinstance(unit, str) and unit:
            units[name] = dimension_of(unit)
        elif kind in _NUMBERS:
            units[name] = dimensionless
        elif kind == "Real":
            raise SpindlebenchError(f"{_declared(path, name)}: {name} declares no unit (give "
                                    "every Real a unit=, \"1\" for a pure number)")

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
        return dimensionless if a == LITERAL else a

    def dim(node: Any) -> Any:
        if isinstance(node, ast.Primary):
            if isinstance(node.value, bool):
                return BOOLEAN
            return LITERAL if isinstance(node.value, int | float) else UNKNOWN
        if isinstance(node, ast.ComponentRef):
            return units.get(_name(node), UNKNOWN)
        if isinstance(node, ast.IfExpression):
            for condition in node.conditions:
                dim(condition)  # a comparison inside is checked
            result = LITERAL
            for branch in node.expressions:
                result = same(result, dim(branch), "the branches of an if-expression")
            return result
        if not isinstance(node, ast.Expression):
            return UNKNOWN
        op = str(getattr(node.operator, "name", node.operator))
        args = [dim(o) for o in node.operands]
        if op in _COMPARISONS and len(args) == 2:
            same(args[0], args[1], f"a comparison ({op})")
            return BOOLEAN
        if op in _LOGICAL:
            return BOOLEAN
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
            if power is None:
                if args[0] != dimensionless:
                    raise _MismatchError(f"a power of {show(args[0])} with a variable "
                                         "exponent (only a dimensionless base may have one)")
                return dimensionless
            return args[0] ** (int(power) if float(power).is_integer() else power)
        if op == "der" and len(args) == 1:
            return UNKNOWN if args[0] in (UNKNOWN, LITERAL) else args[0] / seconds
        if op in ("min", "max"):
            result = args[0]
            for other in args[1:]:
                result = same(result, other, f"{op}()")
            return result
        if op == "smooth" and len(args) == 2:  # smooth(order, expression)
            return args[1]
        if op in _SAME and args:
            return args[0]
        if op == "sqrt" and len(args) == 1:
            return args[0] if args[0] in (UNKNOWN, LITERAL) else args[0] ** 0.5
        if op in _TRANSCENDENTAL and len(args) == 1:
            if args[0] in (UNKNOWN, LITERAL):
                return args[0]
            if args[0] != dimensionless:
                raise _MismatchError(f"{op}() of {show(args[0])}: its argument must be "
                                     "dimensionless (an empirical law on numbers? say so in "
                                     f"the equation's description, \"{EMPIRICAL}: ...\")")
            return dimensionless
        return UNKNOWN

    def equations(items: list[Any]) -> Any:
        for item in items:
            if isinstance(item, ast.ForEquation):
                yield from equations(item.equations)
            elif isinstance(item, ast.IfEquation | ast.WhenEquation):
                yield from ((c, item) for c in item.conditions)
                for block in item.blocks:
                    yield from equations(block)
            elif isinstance(item, ast.Equation):
                yield item, item

    for node, owner in equations(flat_class.equations):
        if str(getattr(owner, "comment", "") or "").startswith(EMPIRICAL):
            continue
        try:
            if isinstance(node, ast.Equation):
                same(dim(node.left), dim(node.right), "sides")
            else:
                dim(node)  # the condition of an if- or when-equation
        except _MismatchError as exc:
            left = getattr(node, "left", None)
            name = _name(left) if isinstance(left, ast.ComponentRef) else ""
            raise SpindlebenchError(f"{_where(path, name)}: unit error in the equation of "
                                    f"{name or 'an expression'}: {exc.what}") from None


def check_connections(tree: Any, path: Path) -> None:
    """Every ``connect(a, b)`` of the parsed source joins two connectors of the same type
    (the same variables, units and ``flow`` prefixes), or one line ``file:line``."""
    import pymoca.ast as ast

    def clauses(items: list[Any]) -> Any:
        for item in items:
            if isinstance(item, ast.ConnectClause):
                yield item
            elif isinstance(item, ast.ForEquation):
                yield from clauses(item.equations)
            elif isinstance(item, ast.IfEquation):
                for block in item.blocks:
                    yield from clauses(block)

    for cls in _classes(tree):
        for clause in clauses(cls.equations):
            left, right = _connector(cls, clause.left), _connector(cls, clause.right)
            if left is None or right is None or left[1] == right[1]:
                continue  # a name pymoca cannot resolve is its own error, reported later
            a, b = _name(clause.left), _name(clause.right)
            raise SpindlebenchError(
                f"{_connect_line(path, a, b)}: connect({a}, {b}) joins a {left[0]} and a "
                f"{right[0]}: a connection needs two connectors of one type (the same "
                f"variables, units and flow prefixes; {left[0]}: {_show_signature(left[1])}; "
                f"{right[0]}: {_show_signature(right[1])})")


def _classes(node: Any) -> Any:
    for cls in getattr(node, "classes", {}).values():
        yield cls
        yield from _classes(cls)


def _lookup(name: str, scope: Any) -> Any:
    """The class a dotted type name means inside ``scope`` (Modelica's lookup: the scope,
    then its enclosing classes), or None."""
    parts = name.split(".")
    while scope is not None:
        found = getattr(scope, "classes", {}).get(parts[0])
        for part in parts[1:]:
            found = getattr(found, "classes", {}).get(part) if found is not None else None
        if found is not None:
            return found
        scope = getattr(scope, "parent", None)
    return None


def _symbol(cls: Any, name: str, seen: frozenset = frozenset()) -> tuple[Any, Any] | None:
    """A component ``name`` of ``cls`` or of a class it extends, with the class declaring it."""
    if name in cls.symbols:
        return cls.symbols[name], cls
    for extends in getattr(cls, "extends", []):
        base = _lookup(_name(extends.component), cls.parent or cls)
        if base is not None and id(base) not in seen:
            found = _symbol(base, name, seen | {id(cls)})
            if found is not None:
                return found
    return None


def _all_symbols(cls: Any, seen: frozenset = frozenset()) -> dict[str, Any]:
    symbols: dict[str, Any] = {}
    for extends in getattr(cls, "extends", []):
        base = _lookup(_name(extends.component), cls.parent or cls)
        if base is not None and id(base) not in seen:
            symbols.update(_all_symbols(base, seen | {id(cls)}))
    symbols.update(cls.symbols)
    return symbols


def _connector(cls: Any, ref: Any) -> tuple[str, tuple] | None:
    """The type name and signature (variable, type, unit, flow) of the connector ``ref``
    names inside ``cls``, or None when it cannot be resolved."""
    import pymoca.ast as ast

    parts, node = [], ref
    while node is not None:
        parts.append(node.name)
        node = node.child[0] if getattr(node, "child", None) else None
    scope = cls
    for i, part in enumerate(parts):
        found = _symbol(scope, part)
        if found is None or not isinstance(found[0].type, ast.ComponentRef):
            return None
        symbol, owner = found
        type_name = _name(symbol.type)
        if type_name in ("Real", "Integer", "Boolean"):
            if i != len(parts) - 1:
                return None
            return type_name, ((type_name, _unit_of(symbol), "flow" in symbol.prefixes),)
        scope = _lookup(type_name, owner)
        if scope is None:
            return None
    signature = tuple(sorted(
        (name, _name(s.type) if isinstance(s.type, ast.ComponentRef) else "",
         str(_unit_of(s)), "flow" in s.prefixes)
        for name, s in _all_symbols(scope).items()))
    return str(scope.name), signature


def _unit_of(symbol: Any) -> str | None:
    """The ``unit=`` of a parsed (not flattened) declaration: pymoca keeps it in the
    declaration's modification until flattening."""
    unit = getattr(symbol.unit, "value", None)
    if unit is not None:
        return str(unit)
    modification = getattr(symbol, "class_modification", None)
    for argument in getattr(modification, "arguments", []):
        value = getattr(argument, "value", None)
        if str(getattr(getattr(value, "component", None), "name", "")) == "unit":
            for item in getattr(value, "modifications", []):
                if getattr(item, "value", None) is not None:
                    return str(item.value)
    return None


def _show_signature(signature: tuple) -> str:
    return ", ".join(f"{'flow ' if item[-1] else ''}{item[0]}"
                     + (f" [{item[2]}]" if len(item) == 4 and item[2] != "None" else "")
                     for item in signature)


def _connect_line(path: Path, left: str, right: str) -> str:
    """``file:line`` of the connect clause joining ``left`` and ``right``, or the file."""
    pattern = re.compile(rf"connect\(\s*{re.escape(left)}(\[[^\]]*\])?\s*,\s*"
                         rf"{re.escape(right)}(\[[^\]]*\])?\s*\)")
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if pattern.search(line.split("//", 1)[0]):
            return f"{path}:{number}"
    return str(path)


def _declared(path: Path, name: str) -> str:
    """``file:line`` of the declaration of ``name``'s last part, or the file."""
    last = re.escape(name.split(".")[-1])
    pattern = re.compile(rf"\b(Real|Integer|Boolean)\b[^;]*?(?<![\w.]){last}\b")
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if pattern.search(line.split("//", 1)[0]):
            return f"{path}:{number}"
    return str(path)


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
