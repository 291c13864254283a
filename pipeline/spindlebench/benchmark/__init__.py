"""``spindlebench benchmark``: a versioned task suite, fair baselines and a leaderboard.

- ``suite``: the suite file (``benchmarks/<suite>.toml``), its version and the hash of its
  tasks;
- ``tasks``: the folds of every task (synthetic families simulated with the FMU, the CAIVIAC
  runs, a user's own recordings);
- ``scoring``: every method and baseline on every fold, through ``selection.evaluate``;
- ``leaderboard``: ranks, marks, and the Markdown, CSV, JSON and figure;
- ``command``: the sub-command.
"""
