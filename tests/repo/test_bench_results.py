"""``bench/results.record``: the machine-readable file every bench script writes."""

from __future__ import annotations

import importlib.util
import json
import os

from conftest import REPO


def _results_module():
    spec = importlib.util.spec_from_file_location("bench_results", REPO / "bench" / "results.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_record_writes_the_rows_with_machine_load_date_and_commit(tmp_path):
    results = _results_module()
    rows = [{"command": "spindlebench --help", "cpu_s_min": 0.04}]
    path = results.record("bench_example", rows, {"help_cpu_s": 0.5}, folder=tmp_path)
    assert path == tmp_path / "bench_example.json"
    document = json.loads(path.read_text(encoding="utf-8"))
    assert document["script"] == "bench_example"
    assert document["rows"] == rows and document["goals"] == {"help_cpu_s": 0.5}
    assert document["machine"]["nproc"] == os.cpu_count()
    assert document["machine"]["cpu_model"]
    assert len(document["load_average"]) == 3
    assert document["date_utc"].endswith("+00:00")
    probe = document["speed_probe_ms"]
    assert probe["additions"] == results.PROBE_ADDITIONS
    assert probe["start"] == results.PROBE_AT_START_MS and 0 < probe["end"] < 60_000
    assert document["git_commit"] is None or len(document["git_commit"].split("+")[0]) == 40
    assert [p.name for p in tmp_path.iterdir()] == ["bench_example.json"]  # no temporary left


def test_a_second_kind_of_run_gets_its_own_file(tmp_path):
    results = _results_module()
    path = results.record("bench_example", [{"row": "x"}], folder=tmp_path,
                          name="bench_example_b")
    assert path == tmp_path / "bench_example_b.json"
    assert json.loads(path.read_text(encoding="utf-8"))["script"] == "bench_example"
    assert not (tmp_path / "bench_example.json").exists()


def test_the_calibration_twin_perturbs_exactly_the_parameters_it_fits():
    """bench_calibration's true factors are keyed by name and cover its fit set (a positional
    tuple of 10 stopped matching when the default fit set gained the heat capacities)."""
    import sys

    sys.path.insert(0, str(REPO / "bench"))
    try:
        spec = importlib.util.spec_from_file_location(
            "bench_calibration", REPO / "bench" / "bench_calibration.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(REPO / "bench"))
    from spindlebench.calibration.fitset import DEFAULT_FIT

    assert sorted(module.FACTORS) == sorted(module.FIT)
    assert set(module.FIT) == set(DEFAULT_FIT) - {"table_L", "c_y_motor"}
    assert all(0.7 <= f <= 1.35 and f != 1.0 for f in module.FACTORS.values())
