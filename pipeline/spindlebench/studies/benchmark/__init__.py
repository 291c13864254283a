"""The benchmark study (``spindlebench benchmark``, ``commands/benchmark.py``): a versioned
task suite, fair baselines and a leaderboard.

- ``benchmark_file``: the suite file (``benchmarks/<suite>.toml``), its version and the hash
  of its tasks;
- ``tasks``: the folds of every task (synthetic families simulated with the FMU, the CAIVIAC
  runs, a user's own recordings);
- ``scoring``: every method and baseline on every fold, through ``selection.evaluate``;
- ``benchmark_run``: one run (entrants, tasks, scores, files);
- ``benchmark_report``: ranks, marks, and the Markdown, CSV, JSON and figure.
"""
