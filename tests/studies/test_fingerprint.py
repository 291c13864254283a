"""``spindlebench fingerprint``: the issue-9 statistics on a hand-made recording whose values
were worked out by hand (below), the command's JSON, figure, reference cache and one-line
errors, and the real CAIVIAC runs."""

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import QUICK as QUICK_BASE
from spindlebench.commands import main as cli
from spindlebench.core.paths import DEFAULT_FMU
from spindlebench.studies.fingerprint.reference import KEY_FILE, cached_reference
from spindlebench.studies.fingerprint.statistics import KEYS, fingerprint

# The hand-made recording: 11 samples, one a minute.
#   T1 (fast) rises 0, 5, 8, then stays at 10        (offset 20 °C)
#   T2 (slow) rises 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5  (offset 18 °C)
#   T3 is constant (zero-variance rise: left out)
#   T4 rises 0.06 K in its last two samples only (< 0.1 K: no t63 of its own)
#   the error rise e = dT1 - dT2 = 0, 5, 7, 9, 8, 8, 7, 7, 6, 6, 5  (offset 100 µm)
TIME_S = [60.0 * i for i in range(11)]
T1 = [0, 5, 8, 10, 10, 10, 10, 10, 10, 10, 10]
T2 = [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5]
T4 = [0] * 9 + [0.06, 0.06]
E = [a - b for a, b in zip(T1, T2, strict=True)]

# By hand (n = 11, sums over the samples):
#   best_raw_psi: T1 wins. Σe = 68, ΣT1 = 93, ΣT1·e = 641, ΣT1² = 889, Σe² = 478:
#     Sxy = 641 - 93·68/11 = 727/11, Sxx = 889 - 93²/11 = 1130/11, Syy = 478 - 68²/11 = 634/11
#     r = 727 / sqrt(1130 · 634) = 727 / sqrt(716420) = 0.85892
#   (T2: ΣT2 = 25, ΣT2² = 85, ΣT2·e = 163 -> r = 93 / sqrt(310 · 634) = 0.2098; T4: r = -0.14)
#   best_single_r2 = 727² / 716420 = 528529 / 716420
#   best_diff_psi = best_pair_r2 = 1: e is dT1 - dT2 exactly.
#   smooth: w = max(3, 11 // 50) = 3, each sample averages itself and its two neighbours:
#     smooth(e) = 2.5, 4, 7, 8, 25/3, 23/3, 22/3, 20/3, 19/3, 17/3, 5.5; final = last 1 = 5.5
#   overshoot = (25/3) / 5.5 = 50/33; early_fraction = smooth(e)[floor(0.1·10) = 1] / 5.5 = 8/11
#   t63(e): smooth - 2.5 >= 0.632 · 3 = 1.896 first at sample 2 (7) -> 120 s
#   t63(T1): smooth = 2.5, 13/3, 23/3, ...; final 10; >= 2.5 + 0.632 · 7.5 = 7.24 at sample 2
#     -> 120 s; t63(T2): smooth = 0, 1/3, 2/3, 4/3, 5/3, 7/3, 8/3, 10/3, ...; final 4.5;
#     >= 2.844 first at sample 7 -> 420 s; T4 (rise 0.06 K) does not count
#   t63_ratio = 120 / median(120, 420) = 120 / 270 = 4/9  (with T4's 540 s it would be 120/420)
BY_HAND = {
    "best_raw_psi": 727 / math.sqrt(716420),
    "best_single_r2": 528529 / 716420,
    "best_diff_psi": 1.0,
    "best_pair_r2": 1.0,
    "t63_ratio": 4 / 9,
    "t63_fastest_ratio": 1.0,  # 120 / min(120, 420)
    "overshoot": 50 / 33,
    "early_fraction": 8 / 11,
}


def hand_made(path: Path, time_column: str = "time_s", target: str = "drift_um") -> Path:
    frame = pd.DataFrame({
        time_column: TIME_S,
        "T1": np.add(T1, 20.0), "T2": np.add(T2, 18.0), "T3": 21.5, "T4": np.add(T4, 19.0),
        target: np.add(E, 100.0), "spindle_speed_rpm": 4000.0,
    })
    frame.to_csv(path, index=False)
    return path


def reference_folder(tmp_path: Path) -> Path:
    """Stands in for the default machine's paper experiments (simulating them takes ~40 s)."""
    folder = tmp_path / "reference"
    folder.mkdir()
    hand_made(folder / "exp1.csv")
    return folder


def test_statistics_of_the_hand_made_recording():
    temps = np.column_stack([np.add(T1, 20.0), np.add(T2, 18.0), np.full(11, 21.5),
                             np.add(T4, 19.0)])
    stats = fingerprint(np.array(TIME_S), temps, np.add(E, 100.0))
    assert list(stats) == list(KEYS)
    for key, value in BY_HAND.items():
        assert stats[key] == pytest.approx(value, rel=1e-9), key


def test_t63_ratio_counts_from_the_first_sample():
    """A clock that starts at 10 h gives the same ratio (120 s / 270 s), not 36120 / 36270."""
    temps = np.column_stack([T1, T2])
    later = fingerprint(np.add(TIME_S, 36000.0), temps, np.array(E, dtype=float))
    assert later["t63_ratio"] == pytest.approx(4 / 9)


def test_pair_statistics_agree_with_brute_force_least_squares():
    """best_diff_psi and best_pair_r2 against np.corrcoef and a design-matrix lstsq."""
    rng = np.random.default_rng(3)
    t = np.arange(200.0)
    temps = np.cumsum(rng.normal(size=(200, 5)), axis=0)
    error = temps[:, 0] - 0.7 * temps[:, 3] + rng.normal(scale=2.0, size=200)
    stats = fingerprint(t, temps, error)
    rises, e = temps - temps[0], error - error[0]
    diff, pair = 0.0, 0.0
    for i in range(5):
        for j in range(i + 1, 5):
            diff = max(diff, abs(np.corrcoef(rises[:, i] - rises[:, j], e)[0, 1]))
            design = np.column_stack([np.ones(200), rises[:, i], rises[:, j]])
            residual = e - design @ np.linalg.lstsq(design, e, rcond=None)[0]
            pair = max(pair, 1 - residual @ residual / ((e - e.mean()) @ (e - e.mean())))
    raw = max(abs(np.corrcoef(rises[:, j], e)[0, 1]) for j in range(5))
    assert stats["best_raw_psi"] == pytest.approx(raw)
    assert stats["best_diff_psi"] == pytest.approx(diff)
    assert stats["best_pair_r2"] == pytest.approx(pair)


def test_command_prints_rows_and_median_and_writes_json(tmp_path, capsys):
    a = hand_made(tmp_path / "a.csv")
    b = tmp_path / "b.csv"  # the same recording with the error halved and a longer tail
    frame = pd.read_csv(a)
    frame["drift_um"] = 100.0 + 0.5 * np.array(E)
    frame.to_csv(b, index=False)
    out = tmp_path / "fp.json"
    figure = tmp_path / "figure.png"
    reference = reference_folder(tmp_path)
    assert cli.main(["fingerprint", str(a), str(b), "--json", str(out), "--figure", str(figure),
                     "--reference", str(reference)]) == 0
    printed = capsys.readouterr().out
    assert "median" in printed and str(a) in printed
    assert f"reference {reference} (median)" in printed
    record = json.loads(out.read_text(encoding="utf-8"))
    first = record["recordings"][0]
    assert first["sensors"] == ["T1", "T2", "T3", "T4"] and first["target"] == "drift_um"
    for key, value in BY_HAND.items():
        assert first[key] == pytest.approx(value, rel=1e-9)
        # scaling the error changes no statistic: both rows and the median agree
        assert record["median"][key] == pytest.approx(value, rel=1e-9)
    assert record["provenance"]["command"] == "fingerprint"
    assert [entry["path"] for entry in record["provenance"]["recordings"]] == [str(a), str(b)]
    assert record["provenance"]["reference"]["kind"] == "folder"
    assert record["reference"]["label"] == f"reference {reference}"
    assert figure.read_bytes()[:4] == b"\x89PNG" and record["figure"] == str(figure)


def test_time_column_target_and_sensors_flags(tmp_path, capsys):
    path = hand_made(tmp_path / "r.csv", time_column="t_min", target="z_um")
    out = tmp_path / "r.json"
    assert cli.main(["fingerprint", str(path), "--time-column", "t_min", "--target", "z_um",
                     "--sensors", "T1,T2", "--json", str(out), "--figure",
                     str(tmp_path / "r.png"), "--reference", str(reference_folder(tmp_path))]) == 0
    row = json.loads(out.read_text(encoding="utf-8"))["recordings"][0]
    assert row["sensors"] == ["T1", "T2"]
    assert row["t63_ratio"] == pytest.approx(4 / 9)  # T4 left out by --sensors changes nothing
    assert row["best_raw_psi"] == pytest.approx(BY_HAND["best_raw_psi"])


def test_target_from_the_sidecar(tmp_path, capsys):
    path = hand_made(tmp_path / "run.csv", target="ch3_um")
    (tmp_path / "run.json").write_text(json.dumps({"axial_target": "ch3_um"}), encoding="utf-8")
    assert cli.main(["fingerprint", str(path)]) == 0
    line = [row for row in capsys.readouterr().out.splitlines() if row.startswith(str(path))]
    assert f"{BY_HAND['overshoot']:.3f}" in line[0]


@pytest.mark.parametrize(("args", "message"), [
    (["missing.csv"], "file not found"),
    (["{r}", "--target", "nope_um"], "target column 'nope_um' not found"),
    (["{r}", "--sensors", "T1", "T9"], "sensor column(s) not found: T9"),
    (["{r}", "--time-column", "t_min"], "--time-column 't_min' not found"),
    (["{r}", "--time-column", "T2"], "line 3: the time column does not increase"),
    (["{r}", "--sensors", "T1", "drift_um"], "the target 'drift_um' is also listed"),
    (["{r}", "--sensors", "T1", "T2", "E2"], "follows the target 'drift_um' with |r| = 1.0000"),
    (["{notime}"], "no time column 'time_s'; the fingerprint (t63 is a time) needs one"),
    (["{semi}", "--delimiter", ","], "read as one column"),
    (["{r}", "--sensors", "T3"], "no temperature column rises"),
    (["{r}", "--json", "{d}/x.txt"], "must be a .json file"),
    (["{r}", "--reference", "{d}/nowhere"], "--reference"),
    (["{d}/empty"], "folder holds no .csv recording"),
    (["{plain}"], "no --target given"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, message):
    recording = hand_made(tmp_path / "r.csv")
    (tmp_path / "empty").mkdir()
    plain = tmp_path / "plain.csv"
    pd.read_csv(recording).rename(columns={"drift_um": "z_um"}).to_csv(plain, index=False)
    frame = pd.read_csv(recording)
    frame.assign(E2=2 * frame["drift_um"]).to_csv(recording, index=False)  # a target copy
    frame.drop(columns="time_s").to_csv(tmp_path / "notime.csv", index=False)
    frame.to_csv(tmp_path / "semi.csv", index=False, sep=";", decimal=",")
    argv = [arg.format(r=recording, d=tmp_path, plain=plain, notime=tmp_path / "notime.csv",
                       semi=tmp_path / "semi.csv") for arg in args]
    before = sorted(tmp_path.iterdir())
    assert cli.main(["fingerprint", *argv, "--json", str(tmp_path / "o.json")]
                    if "--json" not in argv else ["fingerprint", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and message in err
    assert sorted(tmp_path.iterdir()) == before


#: conftest's quick scenario at 15 minutes, 1 s steps and 4000 rpm (a reference run).
QUICK = QUICK_BASE.replace("duration_s = 600", "duration_s = 900").replace(
    "step_s = 10.0", "step_s = 1.0").replace("rpm = 3000", "rpm = 4000")


def test_reference_is_simulated_once_and_redone_when_a_scenario_changes(tmp_path):
    scenarios = tmp_path / "scenarios"
    scenarios.mkdir()
    (scenarios / "exp1.toml").write_text(QUICK, encoding="utf-8")
    cache = tmp_path / "cache"
    said: list[str] = []
    first = cached_reference(cache, DEFAULT_FMU, scenarios, tmp_path / "none", said.append)
    assert len(said) == 1 and [p.name for p in first.recordings] == ["exp1.csv"]
    assert json.loads((cache / KEY_FILE).read_text())["fmu"]["sha256"] == first.source["fmu"][
        "sha256"]
    data = first.recordings[0].read_bytes()
    cached_reference(cache, DEFAULT_FMU, scenarios, tmp_path / "none", said.append)
    assert len(said) == 1  # reused
    (scenarios / "exp1.toml").write_text(QUICK.replace("rpm = 4000", "rpm = 2000"))
    again = cached_reference(cache, DEFAULT_FMU, scenarios, tmp_path / "none", said.append)
    assert len(said) == 2 and again.recordings[0].read_bytes() != data


def test_runs_on_the_caiviac_runs(tmp_path, capsys):
    from spindlebench.adapters import caiviac

    source = caiviac.default_source()
    assert source.is_file(), f"the real recording is expected at {source}"
    runs = tmp_path / "caiviac"
    assert cli.main(["adapt", "caiviac", "--out", str(runs)]) == 0
    out = tmp_path / "caiviac.json"
    files = sorted(str(path) for path in runs.glob("*.csv"))
    reference = reference_folder(tmp_path)
    assert cli.main(["fingerprint", str(runs), "--json", str(out), "--reference",
                     str(reference)]) == 0  # a folder is its recordings
    assert (tmp_path / "caiviac.png").is_file()
    record = json.loads(out.read_text(encoding="utf-8"))
    assert [row["recording"] for row in record["recordings"]] == files
    assert [row["target"] for row in record["recordings"]] == ["ch3_um"] * len(files)
    assert all(len(row["sensors"]) == 16 for row in record["recordings"])
    median = record["median"]
    # the real machine: one sensor nearly follows the axial error, a difference a bit better
    assert 0.9 < median["best_raw_psi"] < median["best_diff_psi"] <= 1.0
    assert median["overshoot"] > 1.0 and 0.0 < median["early_fraction"] < 0.3


def test_reference_key_changes_with_the_testbench_code(monkeypatch):
    from spindlebench.core.provenance import source_sha256
    from spindlebench.studies.fingerprint import reference

    before = reference.inputs_key()
    assert before["code_sha256"] == source_sha256(*reference.REFERENCE_CODE)
    monkeypatch.setattr(reference, "REFERENCE_CODE", reference.REFERENCE_CODE[:-1])
    assert reference.inputs_key()["code_sha256"] != before["code_sha256"]


def test_a_named_machine_gets_its_own_reference(tmp_path):
    scenarios = tmp_path / "scenarios"
    scenarios.mkdir()
    (scenarios / "exp1.toml").write_text(QUICK, encoding="utf-8")
    said: list[str] = []
    default = cached_reference(tmp_path / "cache", DEFAULT_FMU, scenarios, tmp_path / "none",
                               said.append)
    other = cached_reference(tmp_path / "cache", DEFAULT_FMU, scenarios, tmp_path / "none",
                             said.append, machine="ambient-following")
    assert other.recordings[0].parent == tmp_path / "cache" / "ambient-following"
    assert "ambient-following machine" in said[1]
    assert other.source["machine"]["name"] == "ambient-following"
    assert other.recordings[0].read_bytes() != default.recordings[0].read_bytes()


def test_machine_and_reference_exclude_each_other(tmp_path, capsys):
    recording = hand_made(tmp_path / "r.csv")
    assert cli.main(["fingerprint", str(recording), "--machine", "default", "--reference",
                     str(reference_folder(tmp_path))]) == 2
    assert "--machine and --reference" in capsys.readouterr().err
