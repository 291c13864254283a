"""Read the Modelica package and translate it with pymoca into implicit CasADi equations.

The segment count of the large parts is a structural Modelica parameter (``nSeg``); a build
overrides its binding in the parsed syntax tree (what a modification ``(nSeg = N)`` would do),
so the Modelica source itself never has to be generated or edited.
"""

from __future__ import annotations

import contextlib
import io
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import casadi as ca

from spindlebench.core.errors import SpindlebenchError
from spindlebench.model import MAX_SEGMENTS, MODEL_CLASS, MODEL_FILE
from spindlebench.model.units import check_connections, check_declared_units, check_equations

# pymoca 0.12 still calls the Python 2 division hook on CasADi 3.8 expressions.
ca.MX.__div__ = ca.MX.__truediv__

SEGMENTS_PARAMETER = "nSeg"
#: The package of the machine's sub-assemblies (``SpindleBench.Assemblies``).
ASSEMBLY_PACKAGE = "Assemblies"


@dataclass(frozen=True)
class SymbolInfo:
    """Declaration facts pymoca's CasADi model drops: description, unit and the bounds.

    ``minimum``/``maximum`` are the declared ``min``/``max`` when they are plain numbers
    (None when not declared), so the FMU can carry them and importers refuse values outside.
    """

    description: str
    unit: str
    minimum: float | None = None
    maximum: float | None = None


@dataclass
class TranslatedModel:
    """pymoca's CasADi model plus the declaration facts of the flattened class."""

    model: Any
    symbols: dict[str, SymbolInfo]
    component_descriptions: dict[str, str]
    source: Path
    segments: int
    #: Instance names of the machine's sub-assemblies (classes of ``ASSEMBLY_PACKAGE``): the
    #: FMU names drop them (``equations.flat_name``).
    assemblies: frozenset[str] = frozenset()


def model_source(model_dir: str | Path) -> Path:
    """The Modelica file of the package, or a one-line error if it is missing."""
    path = Path(model_dir) / MODEL_FILE
    if not path.is_file():
        raise SpindlebenchError(f"{path}: Modelica source not found")
    try:  # rumoca and pymoca both fail on other encodings with a traceback
        path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        line = path.read_bytes()[: exc.start].count(b"\n") + 1
        raise SpindlebenchError(f"{path}:{line}: Modelica source is not UTF-8 text (byte "
                                f"{exc.start}); save it as UTF-8") from None
    check_nesting(path)
    return path


#: Deepest nesting of brackets, and of classes (``package``/``model``/... ``end``), a model
#: source may have: models/SpindleBench.mo needs 4 and 4; both front ends recurse per level, a
#: source nested thousands deep ran out of stack or for minutes.
MAX_BRACKET_DEPTH, MAX_CLASS_DEPTH = 100, 20
_CLASS_START = re.compile(r"^\s*(?:(?:partial|encapsulated|expandable|operator|pure|impure|"
                          r"replaceable|redeclare|final|inner|outer)\s+)*(?:package|model|block|"
                          r"connector|record|function|class|type)\s+\w+\b(?!\s*=)")
_CLASS_END = re.compile(r"^\s*end\s+(?!(?:for|if|when|while)\b)\w+\s*;")


def check_nesting(path: Path) -> None:
    """Refuse, naming the line, a source nested deeper than any machine model needs."""
    text = path.read_text(encoding="utf-8")
    text = re.sub(r'"(?:[^"\\]|\\.)*"', '""', text)  # strings may hold any bracket
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    depth = classes = 0
    for number, line in enumerate(text.splitlines(), start=1):
        code = line.split("//", 1)[0]
        if _CLASS_START.match(code):
            classes += 1
        if _CLASS_END.match(code):
            classes -= 1
        if classes > MAX_CLASS_DEPTH:
            raise SpindlebenchError(f"{path}:{number}: classes nested more than "
                                    f"{MAX_CLASS_DEPTH} deep; no machine model needs that")
        for char in code:
            depth += char in "([{"
            depth -= char in ")]}"
            if depth > MAX_BRACKET_DEPTH:
                raise SpindlebenchError(f"{path}:{number}: brackets nested more than "
                                        f"{MAX_BRACKET_DEPTH} deep; no machine model needs "
                                        "that")


def _syntax_error_line(message: str) -> int | None:
    match = re.search(r"line (\d+)", message)
    return int(match.group(1)) if match else None


def check_segments(segments: object) -> None:
    """Refuse a segment count the model is not meant for, before any slow step runs."""
    if (isinstance(segments, bool) or not isinstance(segments, int)
            or not 2 <= segments <= MAX_SEGMENTS):
        raise SpindlebenchError(f"segments: must be an integer from 2 to {MAX_SEGMENTS}, got "
                                f"{segments!r}")


def translate(model_dir: str | Path, segments: int,
              model_class: str = MODEL_CLASS) -> TranslatedModel:
    """Parse and flatten the machine model (or another class of the package, such as an
    ``Examples`` model, which has no segment count to set) into pymoca's CasADi representation.

    Errors in the Modelica text become one line naming the file and line.
    """
    import pymoca.ast
    import pymoca.backends.casadi.generator as generator
    import pymoca.parser
    import pymoca.tree

    check_segments(segments)
    path = model_source(model_dir)
    check_declared_units(path)  # file:line of a unit pint does not know, before parsing
    text = path.read_text(encoding="utf-8")
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stderr(chatter), contextlib.redirect_stdout(chatter):
            tree = pymoca.parser.parse(text, bypass_cache=True)
    except pymoca.parser.ModelicaSyntaxError as exc:
        message = str(exc).splitlines()[0]
        line = _syntax_error_line(message)
        where = f"{path}:{line}" if line else str(path)
        raise SpindlebenchError(f"{where}: Modelica syntax error: {message}") from None
    if tree is None:
        raise SpindlebenchError(f"{path}: Modelica source could not be parsed")
    if model_class == MODEL_CLASS:
        _set_segments(tree, path, segments)
    elif _class_of(tree, model_class) is None:
        raise SpindlebenchError(f"{path}: no class {model_class}")
    check_connections(tree, path)  # file:line of a connect() of two different connectors
    try:
        with contextlib.redirect_stderr(chatter), contextlib.redirect_stdout(chatter):
            flat = pymoca.tree.flatten(tree, pymoca.ast.ComponentRef.from_string(model_class))
        (flat_class,) = flat.classes.values()
    except Exception as exc:  # pymoca raises many types; all mean "this model is wrong"
        raise SpindlebenchError(_semantic_error(path, exc)) from None
    check_equations(flat_class, path)  # dimensions, from the declared units (pint)
    try:
        with contextlib.redirect_stderr(chatter), contextlib.redirect_stdout(chatter):
            # generator.generate() would flatten a second time; walk the flat tree ourselves.
            options = generator._merge_default_options(None)
            casadi_generator = generator.Generator(flat, model_class, options)
            generator.GeneratorWalker().walk(casadi_generator, flat)
            model = casadi_generator.model
    except Exception as exc:  # pymoca raises many types; all mean "this model is wrong"
        raise SpindlebenchError(_semantic_error(path, exc)) from None
    symbols = {
        name: SymbolInfo(
            description=str(sym.comment or ""),
            unit=_unit_of(sym),
            minimum=_bound_of(sym, "min"),
            maximum=_bound_of(sym, "max"),
        )
        for name, sym in flat_class.symbols.items()
    }
    assemblies, components = _components(tree, model_class)
    return TranslatedModel(
        model=model,
        symbols=symbols,
        component_descriptions=components,
        source=path,
        segments=segments,
        assemblies=assemblies,
    )


def _components(tree: Any, model_class: str) -> tuple[frozenset[str], dict[str, str]]:
    """The model's sub-assembly instances, and the description of every component by its
    FMU name: the model's own, and those inside its sub-assemblies (``front_bearing``)."""
    top = _class_of(tree, model_class).symbols
    package = model_class.split(".")[0]
    assembly_classes = getattr(tree.classes[package].classes.get(ASSEMBLY_PACKAGE), "classes", {})
    assemblies = frozenset(
        name for name, sym in top.items()
        if str(getattr(sym.type, "name", sym.type)).split(".")[-1] in assembly_classes
    )
    components = {name: str(sym.comment or "") for name, sym in top.items()}
    for name in sorted(assemblies):
        kind = str(getattr(top[name].type, "name", top[name].type)).split(".")[-1]
        for inner, sym in assembly_classes[kind].symbols.items():
            components.setdefault(inner, str(sym.comment or ""))
    return assemblies, components


def _class_of(tree: Any, dotted: str) -> Any:
    """The parsed class ``A.B.C`` of the tree, or None."""
    found: Any = tree
    for part in dotted.split("."):
        found = getattr(found, "classes", {}).get(part)
        if found is None:
            return None
    return found


def _set_segments(tree: Any, path: Path, segments: int) -> None:
    """Bind ``nSeg`` of the machine to ``segments`` in the parsed tree."""
    import pymoca.ast

    package, model = MODEL_CLASS.split(".")
    try:
        symbol = tree.classes[package].classes[model].symbols[SEGMENTS_PARAMETER]
    except KeyError:
        raise SpindlebenchError(
            f"{path}: model {MODEL_CLASS} with parameter {SEGMENTS_PARAMETER} not found"
        ) from None
    for argument in symbol.class_modification.arguments:
        modification = argument.value
        if (
            getattr(modification, "component", None) is not None
            and str(getattr(modification.component, "name", modification.component)) == "value"
        ):
            modification.modifications = [pymoca.ast.Primary(value=segments)]
            return
    raise SpindlebenchError(f"{path}: parameter {SEGMENTS_PARAMETER} needs a default value")


def _unit_of(symbol: Any) -> str:
    unit = getattr(symbol, "unit", None)
    value = getattr(unit, "value", unit)
    return value if isinstance(value, str) else ""


def _bound_of(symbol: Any, attribute: str) -> float | None:
    """A declared ``min``/``max`` that is a finite number, else None (pymoca's default is None)."""
    bound = getattr(symbol, attribute, None)
    value = getattr(bound, "value", bound)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if abs(value) != float("inf") else None


def _semantic_error(path: Path, exc: Exception) -> str:
    """One line for a model pymoca cannot flatten, located as well as we can.

    rumoca's diagnostics carry a line; failing that, a name pymoca could not resolve (its
    error quotes it) is looked up in the source, so the user gets ``file:line`` either way.
    """
    detail = " ".join(str(exc).split()) or type(exc).__name__
    for diagnostic in validate(path):
        return f"{diagnostic} (pymoca: {detail})"
    quoted = re.search(r"'([A-Za-z_][\w.\[\]]*)'", detail)
    if quoted:
        name = quoted.group(1).split(".")[-1].split("[")[0]
        pattern = re.compile(rf"(?<![\w.\"]){re.escape(name)}(?![\w\"])")
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            code = line.split("//", 1)[0]
            if pattern.search(re.sub(r'"[^"]*"', '""', code)):
                return f"{path}:{number}: Modelica error: cannot resolve '{quoted.group(1)}'"
    return f"{path}: Modelica model could not be translated: {detail}"


def validate(path: str | Path) -> list[str]:
    """Check the package with rumoca, an independent Modelica front end.

    Returns one line per problem (``file:line:column: message``); empty when rumoca accepts it.
    """
    import rumoca

    path = Path(path)
    problems = []
    for diagnostic in rumoca.validate(str(path), model=MODEL_CLASS):
        problems.append(_diagnostic_line(path, diagnostic))
    return problems


def _diagnostic_line(path: Path, diagnostic: Any) -> str:
    text = str(diagnostic)
    # rumoca's own position is often 1:1; the real one is in the rendered snippet ─[file:L:C]
    match = re.search(r"─\[[^\]]*?:(\d+):(\d+)\]", text)
    line, column = (
        (match.group(1), match.group(2)) if match else (diagnostic.line, diagnostic.column)
    )
    message = str(diagnostic.message)
    # keep the first complaint ("× unexpected `flow`"), not the rendered source snippet
    complaint = re.search(r"×\s*(.*?)\s*(?:╭|$)", message, flags=re.S)
    summary = " ".join((complaint.group(1) if complaint else message).split())
    summary = re.sub(r"\s*│\s*", " ", summary)
    return f"{path}:{line}:{column}: {summary}"
