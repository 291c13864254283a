"""Bring your own method: a scikit-learn selector, regressor or pipeline named by import path.

A method label's part written ``package.module:Class`` (optionally with parameters,
``package.module:Class[alpha=0.5,mode="x"]``; a value ``"@package.module:name"`` is that
object, e.g. a score function) names the user's estimator class. In the
method's place it must be a selector (scikit-learn's ``SelectorMixin``, or anything with
``get_support()`` after ``fit``); in the regressor's place anything with ``fit`` and
``predict`` (a regressor, or a ``Pipeline`` ending in one). Every command that takes method
labels (``evaluate --method``, study files of ``paper``, ``sweep``, ``place``; ``benchmark
--method``) then runs it through ``registry.select_with`` / ``fit_with``, with the checks a
built-in gets (constant candidates dropped first, the budget checked, one-line errors).

The budget and the seed reach the estimator the way scikit-learn names them: ``k`` (the
package's name, and ``SelectKBest``'s), else ``n_features_to_select`` (``RFE``,
``SequentialFeatureSelector``), else ``n_clusters``; ``random_state`` gets the command's seed
unless the label sets it. ``provenance`` records the class's package, its version and the
SHA-256 of the file that defines it, so a result says which code made it.
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import re
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from spindlebench.selection.errors import SelectionError

#: ``module.path:Attribute`` with an optional ``[name=value,...]``.
_PATH = re.compile(r"^(?P<module>[A-Za-z_][\w.]*):(?P<attr>[A-Za-z_][\w.]*)"
                   r"(?:\[(?P<params>.*)\])?$")
#: The budget's names, in the order they are looked for in an estimator's parameters.
BUDGET_NAMES = ("k", "n_features_to_select", "n_clusters")


def is_import_path(part: str) -> bool:
    """Whether a label part names a user's class (it has a ``:``)."""
    return ":" in part


@dataclass(frozen=True)
class UserMethod:
    """A user's estimator class by import path, with the parameters the label gives it."""

    path: str
    params: tuple[tuple[str, Any], ...] = ()

    @property
    def label(self) -> str:
        if not self.params:
            return self.path
        shown = ",".join(f"{name}={_literal(value)}" for name, value in self.params)
        return f"{self.path}[{shown}]"

    def resolve(self) -> type:
        """The class (imported; a one-line error if it cannot be)."""
        module_name, _, attr = self.path.partition(":")
        try:
            target: Any = importlib.import_module(module_name)
        except ImportError as exc:
            raise SelectionError(f"method {self.path!r}: cannot import {module_name!r} ({exc}); "
                                 "is its package installed or on PYTHONPATH?") from None
        for name in attr.split("."):
            if not hasattr(target, name):
                raise SelectionError(f"method {self.path!r}: {module_name!r} has no "
                                     f"{attr!r}")
            target = getattr(target, name)
        if not callable(target):
            raise SelectionError(f"method {self.path!r}: {attr!r} is not a class or factory")
        return target

    def build(self, k: int | None = None, random_state=None, role: str = "method"):
        """An instance with the label's parameters, the budget and the seed set; checked to
        be a selector (``role`` "method") or a regressor (``role`` "regressor")."""
        estimator = self.resolve()()
        check_role(estimator, self.path, role)
        known = estimator.get_params() if hasattr(estimator, "get_params") else {}
        given = dict(self.params)
        unknown = [name for name in given if name not in known]
        if unknown:
            raise SelectionError(f"method {self.path!r}: unknown parameter(s) "
                                 f"{', '.join(unknown)}; it has {', '.join(sorted(known))}")
        settings = {name: _object(value) for name, value in given.items()}
        budget = next((name for name in BUDGET_NAMES if name in known), None)
        if k is not None and budget is not None and budget not in given:
            settings[budget] = int(k)
        if "random_state" in known and "random_state" not in given and random_state is not None:
            settings["random_state"] = random_state
        if settings:
            try:
                estimator.set_params(**settings)
            except (TypeError, ValueError) as exc:
                raise SelectionError(f"method {self.path!r}: {exc}") from None
        return estimator

    def provenance(self) -> dict[str, Any]:
        """Package, version and source hash of the class (what made a result)."""
        cls = self.resolve()
        module_name = getattr(cls, "__module__", self.path.partition(":")[0])
        package = module_name.split(".")[0]
        try:
            source = inspect.getsourcefile(cls)
        except TypeError:
            source = None
        digest = hashlib.sha256(Path(source).read_bytes()).hexdigest() if source else None
        return {"path": self.path, "params": {name: value for name, value in self.params},
                "package": package, "version": _version(package),
                "module": module_name, "source_sha256": digest}


def check_role(estimator: Any, path: str, role: str) -> None:
    """A selector has ``fit`` and ``get_support``; a regressor ``fit`` and ``predict``."""
    if not hasattr(estimator, "fit"):
        raise SelectionError(f"method {path!r}: {type(estimator).__name__} has no fit()")
    if role == "method" and not hasattr(estimator, "get_support"):
        raise SelectionError(f"method {path!r}: a selection method must be a selector "
                             "(scikit-learn SelectorMixin, or get_support()); a regressor or "
                             "pipeline goes in the regressor's place: all-candidates+" + path)
    if role == "regressor" and not hasattr(estimator, "predict"):
        raise SelectionError(f"regressor {path!r}: {type(estimator).__name__} has no "
                             "predict()")


def parse_user_part(part: str) -> UserMethod:
    """``module:Class[name=value,...]`` -> ``UserMethod``; values are TOML literals
    (``3``, ``0.5``, ``true``, ``"text"``), a bare word is a string."""
    match = _PATH.match(part.strip())
    if match is None:
        raise SelectionError(f"method part {part!r}: write an import path as "
                             "package.module:Class, optionally with [name=value,...]")
    params = parse_params(match["params"] or "", part)
    return UserMethod(f"{match['module']}:{match['attr']}", params)


def _object(value: Any) -> Any:
    """A parameter value; ``"@package.module:name"`` is that object (a function, a class:
    ``SelectKBest[score_func="@sklearn.feature_selection:f_regression"]``)."""
    if isinstance(value, str) and value.startswith("@") and is_import_path(value):
        return UserMethod(value[1:]).resolve()
    return value


def parse_params(text: str, where: str) -> tuple[tuple[str, Any], ...]:
    """``a=1,b="x"`` -> ((a, 1), (b, "x")); one-line error naming ``where``."""
    out: dict[str, Any] = {}
    for item in _split_top(text, ","):
        if not item.strip():
            continue
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name.isidentifier():
            raise SelectionError(f"{where}: parameter {item.strip()!r} is not name=value")
        if name in out:
            raise SelectionError(f"{where}: parameter {name!r} given twice")
        out[name] = parse_value(value.strip())
    return tuple(out.items())


def parse_value(text: str) -> Any:
    """A TOML literal, or the text itself."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def split_label(label: str) -> list[str]:
    """A method label's ``+``-separated parts, ignoring ``+`` inside ``[...]``."""
    return [part.strip() for part in _split_top(label, "+")]


def _split_top(text: str, separator: str) -> list[str]:
    parts, depth, current = [], 0, []
    for char in text:
        depth += char == "["
        depth -= char == "]"
        if char == separator and depth == 0:
            parts.append("".join(current))
            current = []
        else:
            current.append(char)
    parts.append("".join(current))
    return parts


def _literal(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace('"', '\\"') + '"'
    return repr(value)


def _version(package: str) -> str | None:
    """The installed version of the distribution that provides the top-level ``package``
    (``sklearn`` -> scikit-learn's), else the module's ``__version__``."""
    from importlib import metadata

    for distribution in metadata.packages_distributions().get(package, [package]):
        try:
            return metadata.version(distribution)
        except metadata.PackageNotFoundError:
            continue
    version = getattr(sys.modules.get(package), "__version__", None)
    return None if version is None else str(version)
