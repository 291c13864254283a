"""formats.json_text writes exactly the text of json.dumps(indent=2, ensure_ascii=False)."""

from __future__ import annotations

import dataclasses
import datetime
import enum
import json
import uuid

import numpy as np
import pytest
from conftest import QUICK
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.formats.json_text import indented_json
from spindlebench.formats.recording import write_recording
from spindlebench.testbench.scenario import load_scenario
from spindlebench.testbench.simulate import record


def _reference(data, **options) -> str:
    return json.dumps(data, indent=2, ensure_ascii=False, **options)


class _Colour(enum.IntEnum):
    RED = 1


@dataclasses.dataclass
class _Point:
    x: float = 1.0


AWKWARD = [
    {}, [], {"a": {}, "b": [], "c": [[]], "d": [{}]}, "text", 0, None, True,
    {"floats": [0.0, -0.0, 1e-4, 9.999e-5, 1e-5, 1e-7, -2.5e-7, 1e16, 9.999999999999998e15,
                1.5e300, 5e-324, 2.2250738585072014e-308, 0.1 + 0.2, 6000.0, -1e22, 123.456]},
    {"ints": [2**63 - 1, -2**63, 2**64 - 1, 2**64, -2**63 - 1, 10**30]},
    {"strings": ["\x00\x01\x1f\x7f", 'q"uote\\back', "tab\tnl\ncr\r\b\f", "é€😀\u2028\ufeff"]},
    {"tuple": (1, 2.5, "x"), "nested": {"deep": [[[{"k": 1e-9}]]]}},
    {1: "int key"}, {1.5: "float key"}, {True: 1, None: 2},
    {"nan": float("nan")}, {"inf": [float("inf")]}, [float("-inf")],
    {"enum": _Colour.RED}, [np.float64(1.5), np.float64(1e-5)],
]


@pytest.mark.parametrize("data", AWKWARD)
def test_awkward_values_give_the_text_of_json_dumps(data):
    assert indented_json(data) == _reference(data)


@pytest.mark.parametrize("data", [{"nan": float("nan")}, [float("inf")], {"x": _Point()},
                                  [uuid.UUID(int=1)], {"d": datetime.date(2024, 1, 1)}])
def test_what_json_refuses_is_refused_alike_and_default_is_used_as_json_uses_it(data):
    for options in ({"allow_nan": False}, {"default": None}):
        try:
            expected = _reference(data, **options)
        except (TypeError, ValueError) as exc:
            with pytest.raises(type(exc)):
                indented_json(data, **options)
        else:
            assert indented_json(data, **options) == expected
    assert indented_json(data, default=str) == _reference(data, default=str)


def test_random_floats_and_integers_give_the_text_of_json_dumps():
    rng = np.random.default_rng(26)
    bits = rng.integers(0, 2**63, 20_000, dtype=np.int64).view(np.float64)
    floats = [x for x in bits.tolist() if np.isfinite(x)]
    scaled = (rng.standard_normal(20_000) * 10.0 ** rng.integers(-12, 20, 20_000)).tolist()
    data = {"bits": floats, "scaled": scaled,
            "ints": rng.integers(-2**62, 2**62, 2_000).tolist(), "neg": [-x for x in scaled]}
    assert indented_json(data) == _reference(data)


def test_a_simulated_recordings_sidecar_is_the_text_of_json_dumps(tmp_path):
    scenario = tmp_path / "quick.toml"
    scenario.write_text(QUICK, encoding="utf-8")
    frame, sidecar = record(load_scenario(scenario), DEFAULT_FMU)
    write_recording(tmp_path / "r.csv", frame, sidecar)
    written = (tmp_path / "r.json").read_text(encoding="utf-8")
    paired = json.loads(written)
    assert written == _reference(paired, allow_nan=False) + "\n"
    assert paired == {**sidecar, "recording_sha256": paired["recording_sha256"]}
