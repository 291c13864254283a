"""The machine's explicit ODE kept on disk, so each process does not translate the model again.

Translating ``models/SpindleBench.mo`` (pymoca's parse and flatten, the unit checks and the
causalisation) costs about 9 CPU-s. That is 90 % of a small ``calibrate``, and every process
that needs the equations paid it again: each command, each notebook, each test's child
interpreter. The result is a CasADi SX function plus names, starts, units and bounds. It is
stored as one JSON file with the function in CasADi's own serialisation
(``Function.serialize``). Reading it back takes about 20 ms. The evaluated numbers are the
same: the graph is the same, node for node.

The file is in ``$SPINDLEBENCH_ODE_CACHE``, else ``ode/`` in ``paths.user_cache_dir()``. It is
named by a SHA-256 of everything the ODE depends on: the Modelica source's bytes, the segment
count, the model class, and the source of the modules that translate it, with the package
versions (pymoca and CasADi among them). It is written atomically, so parallel processes can
share it, and an edited model or front end can never hit a stale entry. The file also carries
its key and a SHA-256 of all its fields, and is used only when both match. An edited or
damaged entry is named in a warning and computed again. Only a successful translation is
stored, so every error in a model source is still reported on every run.
"""

from __future__ import annotations

import hashlib
import json
import warnings
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from spindlebench.core import atomic
from spindlebench.core.errors import StaleCacheWarning
from spindlebench.core.paths import user_cache_folder
from spindlebench.core.provenance import sha256_file, source_sha256
from spindlebench.model.equations import ExplicitOde, build_explicit_ode
from spindlebench.model.frontend import check_segments, model_source, translate

CACHE_ENV = "SPINDLEBENCH_ODE_CACHE"
#: Bumped when the stored layout changes, so old cache files are not read.
RECIPE = 1
#: The modules whose source (with the package versions) is part of the key: a changed front
#: end, unit check or causalisation computes another ODE.
ODE_CODE = ("spindlebench.model.frontend", "spindlebench.model.units",
            "spindlebench.model.causalise", "spindlebench.model.equations",
            "spindlebench.model.ode_cache")
#: The fields stored as JSON as they are (the rest: the function, arrays, bounds).
_PLAIN = ("states", "inputs", "parameters", "outputs", "segments", "units", "descriptions")


def cache_dir() -> Path:
    """Where translated models are kept: ``$SPINDLEBENCH_ODE_CACHE``, else ``ode/`` in the
    per-user cache (``paths.user_cache_dir``), never the current folder."""
    return user_cache_folder("ode", CACHE_ENV)


def ode_key(source: Path, segments: int, model_class: str) -> str:
    """SHA-256 of everything the explicit ODE of ``source`` depends on."""
    what = {"recipe": RECIPE, "code_sha256": source_sha256(*ODE_CODE),
            "source_sha256": sha256_file(source), "segments": segments,
            "model_class": model_class}
    text = json.dumps(what, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def cached_explicit_ode(model_dir: str | Path, segments: int, model_class: str) -> ExplicitOde:
    """The explicit ODE of ``model_dir``'s model: from the cache file when it holds this
    source's, else translated (errors as :func:`frontend.translate` gives them) and stored."""
    check_segments(segments)
    source = model_source(model_dir)
    key = ode_key(source, segments, model_class)
    file = cache_dir() / f"{key}.json"
    ode = _load(file, key)
    if ode is None:
        ode = build_explicit_ode(translate(model_dir, segments, model_class))
        _store(file, key, ode)
    return ode


def _store(file: Path, key: str, ode: ExplicitOde) -> None:
    """Write ``ode`` to ``file``; a cache that cannot be written only costs the next run
    the translation again, so a refused write is a warning, not an error."""
    function = ode.ode.serialize()
    entry: dict[str, Any] = {name: getattr(ode, name) for name in _PLAIN}
    entry.update(
        key=key, recipe=RECIPE, function=function,
        state_start=ode.state_start.tolist(), input_start=ode.input_start.tolist(),
        bounds={name: list(bound) for name, bound in ode.bounds.items()},
    )
    entry["entry_sha256"] = _entry_sha256(entry)
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        atomic.write_text(file, json.dumps(entry))
    except OSError as exc:
        warnings.warn(f"{file}: could not keep the translated model ({exc.strerror or exc}); "
                      "the next run translates it again", StaleCacheWarning, stacklevel=3)


def _load(file: Path, key: str) -> ExplicitOde | None:
    """The ODE stored in ``file``, or None (with a warning if the file exists but is not a
    good entry for ``key``)."""
    try:
        entry = json.loads(file.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as exc:
        return _stale(file, f"cannot be read ({exc})")
    if not isinstance(entry, dict) or entry.get("key") != key or entry.get("recipe") != RECIPE:
        return _stale(file, "is not the entry of this model")
    if entry.pop("entry_sha256", None) != _entry_sha256(entry):
        return _stale(file, "does not match its hash (edited or damaged)")
    try:
        ode = ca.Function.deserialize(entry["function"])
        return ExplicitOde(
            ode=ode,
            state_start=np.array(entry["state_start"], dtype=float),
            input_start=np.array(entry["input_start"], dtype=float),
            bounds={name: tuple(bound) for name, bound in entry["bounds"].items()},
            symbols=(ode.sx_in(0), ode.sx_in(1), ode.sx_in(2)),
            **{name: entry[name] for name in _PLAIN},
        )
    except (KeyError, TypeError, ValueError, RuntimeError) as exc:
        return _stale(file, f"is incomplete ({exc!r})")


def _entry_sha256(entry: dict[str, Any]) -> str:
    """SHA-256 of an entry's every field but this hash (JSON text, keys sorted)."""
    text = json.dumps(entry, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _stale(file: Path, why: str) -> None:
    warnings.warn(f"{file}: translated-model cache {why}; translating again",
                  StaleCacheWarning, stacklevel=3)
    return None
