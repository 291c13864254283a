"""The translated model kept on disk (model.ode_cache): the same ODE, node for node; any
change of the source is a new entry; a damaged entry is named and computed again."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from conftest import MODELS
from spindlebench.core.errors import StaleCacheWarning
from spindlebench.model import DEFAULT_SEGMENTS, MODEL_CLASS, MODEL_FILE, ode_cache
from spindlebench.model.equations import ExplicitOde, explicit_ode


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv(ode_cache.CACHE_ENV, str(tmp_path / "ode"))
    return tmp_path / "ode"


def _same(a: ExplicitOde, b: ExplicitOde) -> None:
    for field in dataclasses.fields(ExplicitOde):
        if field.name in ("ode", "symbols"):
            continue
        left, right = getattr(a, field.name), getattr(b, field.name)
        if isinstance(left, np.ndarray):
            assert left.dtype == right.dtype and np.array_equal(left, right), field.name
        else:
            assert left == right and type(left) is type(right), field.name
    assert list(a.parameters) == list(b.parameters)  # the order of ``p``
    assert a.ode.serialize() == b.ode.serialize()
    rng = np.random.default_rng(3)
    x = a.state_start + rng.uniform(0.0, 30.0, a.state_start.size)
    u = a.input_start + rng.uniform(0.0, 1.0, a.input_start.size)
    p = a.parameter_vector()
    for left, right in zip(a.ode(x, u, p), b.ode(x, u, p), strict=True):
        assert np.array_equal(np.array(left), np.array(right))
    assert np.array_equal(np.array(a.state_jacobian()(x, u, p)),
                          np.array(b.state_jacobian()(x, u, p)))


@pytest.mark.slow
def test_a_cached_model_is_the_translated_one_bit_for_bit(cache):
    translated = explicit_ode(MODELS)  # an empty cache: translated, then stored
    (entry,) = cache.glob("*.json")
    loaded = explicit_ode(MODELS)
    assert loaded is not translated
    _same(translated, loaded)
    entry.write_text(entry.read_text().replace('"segments": ', '"segments": 1'))
    with pytest.warns(StaleCacheWarning, match=str(entry)):
        assert ode_cache._load(entry, entry.stem) is None  # the hash no longer matches


def test_every_input_of_the_translation_is_in_the_key(tmp_path):
    source = MODELS / MODEL_FILE
    key = ode_cache.ode_key(source, DEFAULT_SEGMENTS, MODEL_CLASS)
    edited = tmp_path / MODEL_FILE
    edited.write_bytes(source.read_bytes() + b"\n// a comment\n")
    assert ode_cache.ode_key(edited, DEFAULT_SEGMENTS, MODEL_CLASS) != key
    assert ode_cache.ode_key(source, DEFAULT_SEGMENTS + 1, MODEL_CLASS) != key
    assert ode_cache.ode_key(source, DEFAULT_SEGMENTS, "SpindleBench.Other") != key
    assert ode_cache.ode_key(source, DEFAULT_SEGMENTS, MODEL_CLASS) == key


@pytest.mark.parametrize("damage", ["not json", "other key", "function edited", "incomplete"])
def test_a_damaged_entry_is_named_and_not_used(cache, damage):
    cache.mkdir()
    file = cache / "k.json"
    entry = {"key": "k", "recipe": ode_cache.RECIPE, "function": "x"}
    if damage == "not json":
        file.write_text("{")
    else:
        if damage == "other key":
            entry["key"] = "other"
        entry["entry_sha256"] = ode_cache._entry_sha256(entry)
        if damage == "function edited":
            entry["function"] = "y"
        file.write_text(json.dumps(entry))  # "incomplete": hash right, the fields missing
    with pytest.warns(StaleCacheWarning, match=str(file)):
        assert ode_cache._load(file, "k") is None


def test_no_file_is_a_quiet_miss(cache):
    assert ode_cache._load(cache / "absent.json", "absent") is None
