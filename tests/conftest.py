"""Shared test set-up: the repository's paths and fixtures more than one test module uses.

Test modules import the paths (``from conftest import REPO``); fixtures are found by pytest.
"""

from __future__ import annotations

from pathlib import Path

import pytest

#: The repository root (the folder holding ``tests/``).
REPO = Path(__file__).resolve().parents[1]
MODELS = REPO / "models"
FMU = REPO / "fmus" / "SpindleBench.fmu"
SCENARIOS = REPO / "scenarios"
#: The real recordings, outside the repository (never copied in).
SHARED_RECORDINGS = REPO.parent / "shared" / "recordings"
REAL_RECORDING = SHARED_RECORDINGS / "caiviac-fl-thermal" / "data.csv"
#: A 10-minute constant-speed scenario: the smallest real simulation, for tests that feed it
#: bad variations or interrupt it.
QUICK = """\
duration_s = 600
step_s = 10.0
sample_interval_s = 60
seed = 2

[speed]
kind = "constant"
rpm = 3000

[feed]
kind = "with_spindle"
x_mm_per_min = 1500
y_mm_per_min = 1500

[ambient]
kind = "constant"
temperature_C = 18.0
"""


@pytest.fixture(scope="session")
def repo() -> Path:
    """The repository root."""
    return REPO


#: The slowest modules, longest first: each builds the FMU from the Modelica source (gcc on
#: 1.5 MB of generated C) or executes the course's notebooks. They are collected first so
#: that under ``make test`` (pytest-xdist, ``--dist loadfile --no-loadscope-reorder``) they
#: start at once on different workers instead of being the last, lone, tail of the run.
SLOW_FIRST = ("test_fmu_build.py", "test_notebooks.py", "test_install.py")

#: Module-scoped fixtures (``file::fixture``) that cost seconds (a simulated study, a fitted
#: twin, a docs build, an FMU build): every test that uses one is ``slow``, also a quick
#: assertion on it, since running it alone pays for the fixture.
SLOW_FIXTURES = frozenset({
    "test_calibration.py::twin", "test_docs.py::site", "test_model_physics.py::ode",
    "test_paper_study.py::generated", "test_paper_study.py::caiviac_runs",
    "test_placement_study.py::tiny_run", "test_reliability.py::tiny_sweep",
    "test_sweep_run.py::reference", "test_fmu_build.py::rebuilt", "test_fmu_build.py::coarse",
    "test_install.py::installed", "test_notebooks.py::executed",
})

#: Tests (``file::function``, every parametrisation) of modules other people edit that take
#: more than ~3 s on an idle 2-core machine (a real simulation of hours, a study, a child
#: interpreter, a Modelica translation), from ``pytest --durations``. Kept here rather than
#: as decorators in those files so that the marks do not collide with their edits; a test
#: moved into its own module later can carry ``@pytest.mark.slow`` itself.
SLOW_TESTS = frozenset({
    "test_calibration.py::test_calibrated_machine_runs_through_sweep_unchanged",
    "test_calibration.py::test_fit_bounds_respect_the_fmus_declared_range",
    "test_cli.py::test_console_script_is_installed",
    "test_column_roles.py::test_paper_takes_the_roles_from_its_study_file",
    "test_column_roles.py::test_the_example_can_be_regenerated",
    "test_five_probe.py::test_the_unit_check_covers_the_five_probe_equations",
    "test_model_frontend.py::test_missing_equation_is_reported_with_the_file",
    "test_model_frontend.py::test_pymoca_translates_the_machine_with_the_requested_segments",
    "test_overview_plot.py::test_plot_command_draws_one_or_several_recordings",
    "test_overview_plot.py::test_simulate_plot_writes_the_figure_beside_the_recording",
    "test_paper_study.py::test_a_folder_in_the_way_of_an_output_leaves_every_old_file_in_place",
    "test_paper_study.py::test_a_sidecar_of_another_csv_is_one_warning_line_and_not_embedded",
    "test_paper_study.py::test_folder_study_file_is_used_without_config_and_named_in_errors",
    "test_paper_study.py::test_list_flags_space_or_comma_separated_and_unused_columns_ignored",
    "test_paper_study.py::test_list_flags_with_an_empty_item_are_refused",
    "test_paper_study.py::test_methods_compared_table",
    "test_paper_study.py::test_paper_tables_4_and_5_only_beside_a_study_that_trains_like_the_paper",
    "test_paper_study.py::test_real_runs_comparison",
    "test_paper_study.py::test_rerun_into_the_same_folder_removes_only_its_own_stale_files",
    "test_paper_study.py::test_table6_of_another_training_experiment_shows_no_paper_numbers",
    "test_paper_study.py::test_table6_shows_the_papers_numbers_only_for_the_experiments_we_predict",
    "test_paper_study.py::test_table6_without_a_common_experiment_shows_no_paper_numbers",
    "test_placement_study.py::test_a_rerun_resumes_and_reproduces_the_placements",
    "test_placement_study.py::test_resuming_ignores_comments_but_not_changed_values",
    "test_population.py::test_a_population_sweep_counts_the_machines_on_which_the_claim_holds",
    "test_recording_read_engines.py::test_decimal_comma_cells_read_alike",
    "test_recording_read_engines.py::test_odd_cells_read_alike",
    "test_reliability.py::test_a_damaged_fmu_is_one_line_and_leaves_no_extracted_folder",
    "test_reliability.py::test_a_diverging_simulation_names_the_scenario_and_the_parameters_it_changes",
    "test_reliability.py::test_a_second_signal_while_the_workers_stop_does_not_hang_the_sweep",
    "test_reliability.py::test_a_second_study_process_in_a_locked_folder_is_refused_naming_the_holder",
    "test_reliability.py::test_a_signal_during_simulate_ends_it_at_once_with_one_line_and_nothing_written",
    "test_reliability.py::test_a_study_parameter_outside_the_declared_bounds_is_refused",
    "test_reliability.py::test_a_unit_error_in_an_equation_is_file_and_line",
    "test_reliability.py::test_an_ambient_csv_row_with_an_extra_field_is_refused_naming_the_line",
    "test_reliability.py::test_an_unknown_unit_is_file_and_line",
    "test_reliability.py::test_cli_prints_the_named_file_of_a_refused_write",
    "test_reliability.py::test_kill_9_of_a_sweep_leaves_no_worker_forkserver_or_tracker_behind",
    "test_reliability.py::test_resuming_over_damaged_results_names_and_redoes_the_damaged_pieces",
    "test_reliability.py::test_sigterm_during_place_stops_it_and_the_rerun_resumes_to_the_same_bytes",
    "test_reliability.py::test_the_shipped_model_passes_the_unit_check",
    "test_reliability.py::test_warnings_from_sweep_workers_are_one_line_each",
    "test_runner_fmu_cache.py::test_main_and_worker_processes_remove_their_folder_at_exit",
    "test_selection_missing.py::test_checked_recordings_reused_give_what_evaluate_gives_each_time",
    "test_selection_missing.py::test_paper_study_option_and_config_key",
    "test_simulate_cli.py::test_console_script_runs_a_shipped_scenario",
    "test_sweep_methods.py::test_one_pass_scores_equal_each_method_on_its_own_frames",
})


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark the tests of ``SLOW_TESTS`` and the users of ``SLOW_FIXTURES`` ``slow``; run the
    modules of ``SLOW_FIRST`` first (in that order), every other in its order."""
    for item in items:
        module = item.path.name
        fixtures = {f"{module}::{name}" for name in getattr(item, "fixturenames", ())}
        if (f"{module}::{getattr(item, 'originalname', item.name)}" in SLOW_TESTS
                or fixtures & SLOW_FIXTURES):
            item.add_marker(pytest.mark.slow)

    def rank(item: pytest.Item) -> int:
        name = item.path.name
        return SLOW_FIRST.index(name) if name in SLOW_FIRST else len(SLOW_FIRST)

    items.sort(key=rank)  # stable: the order inside each module is kept


#: What a test run may add to the checkout: caches of Python and of the tools themselves.
_ALLOWED_LEFTOVERS = ("__pycache__", ".pytest_cache", ".ruff_cache", ".venv", ".egg-info",
                      "build/")
_checkout_before: set[str] | None = None


def _untracked() -> set[str] | None:
    """The checkout's untracked and ignored entries (``git status``), or None without git."""
    import subprocess

    try:
        done = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--ignored"],
                              capture_output=True, text=True, timeout=60, check=True)
    except (OSError, subprocess.SubprocessError):
        return None
    return {line[3:] for line in done.stdout.splitlines()
            if line[:2] in ("??", "!!") and not any(a in line for a in _ALLOWED_LEFTOVERS)}


def pytest_sessionstart(session: pytest.Session) -> None:
    global _checkout_before
    if not hasattr(session.config, "workerinput"):  # the controller, not an xdist worker
        _checkout_before = _untracked()


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Fail the run if it left files in the checkout (tests write under ``tmp_path``; the
    commands' caches go to the per-user cache): ``make test`` wrote ``results/`` before."""
    if _checkout_before is None or hasattr(session.config, "workerinput"):
        return
    after = _untracked()
    new = sorted((after or set()) - _checkout_before)
    if new:
        print(f"\nerror: the tests wrote into the checkout {REPO}: {', '.join(new[:5])}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
