"""The placement search runs with BLAS and OpenMP single-threaded (issue 26: threaded
k-means cost 24.8 of the tiny study's 28.5 s search on a busy 2-core machine)."""

import importlib

from threadpoolctl import threadpool_info

placements = importlib.import_module("spindlebench.studies.placement.placements")


def test_every_method_searches_single_threaded(monkeypatch):
    import sklearn.cluster  # noqa: F401  (loads the OpenMP runtime k-means uses)

    seen = []
    monkeypatch.setattr(placements, "_find_placements",
                        lambda *args: seen.extend(threadpool_info()) or [])
    assert placements.find_placements(None, [], []) == []
    assert seen, "no thread pool found to check"
    assert {pool["user_api"] for pool in seen} >= {"blas", "openmp"}
    assert all(pool["num_threads"] == 1 for pool in seen), seen
