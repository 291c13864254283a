"""Studies built on the testbench: season stress tests (``sweep``) and sensor placement.

The shared machinery (study-file checking, executors, resumable result stores, seeds) lives
here so that every study runs, resumes and reports the same way.
"""
