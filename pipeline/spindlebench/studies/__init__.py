"""Studies built on the testbench: season stress tests (``sweep``) and sensor placement.

One subpackage per study type (``sweep``, ``placement``, ``paper``, ``compensation``,
``fingerprint``); what they share lives in ``family`` (the study family file, experiments,
climates, seeds, method specs) and ``running`` (executors, resumable result stores, jobs), so
that every study runs, resumes and reports the same way.
"""
