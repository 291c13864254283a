"""Issue 28: a followed lock link, a hung sweep, shipped files overwritten, trusted caches.

One test (at least) per item of the issue, each against the real code path that failed:
data loss, hangs, silent wrong results, security and misleading messages. The hostile-input
table (tests/system/test_hostile_inputs.py) holds the one-line refusals of the command line; this
file holds what needs more than one command or a look at the bytes.
"""

from __future__ import annotations

import gzip
import hashlib
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from conftest import REPO
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.paths import DEFAULT_FMU, allow_shipped, refuse_shipped, shipped
from spindlebench.studies.running.store import ResultStore

TINY_COMPENSATE = REPO / "scenarios" / "studies" / "tiny_compensate.toml"
DEFAULT_MACHINE = REPO / "scenarios" / "machines" / "default.toml"


def sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def one_error_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("error: ") and "Traceback" not in stderr
    return lines[0]


# --------------------------------------------------------------------------- data loss


def test_a_lock_that_is_a_symlink_is_refused_and_its_target_untouched(tmp_path):
    victim = tmp_path / "precious.txt"
    victim.write_text("keep me\n", encoding="utf-8")
    root = tmp_path / "results"
    root.mkdir()
    (root / ".lock").symlink_to(victim)
    with pytest.raises(SpindlebenchError, match="symbolic link"):
        ResultStore(root).lock()
    assert victim.read_text(encoding="utf-8") == "keep me\n"


def test_a_lock_that_is_a_fifo_is_refused_without_blocking(tmp_path):
    root = tmp_path / "results"
    root.mkdir()
    os.mkfifo(root / ".lock")
    with pytest.raises(SpindlebenchError, match="not a regular file"):
        ResultStore(root).lock()


def test_a_symlinked_subfolder_of_a_results_folder_is_never_written_through(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    root = tmp_path / "results"
    root.mkdir()
    (root / "runs").symlink_to(elsewhere, target_is_directory=True)
    store = ResultStore(root)
    with pytest.raises(SpindlebenchError, match="symbolic link inside the results folder"):
        store.write_json("runs/r000/x.json", {"a": 1})
    assert not any(elsewhere.iterdir())


def test_a_piece_or_a_new_folder_turned_into_a_link_is_refused_after_earlier_writes(tmp_path):
    """The store looks at a real folder once; a piece that is a link, or a folder it has not
    found yet that is one, is refused however many writes came before."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    root = tmp_path / "results"
    store = ResultStore(root)
    store.write_json("runs/r000/x.json", {"a": 1})
    store.write_json("runs/r000/y.json", {"a": 1})  # runs/ and r000/ seen to be real
    (root / "runs" / "r000" / "x.json").unlink()
    (root / "runs" / "r000" / "x.json").symlink_to(elsewhere / "x.json")
    (root / "runs" / "r001").symlink_to(elsewhere, target_is_directory=True)
    for piece in ("runs/r000/x.json", "runs/r001/x.json"):
        with pytest.raises(SpindlebenchError, match="symbolic link inside the results folder"):
            store.write_json(piece, {"a": 2})
    assert not any(elsewhere.iterdir())


def test_a_link_to_a_shipped_file_is_shipped_in_a_folder_checked_before(tmp_path):
    """``shipped`` resolves a folder once per process, the file itself every time."""
    (tmp_path / "plain.toml").write_text("", encoding="utf-8")
    assert not shipped(tmp_path / "plain.toml")
    (tmp_path / "machine.toml").symlink_to(DEFAULT_MACHINE)
    (tmp_path / "scenarios").symlink_to(REPO / "scenarios", target_is_directory=True)
    assert shipped(tmp_path / "machine.toml")
    assert shipped(tmp_path / "scenarios" / "seasons" / "chongqing.toml")
    with pytest.raises(SpindlebenchError, match="--overwrite-shipped"):
        refuse_shipped(tmp_path / "machine.toml")


def test_a_linked_results_root_is_still_allowed(tmp_path):
    """Results on another disk through a link is a user's choice, not an attack."""
    real = tmp_path / "disk"
    real.mkdir()
    (tmp_path / "results").symlink_to(real, target_is_directory=True)
    store = ResultStore(tmp_path / "results")
    store.write_json("a/b.json", {"x": 1})
    assert (real / "a" / "b.json").is_file()


@pytest.mark.parametrize("target", [
    DEFAULT_MACHINE, DEFAULT_FMU, REPO / "scenarios" / "seasons" / "chongqing.toml",
    REPO / "models" / "SpindleBench.mo", REPO / "pipeline" / "spindlebench" / "new.csv"])
def test_shipped_files_are_never_an_output_unless_allowed(target):
    assert shipped(target)
    with pytest.raises(SpindlebenchError, match="--overwrite-shipped"):
        refuse_shipped(target)
    with allow_shipped():
        refuse_shipped(target)  # --overwrite-shipped: allowed
    with allow_shipped(target):
        refuse_shipped(target)


def test_a_new_file_beside_the_shipped_machines_is_not_shipped():
    assert not shipped(REPO / "scenarios" / "machines" / "mine-not-there.toml")
    assert not shipped(REPO / "fmus" / "SpindleBench_3seg.fmu")


@pytest.mark.skipif(not (REPO / ".git").exists(), reason="needs the git checkout")
def test_a_users_own_machine_file_there_may_be_written_again():
    """README's `calibrate ... -o scenarios/machines/mine.toml`, run twice."""
    mine = REPO / "scenarios" / "machines" / f"zz-untracked-{os.getpid()}.toml"
    mine.write_text("# a user's machine\n", encoding="utf-8")
    try:
        assert not shipped(mine)
        refuse_shipped(mine)
    finally:
        mine.unlink()


def test_calibrate_refuses_to_replace_the_default_machine_before_any_work(tmp_path, capsys):
    before = sha(DEFAULT_MACHINE)
    status = cli.main(["calibrate", str(tmp_path / "none.csv"), "--map",
                       str(tmp_path / "none.toml"), "-o", str(DEFAULT_MACHINE)])
    line = one_error_line(capsys.readouterr().err)
    assert status == 2 and "default.toml" in line and "--overwrite-shipped" in line
    assert sha(DEFAULT_MACHINE) == before
    assert not list(DEFAULT_MACHINE.parent.glob("default.calibration*"))


def test_build_with_other_segments_refuses_to_replace_the_committed_fmu_at_once(tmp_path,
                                                                               capsys):
    before = sha(DEFAULT_FMU)
    started = time.process_time()
    (tmp_path / "models").mkdir()  # no source: code without the check fails, writes nothing
    status = cli.main(["build", "--segments", "3", "--models", str(tmp_path / "models"),
                       "--out", str(DEFAULT_FMU)])
    line = one_error_line(capsys.readouterr().err)
    assert status == 2 and "SpindleBench.fmu" in line and "--overwrite-shipped" in line
    assert time.process_time() - started < 5  # refused before the minutes of building
    assert sha(DEFAULT_FMU) == before


def test_every_command_has_the_overwrite_flag():
    parser = cli.build_parser()
    for name, sub in parser.commands.items():
        assert any("--overwrite-shipped" in a.option_strings for a in sub._actions), name


def test_compensate_refuses_a_sweeps_folder_and_leaves_its_readme(tmp_path, capsys):
    sweep = tmp_path / "sweep"
    sweep.mkdir()
    (sweep / "state.json").write_text("{}\n", encoding="utf-8")
    (sweep / "README.md").write_text("the sweep's\n", encoding="utf-8")
    status = cli.main(["compensate", str(TINY_COMPENSATE), "-o", str(sweep)])
    line = one_error_line(capsys.readouterr().err)
    assert status == 2 and "state.json" in line
    assert (sweep / "README.md").read_text(encoding="utf-8") == "the sweep's\n"
    assert not (sweep / ".lock").exists()


def test_compensate_holds_the_folder_lock(tmp_path, capsys):
    out = tmp_path / "comp"
    holder = ResultStore(out)
    holder.lock()
    child = subprocess.run([sys.executable, "-m", "spindlebench", "compensate",
                            str(TINY_COMPENSATE), "-o", str(out)], capture_output=True,
                           text=True, timeout=300)
    holder.unlock()
    assert child.returncode == 2
    assert "in use by process" in one_error_line(child.stderr)
    assert not (out / "README.md").exists()


def test_compensate_writes_its_completion_markers_last():
    from spindlebench.studies.compensation import compensation_report as command

    assert set(command.COMPLETE_MARKERS) <= command.OUTPUT_FILES


@pytest.mark.slow
def test_compensate_twice_gives_the_same_bytes_and_reuses_its_own_folder(tmp_path):
    first, second = tmp_path / "one", tmp_path / "two"
    for out in (first, second, second):  # the third: a rerun into its own folder
        assert cli.main(["compensate", str(TINY_COMPENSATE), "-o", str(out), "--days",
                         "cold-starts"]) == 0
        time.sleep(1.1)  # a gzip header with a time would differ now
    for name in ("timeseries.csv.gz", "days.csv", "summary.csv"):
        assert (first / name).read_bytes() == (second / name).read_bytes(), name
    raw = (first / "timeseries.csv.gz").read_bytes()
    assert raw[4:8] == bytes(4)  # gzip MTIME field
    assert raw[3] & 0x08 == 0  # no FNAME field (a temporary file's random name)
    assert b"residual_um" in gzip.decompress(raw).split(b"\n", 1)[0]


# --------------------------------------------------------------------------- hangs


def descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (from /proc: no dependency for a test)."""
    parents: dict[int, int] = {}
    for stat_file in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat_file.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        parents[int(stat_file.parent.name)] = int(fields[1])
    found, frontier = [], [pid]
    while frontier:
        children = [c for c, p in parents.items() if p in frontier]
        found += children
        frontier = children
    return found


def workers_of(pid: int) -> list[int]:
    """The pool's worker processes: the grandchildren (children of the forkserver)."""
    children = [c for c in descendants(pid)
                if int(Path(f"/proc/{c}/stat").read_text().rsplit(")", 1)[1].split()[1]) != pid]
    return sorted(children)


def nap(seconds: float) -> int:
    """A task for the worker tests: sleep, return the worker's pid."""
    time.sleep(seconds)
    return os.getpid()


@pytest.mark.slow
@pytest.mark.parametrize("which", [0, 1])
def test_a_killed_local_worker_is_noticed_and_its_task_retried(which):
    from spindlebench.studies.running.executor import Task, TaskRunner

    killed: list[int] = []

    def on_outcome(outcome):
        if not killed:
            victims = workers_of(os.getpid())
            assert len(victims) >= 2, victims
            killed.append(victims[which])
            os.kill(victims[which], signal.SIGKILL)  # as the out-of-memory killer would

    runner = TaskRunner(workers=2, progress=False)
    tasks = [Task(f"nap {i}", nap, (1.0,)) for i in range(6)]
    outcomes = []
    stats = runner.run(tasks, lambda o: (outcomes.append(o), on_outcome(o))[1])
    assert killed
    assert stats.total() == 6 and sum(stats.done.values()) == 6, [o.error for o in outcomes]
    assert sorted(o.task.key for o in outcomes) == sorted(t.key for t in tasks)


def die_mid_send() -> None:
    """A worker killed halfway through sending its result (as the out-of-memory killer can
    catch one sending a recording): a message header for 1 MB, 100 bytes of it, then
    SIGKILL. The pool's manager thread then waits for the rest for ever."""
    import gc
    import multiprocessing.queues
    import struct

    results = next(o for o in gc.get_objects()
                   if isinstance(o, multiprocessing.queues.SimpleQueue))
    os.write(results._writer.fileno(), struct.pack("!i", 1 << 20) + b"\x80" * 100)
    os.kill(os.getpid(), signal.SIGKILL)


HALF_SENT = """
import sys
sys.path[:0] = [{tests!r}, {root!r}]
from test_faults import die_mid_send, nap
from spindlebench.studies.running.executor import Task, TaskRunner
if __name__ == "__main__":
    tasks = [Task("n0", nap, (0.5,)), Task("half", die_mid_send),
             *[Task(f"n{{i}}", nap, (0.2,)) for i in range(1, 5)]]
    failed = []
    stats = TaskRunner(workers=2, progress=False).run(
        tasks, lambda o: failed.append(o.task.key) if o.error else None)
    print("done", sum(stats.done.values()), failed)
"""


@pytest.mark.slow
def test_a_worker_killed_while_sending_its_result_does_not_hang_the_run(tmp_path):
    """The sweep that hung in 3 of 9 tries: the pool never noticed (its manager waited for
    the rest of the message), Ctrl-C then waited on its shutdown. Now the dead worker is
    seen, the manager unblocked, the task reported, the others done."""
    script = tmp_path / "half.py"
    here = Path(__file__).resolve()
    script.write_text(HALF_SENT.format(tests=str(here.parent), root=str(here.parents[1])),
                      encoding="utf-8")
    child = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                           timeout=240)
    assert child.returncode == 0, child.stderr
    assert "done 5 ['half']" in child.stdout, child.stdout + child.stderr


def quick_sweep_child(out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "spindlebench", "sweep",
                             str(REPO / "scenarios" / "studies" / "tiny_sweep.toml"), "-o",
                             str(out), "--workers", "2", "--no-progress", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_first_recording(child: subprocess.Popen, out: Path) -> None:
    deadline = time.monotonic() + 300
    while not list(out.glob("runs/*/*.csv")):
        assert child.poll() is None and time.monotonic() < deadline, child.communicate()
        time.sleep(0.02)


@pytest.mark.slow
def test_a_sweep_with_a_killed_worker_finishes_every_run(tmp_path):
    out = tmp_path / "sweep"
    child = quick_sweep_child(out)
    wait_first_recording(child, out)
    os.kill(workers_of(child.pid)[0], signal.SIGKILL)
    _, stderr = child.communicate(timeout=300)
    assert child.returncode == 0, stderr
    assert (out / "README.md").is_file()
    assert not list(out.rglob("*.error.json"))  # the killed worker's run was retried


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_after_a_killed_worker_still_ends_the_sweep(tmp_path, signum):
    out = tmp_path / "sweep"
    child = quick_sweep_child(out)
    wait_first_recording(child, out)
    os.kill(workers_of(child.pid)[0], signal.SIGKILL)
    time.sleep(0.3)
    if child.poll() is None:
        child.send_signal(signum)
    _, stderr = child.communicate(timeout=60)
    assert child.returncode in (0, 130), stderr
    assert not list(out.rglob("*.part"))


# --------------------------------------------------------------------------- silent wrong results


@pytest.fixture
def soak_cache(tmp_path, monkeypatch):
    from spindlebench.testbench import soak

    folder = tmp_path / "soak-cache"
    monkeypatch.setenv(soak.CACHE_ENV, str(folder))
    monkeypatch.setattr(soak, "_memory", {})
    return folder


def test_a_tampered_or_renamed_soak_cache_is_named_and_recomputed(tmp_path, soak_cache,
                                                                  monkeypatch):
    import json

    from conftest import QUICK
    from spindlebench.testbench import soak
    from spindlebench.testbench.scenario import load_scenario

    path = tmp_path / "s.toml"
    path.write_text(QUICK + '\n[initial]\nkind = "soak"\ndays = 1\n', encoding="utf-8")
    scenario = load_scenario(path)
    states = soak.soak_state(scenario, DEFAULT_FMU)
    (file,) = soak_cache.glob("*.json")
    record = json.loads(file.read_text(encoding="utf-8"))
    assert record["states_sha256"] == soak.states_sha256(states)
    name = next(iter(record["states_K"]))
    record["states_K"][name] = 250.0  # -23 °C, a plausible kelvin number, in an 18 °C room
    file.write_text(json.dumps(record), encoding="utf-8")
    monkeypatch.setattr(soak, "_memory", {})
    with pytest.warns(soak.StaleCacheWarning, match="checksum"):
        again = soak.soak_state(scenario, DEFAULT_FMU)
    assert again == states
    # a valid file of other inputs copied under this key's name is not these inputs' soak
    other = json.loads(file.read_text(encoding="utf-8"))
    other["soak_key"] = "0" * 64
    file.write_text(json.dumps(other), encoding="utf-8")
    monkeypatch.setattr(soak, "_memory", {})
    with pytest.warns(soak.StaleCacheWarning, match="other inputs"):
        assert soak.soak_state(scenario, DEFAULT_FMU) == states


def test_speeds_that_differ_get_their_own_experiment_ids(tmp_path):
    from spindlebench.studies.family.experiments import experiments, speed_label
    from spindlebench.studies.family.family_file import load_study

    assert speed_label(2000.0) == "2000" and speed_label(1500.5) == "1500.5"
    assert speed_label(2000.0001) == "2000.0001"
    text = (REPO / "scenarios" / "studies" / "tiny_sweep.toml").read_text(encoding="utf-8")
    path = tmp_path / "study.toml"
    path.write_text(text.replace("speeds_rpm = [2000, 4000]",
                                 "speeds_rpm = [2000, 2000.0001, 4000]"), encoding="utf-8")
    ids = [e.id for e in experiments(load_study(path))]
    assert len(set(ids)) == len(ids) == 6, ids


def test_an_ambient_csv_with_a_bom_is_read_like_a_recording(tmp_path):
    from conftest import QUICK
    from spindlebench.testbench.scenario import load_scenario

    (tmp_path / "air.csv").write_bytes(b"\xef\xbb\xbftime_s,ambient_C\n0,18\n300,18.5\n600,19\n")
    path = tmp_path / "s.toml"
    path.write_text(QUICK.replace('kind = "constant"\ntemperature_C = 18.0',
                                  'kind = "csv"\nfile = "air.csv"'), encoding="utf-8")
    assert list(load_scenario(path).ambient.values_C) == [18.0, 18.5, 19.0]


# --------------------------------------------------------------------------- security

PASSWORD_FILE = ("root:x:0:0:root:/root:/bin/bash\n"
                 "daemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n"
                 "secretuser:x:1000:1000:Secret Person,,,:/home/secret:/bin/bash\n")


@pytest.mark.parametrize("argv", [
    ["evaluate", "--train", "{f}", "--test", "{f}", "--target", "drift_um", "--clusters", "2"],
    ["fingerprint", "{f}"],
    ["fingerprint", "{f}", "--target", "drift_um"],
    ["fingerprint", "{f}", "--sensors", "T1", "--target", "drift_um"],
    ["plot", "{f}", "-o", "x.png"],
    ["plot", "{f}", "-o", "x.png", "--time-column", "t"],
])
def test_an_error_never_echoes_a_files_first_line(tmp_path, monkeypatch, capsys, argv):
    monkeypatch.chdir(tmp_path)
    secret = tmp_path / "recording.csv"
    secret.write_text(PASSWORD_FILE, encoding="utf-8")
    assert cli.main([a.replace("{f}", str(secret)) for a in argv]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert "recording.csv" in line
    for leaked in ("x:0:0", "/bin/bash", "nologin", "Secret Person"):
        assert leaked not in line, line


def test_a_close_column_name_is_still_suggested(tmp_path, capsys):
    rec = tmp_path / "r.csv"
    rec.write_text("time_s,drift_um,T1,T2\n0,0,20,20\n60,1,21,21.5\n120,2,22,23\n",
                   encoding="utf-8")
    assert cli.main(["fingerprint", str(rec), "--target", "drift_mu"]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert "closest: 'drift_um'" in line and "4 column(s)" in line


def serve_once(reply: bytes | None) -> tuple[str, threading.Thread]:
    """A TCP server on a free local port that sends ``reply`` (None: nothing) to one client."""
    import socket

    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def answer():
        with server:
            conn, _ = server.accept()
            with conn:
                if reply is not None:
                    conn.sendall(reply)
                time.sleep(3)

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    return f"tcp://127.0.0.1:{port}", thread


@pytest.mark.parametrize(("reply", "expected"), [
    (b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n", "not a Dask scheduler"),
    (None, "no Dask handshake within 1 s"),
    ((40).to_bytes(8, "little") + b"x" * 40, "not a Dask handshake"),
])
def test_a_dask_address_that_is_not_a_scheduler_is_one_line(reply, expected):
    from spindlebench.studies.running.executor import Task, TaskRunner

    address, _ = serve_once(reply)
    runner = TaskRunner(dask_address=address, progress=False, connect_timeout_s=1)
    with pytest.raises(SpindlebenchError, match=expected):
        runner.run([Task("nap", nap, (0.0,))])


def test_a_real_dask_scheduler_passes_the_handshake_check():
    distributed = pytest.importorskip("distributed")
    from spindlebench.studies.running.executor import check_dask_scheduler

    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as c:
        check_dask_scheduler(c.scheduler_address, 5.0)


# --------------------------------------------------------------------------- misleading


def test_a_target_name_near_the_limit_gets_a_short_part_name(tmp_path):
    from spindlebench.core.atomic import atomic_path, remove_stale_parts_in, write_text

    target = tmp_path / ("r" * 240 + ".json")  # 245 characters: the file system takes 255
    write_text(target, "{}\n")
    assert target.read_text(encoding="utf-8") == "{}\n"
    with atomic_path(target) as tmp:
        assert len(tmp.name) < 160
        stale = tmp.with_name(tmp.name.replace(f".{os.getpid()}.", ".999999999.", 1))
        stale.write_text("left by a killed writer", encoding="utf-8")
    assert remove_stale_parts_in(tmp_path) == [stale]


def test_evaluate_writes_a_json_with_a_245_character_name(tmp_path, capsys):
    from selection_data import synthetic_experiment

    train, test = tmp_path / "train.csv", tmp_path / "test.csv"
    synthetic_experiment(0).to_csv(train, index=False)
    synthetic_experiment(1).to_csv(test, index=False)
    out = tmp_path / ("e" * 240 + ".json")
    assert cli.main(["evaluate", "--train", str(train), "--test", str(test), "--target",
                     "drift_um", "--clusters", "2", "--json", str(out)]) == 0
    assert out.is_file()


@pytest.mark.slow
@pytest.mark.parametrize("pause_s", [0.0, 0.3, 0.8])
def test_sigterm_then_sigint_a_millisecond_later_leaves_no_part_file(tmp_path, pause_s):
    out = tmp_path / "sweep"
    child = quick_sweep_child(out)
    wait_first_recording(child, out)
    time.sleep(pause_s)
    child.send_signal(signal.SIGTERM)
    time.sleep(0.001)
    child.send_signal(signal.SIGINT)
    _, stderr = child.communicate(timeout=120)
    assert child.returncode == 130, stderr
    # both may be pending when Python looks (it runs SIGINT's handler first): either name
    assert re.fullmatch(r"error: interrupted by SIG(TERM|INT); the unfinished output was not "
                        r"written", one_error_line(stderr))
    assert not list(out.rglob("*.part"))


def test_a_second_signal_while_unwinding_is_recorded_and_a_third_raises():
    from spindlebench.core import interrupts

    interrupts.install()
    try:
        with pytest.raises(interrupts.Interrupted):
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(1)
            finally:  # unwinding: one more signal must not cut this block short
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)
                cleaned = True
        assert cleaned
        with pytest.raises(interrupts.Interrupted):
            try:
                raise interrupts.Interrupted(signal.SIGTERM)
            finally:
                interrupts._pending.clear()
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)
                os.kill(os.getpid(), signal.SIGINT)  # the third: the user insists
                time.sleep(0.05)
                pytest.fail("the third signal did not raise")
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        interrupts._pending.clear()


class _SignalsInItsDestructor:
    """Sends a signal to this process from ``__del__`` (as FMPy's ``CVodeSolver.__del__``,
    run by the garbage collector, was running when a sweep's Ctrl-C arrived)."""

    def __init__(self, signum: int) -> None:
        self.signum = signum

    def __del__(self) -> None:
        os.kill(os.getpid(), self.signum)
        self.sent = True  # a bytecode after the signal: its handler runs here, in __del__


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_landing_in_a_destructor_is_not_swallowed(signum):
    """Python prints an exception raised in ``__del__`` as "Exception ignored" and goes on:
    the sweep lost its Ctrl-C and ended with status 0. It is delivered again and raises in
    the code that runs next."""
    from spindlebench.core import interrupts

    hook = sys.unraisablehook
    interrupts.install()
    try:
        with pytest.raises(interrupts.Interrupted) as raised:
            victim = _SignalsInItsDestructor(signum)
            del victim
            deadline = time.monotonic() + 30  # a safety net: it raises within milliseconds
            while time.monotonic() < deadline:  # ordinary code after the destructor
                time.sleep(0.01)
        assert raised.value.signum == signum
    finally:
        sys.unraisablehook = hook
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        interrupts._pending.clear()


def test_a_test_recording_with_its_columns_reordered_is_evaluated_the_same(tmp_path, capsys):
    import json

    from selection_data import synthetic_experiment

    train, test, shuffled = (tmp_path / n for n in ("train.csv", "test.csv", "shuffled.csv"))
    synthetic_experiment(0).to_csv(train, index=False)
    frame = synthetic_experiment(1)
    frame.to_csv(test, index=False)
    frame[list(reversed(frame.columns))].to_csv(shuffled, index=False)
    results = []
    for held_out in (test, shuffled):
        out = tmp_path / f"{held_out.stem}.json"
        assert cli.main(["evaluate", "--train", str(train), "--test", str(held_out),
                         "--target", "drift_um", "--clusters", "2", "--json", str(out)]) == 0
        record = json.loads(out.read_text(encoding="utf-8"))
        record.pop("provenance")
        results.append(json.dumps(record, sort_keys=True).replace("shuffled", "test"))
    assert '"rmse_um"' in results[0] and results[0] == results[1]


@pytest.mark.parametrize("make", ["file", "fifo", "under a file"])
def test_demo_refuses_a_bad_out_before_building_the_fmu(tmp_path, monkeypatch, capsys, make):
    from spindlebench.commands import demo

    def no_build(argv):
        raise AssertionError(f"a stage ran: {argv}")

    monkeypatch.setattr(demo, "_step", no_build)
    target = tmp_path / "out"
    if make == "fifo":
        os.mkfifo(target)
    else:
        target.write_text("a file\n", encoding="utf-8")
    out = target / "sub" if make == "under a file" else target
    assert cli.main(["demo", "--out", str(out)]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert "--out" in line and ("a FIFO" if make == "fifo" else "a file") in line


CALIBRATION_MAP = """[inputs]
spindle_speed_rpm = "spindle_speed_rpm"
feed_x_mm_per_min = 0.0
feed_y_mm_per_min = 0.0
ambient_C = "{ambient}"
[error]
column = "drift_um"
[temperatures]
T1 = "T1"
T6 = "T6"
"""


@pytest.mark.slow
@pytest.mark.parametrize(("edit", "ambient", "expected"), [
    ("kelvin", "ambient_K", "ambient_C from column 'ambient_K' is 291.15 °C"),
    ("constant error", "unknown", "error column 'drift_um' is constant"),
])
def test_calibrate_says_what_is_wrong_instead_of_did_not_converge(tmp_path, capsys, edit,
                                                                   ambient, expected):
    from selection_data import synthetic_experiment

    frame = synthetic_experiment(0)
    frame["ambient_K"] = 291.15
    if edit == "constant error":
        frame["drift_um"] = 3.0
    rec = tmp_path / "rec.csv"
    frame.to_csv(rec, index=False)
    mapping = tmp_path / "map.toml"
    mapping.write_text(CALIBRATION_MAP.format(ambient=ambient), encoding="utf-8")
    assert cli.main(["calibrate", str(rec), "--map", str(mapping), "-o",
                     str(tmp_path / "m.toml")]) == 2
    line = one_error_line(capsys.readouterr().err)
    assert expected in line and "rec.csv" in line and "converge" not in line
    assert not (tmp_path / "m.toml").exists()


def test_a_signal_right_after_the_part_file_is_made_leaves_no_part_file(tmp_path, monkeypatch):
    """Ctrl-C between making the part file (then ``mkstemp``) and the ``try`` that removes
    it left ``.manifest.json.<pid>.<random>.part`` in a study folder; and, with the file
    made open, its handle open in the process (a notebook's or a library user's, which
    goes on after the Ctrl-C)."""
    from spindlebench.core import atomic, interrupts

    def open_handles():
        return {fd: os.readlink(f"/proc/self/fd/{fd}") for fd in os.listdir("/proc/self/fd")
                if os.path.exists(f"/proc/self/fd/{fd}")}

    before = open_handles()

    made = atomic._create

    def create_then_signal(*args, **kwargs):
        created = made(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGINT)  # lands at the next bytecode, here
        return created

    monkeypatch.setattr(atomic, "_create", create_then_signal)
    interrupts.install()
    try:
        with pytest.raises(KeyboardInterrupt):
            atomic.write_text(tmp_path / "manifest.json", "{}\n")
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        interrupts._pending.clear()
    assert list(tmp_path.iterdir()) == []
    left = {fd: name for fd, name in open_handles().items() if fd not in before}
    assert not [name for name in left.values() if ".part" in name], left  # "... (deleted)"
