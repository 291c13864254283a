"""``spindlebench paper``: the whole comparison on generated recordings and on the real runs."""

import json

import numpy as np
import pandas as pd
import pytest
from scipy.cluster.hierarchy import fcluster
from spindlebench.adapters import caiviac
from spindlebench.commands import main as cli
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import GROUPS, PAPER_SIX
from spindlebench.formats.recording import read_recording
from spindlebench.selection import evaluate, linkage_from_similarity
from spindlebench.studies.paper import config as study_config
from spindlebench.studies.paper import reference
from spindlebench.studies.paper.analysis import choose_six, run_study
from spindlebench.studies.paper.figures import cut_height

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
FIGURES = [
    "fig3_error_curves.png", "fig4_six_temperatures.png", "fig6_rmse_bars.png",
    "dendrogram_all_raw.png", "dendrogram_six_raw.png", "dendrogram_six_diff.png",
]


def _experiment(seed: int, speed: float, ambient_start: float, ambient_slope: float):
    """A warm-up with the paper's column names; the drift depends on T1-T10 and T13-T16."""
    rng = np.random.default_rng(seed)
    t = np.arange(150) * 60.0
    ambient = ambient_start + ambient_slope * t / t[-1]
    columns = {"time_s": t}
    gains = np.linspace(0.2, 3.0, 20) * speed / 4000
    taus = np.linspace(900, 6000, 20)
    for i in range(20):
        heat = gains[i] * 8 * (1 - np.exp(-t / taus[i]))
        columns[f"T{i + 1}"] = ambient + heat + rng.normal(0, 0.02, t.size)
    columns["T10"] = ambient + rng.normal(0, 0.02, t.size)  # the ambient sensor
    drift = 8.0 * (columns["T1"] - columns["T10"]) - 2.0 * (columns["T13"] - columns["T16"])
    drift += rng.normal(0, 0.1, t.size)
    columns["drift_um"] = drift - drift[0]
    return pd.DataFrame(columns)


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("synthetic")
    setups = [(4000, 5.3, 5.1), (2000, 7.3, 3.8), (4000, 9.6, 3.0), (4000, 20.5, 3.2),
              (2000, 23.6, 3.9)]  # the paper's speeds and ambient ranges
    for number, (speed, start, slope) in enumerate(setups, start=1):
        _experiment(number, speed, start, slope).to_csv(folder / f"exp{number}.csv", index=False)
    out = folder / "study"
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(out)]) == 0
    return folder, out


def test_defaults_write_every_table_and_figure(generated):
    _folder, out = generated
    for name in [*FIGURES, "fig5_measured_vs_predicted.png"]:
        assert (out / name).read_bytes()[:8] == PNG_SIGNATURE, name
    table4 = pd.read_csv(out / "table4_selected.csv")
    assert len(table4) == 3 * (2 + 3 + 4)
    assert table4.groupby(["clusters", "group"]).size().to_dict() == {
        (k, g): k for k in (2, 3, 4) for g in GROUPS
    }
    table5 = pd.read_csv(out / "table5_r2.csv")
    assert table5.shape == (3, 7)
    assert ((table5[list(GROUPS)] > 0.9) & (table5[list(GROUPS)] <= 1)).all().all()
    table6 = pd.read_csv(out / "table6_rmse.csv")
    assert list(table6.columns) == [
        "clusters", "group", "exp2", "exp3", "exp4", "exp5", "mean",
        "paper_exp2", "paper_exp3", "paper_exp4", "paper_exp5", "paper_mean",
    ]
    assert len(table6) == 9
    tests = table6[["exp2", "exp3", "exp4", "exp5"]]
    np.testing.assert_allclose(table6["mean"], tests.mean(axis=1), rtol=1e-5)
    provenance = json.loads((out / "provenance.json").read_text())
    assert provenance["study"]["six"] == ["T1", "T6", "T8", "T10", "T13", "T16"]
    assert set(provenance["inputs"]) == {f"exp{i}" for i in range(1, 6)}
    assert "package_versions" in provenance


def test_differences_recover_the_generating_terms(generated):
    _, out = generated
    table4 = pd.read_csv(out / "table4_selected.csv")
    diff = table4[table4["group"] == "six_diff"]
    # T1-T10, the main generating term, is kept at every k
    assert all("T1-T10" in set(chosen) for _, chosen in diff.groupby("clusters")["selected"])
    table6 = pd.read_csv(out / "table6_rmse.csv").set_index(["clusters", "group"])
    mean = table6["mean"]
    assert mean[(2, "six_diff")] < 1.0
    assert mean[(2, "six_diff")] < min(mean[(2, "all_raw")], mean[(2, "six_raw")])


def test_table6_matches_evaluate_called_directly(generated):
    folder, out = generated
    table6 = pd.read_csv(out / "table6_rmse.csv").set_index(["clusters", "group"])
    direct = evaluate(
        folder / "exp1.csv",
        {f"exp{i}": folder / f"exp{i}.csv" for i in range(2, 6)},
        target="drift_um",
        sensors=list(PAPER_SIX),
        k=3,
        differences=True,
    )
    for name, value in direct.rmse_um.items():
        assert table6.loc[(3, "six_diff"), name] == pytest.approx(value, rel=1e-5)
    results = json.loads((out / "results.json").read_text())
    cell = next(c for c in results["cells"] if c["group"] == "six_diff" and c["k"] == 3)
    assert cell["selected"] == direct.selected
    assert cell["coefficients"] == pytest.approx(direct.coefficients)


def test_paper_numbers_appear_beside_ours(generated):
    _, out = generated
    readme = (out / "README.md").read_text()
    table6 = pd.read_csv(out / "table6_rmse.csv").set_index(["clusters", "group"])
    for k, groups in reference.RMSE_UM.items():
        for group, numbers in groups.items():
            row = table6.loc[(k, group)]
            assert tuple(row[[f"paper_exp{i}" for i in range(2, 6)] + ["paper_mean"]]) == numbers
    assert "| 2 | six + differences |" in readme
    assert "**3.6**" in readme and "**11.1**" in readme and "**10.3**" in readme
    assert "T1-T10 (ψ=0.9961)" in readme
    assert "0.9943" in (out / "table5.md").read_text()


def test_paper_reference_means_match_its_rows():
    """Transcription check: each printed mean is the mean of its four RMSE values."""
    for groups in reference.RMSE_UM.values():
        for *values, mean in groups.values():
            assert abs(np.mean(values) - mean) <= 0.051


def test_dendrogram_cut_line_gives_the_cells_clusters(generated):
    folder, _ = generated
    config = study_config.load(None, {"clusters": "2,3,4"})
    result = run_study(folder, config)
    for group in GROUPS:
        names, closure = result.closure(group)
        tree = linkage_from_similarity(closure)
        for k in config.clusters:
            cell = result.cell(group, k)
            labels = fcluster(tree, cut_height(tree[:, 2], cell.eta), criterion="distance")
            found = {frozenset(n for n, lab in zip(names, labels, strict=True) if lab == label)
                     for label in set(labels)}
            assert found == {frozenset(c) for c in cell.clusters}


@pytest.fixture(scope="module")
def caiviac_runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("caiviac")
    caiviac.write_runs(folder, phase="heating")
    return folder


def test_real_runs_comparison(caiviac_runs, tmp_path, capsys):
    config_path = caiviac_runs / caiviac.STUDY_FILE
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(caiviac_runs), "--config", str(config_path),
                     "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    config = study_config.load(config_path)
    assert config.train == "run4_5000rpm" and config.target == "ch3_um"
    table6 = pd.read_csv(out / "table6_rmse.csv")
    assert list(table6.columns[2:7]) == list(config.tests)
    assert len(table6) == 9
    # the six come from the stated rule, applied to the training run
    six = choose_six(read_recording(caiviac_runs / "run4_5000rpm.csv"), config.sensors_all,
                     "abs-pearson")
    assert f"six = {', '.join(six)}" in printed
    table4 = pd.read_csv(out / "table4_selected.csv")
    raw_six = table4[table4["group"] == "six_raw"]["selected"]
    assert set(raw_six) <= set(six)
    # our Table 6 is evaluate()'s numbers
    direct = evaluate(
        caiviac_runs / "run4_5000rpm.csv",
        {name: caiviac_runs / f"{name}.csv" for name in config.tests},
        target="ch3_um", sensors=list(config.sensors_all), k=2,
    )
    row = table6[(table6["clusters"] == 2) & (table6["group"] == "all_raw")].iloc[0]
    for name, value in direct.rmse_um.items():
        assert row[name] == pytest.approx(value, rel=1e-5)
    for name in FIGURES:
        assert (out / name).read_bytes()[:8] == PNG_SIGNATURE


def test_bad_configuration_is_one_line(tmp_path, generated):
    folder, _ = generated
    bad = tmp_path / "bad.toml"
    bad.write_text('target = "drift_um"\nsix_sensors = ["T1"]\n')
    with pytest.raises(SpindlebenchError, match=r"bad.toml: key 'six_sensors': unknown key"):
        study_config.load(bad)
    bad.write_text("clusters = [2, 3\n")
    with pytest.raises(SpindlebenchError, match=r"bad\.toml: not valid TOML"):
        study_config.load(bad)
    bad.write_bytes("# Grüße\nclusters = [2, 3]\n".encode("latin-1"))
    with pytest.raises(SpindlebenchError, match=r"bad\.toml: not valid TOML: not UTF-8"):
        study_config.load(bad)
    with pytest.raises(SpindlebenchError, match="key 'six': T99 not among sensors_all"):
        study_config.load(None, {"six": "T1,T99"})
    with pytest.raises(SpindlebenchError, match="also the training run"):
        study_config.load(None, {"tests": "exp1,exp2"})
    with pytest.raises(SpindlebenchError, match="key 'clusters': expected integers"):
        study_config.load(None, {"clusters": "2,x"})
    config = study_config.load(None, {"tests": "exp2,exp9"})
    with pytest.raises(SpindlebenchError, match=r"exp9.csv: experiment 'exp9' not found"):
        run_study(folder, config)
    config = study_config.load(None, {"target": "no_such_um"})
    with pytest.raises(SpindlebenchError, match=r"missing column.*no_such_um"):
        run_study(folder, config)
    config = study_config.load(None, {"six": "T1,T2", "clusters": "2,4"})
    with pytest.raises(SpindlebenchError,
                       match=r"group six_raw, k = 4: recording .*exp1\.csv: cannot make 4"):
        run_study(folder, config)
    assert cli.main(["paper", "--recordings", str(tmp_path / "nowhere")]) == 2


def test_rerun_into_the_same_folder_removes_only_its_own_stale_files(generated, tmp_path):
    folder, _out = generated
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(out)]) == 0
    (out / "my_notes.txt").write_text("keep me")
    # an output an earlier version of the study wrote (fig5 was once one file per test run)
    provenance = json.loads((out / "provenance.json").read_text())
    provenance["outputs"].append("fig5_measured_vs_predicted_exp2.png")
    (out / "provenance.json").write_text(json.dumps(provenance))
    (out / "fig5_measured_vs_predicted_exp2.png").write_bytes(b"stale")
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(out),
                     "--tests", "exp3,exp4"]) == 0
    names = {path.name for path in out.iterdir()}
    assert "fig5_measured_vs_predicted.png" in names
    assert "fig5_measured_vs_predicted_exp2.png" not in names  # the first run's, now stale
    assert "my_notes.txt" in names  # not the study's: never touched
    listed = set(json.loads((out / "provenance.json").read_text())["outputs"])
    assert names - {"my_notes.txt", "provenance.json"} == listed


def test_a_sidecar_of_another_csv_is_one_warning_line_and_not_embedded(generated, tmp_path,
                                                                       capsys):
    folder, _out = generated
    recordings = tmp_path / "recordings"
    recordings.mkdir()
    for path in folder.glob("exp*.csv"):
        (recordings / path.name).write_bytes(path.read_bytes())
    (recordings / "exp1.json").write_text(json.dumps({"seed": 1, "recording_sha256": "0" * 64}))
    (recordings / "exp2.json").write_text(json.dumps({"seed": 2}))  # older sidecar: trusted
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(recordings), "--out", str(out)]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "exp1.json" in line]
    assert len(warned) == 1 and warned[0].startswith("warning: ")
    assert "not the CSV's" in warned[0]
    inputs = json.loads((out / "provenance.json").read_text())["inputs"]
    assert "not embedded" in inputs["exp1"]["sidecar"]  # a note, not the wrong provenance
    assert inputs["exp2"]["sidecar"] == {"seed": 2}


def test_table6_shows_the_papers_numbers_only_for_the_experiments_we_predict(generated,
                                                                             tmp_path):
    """--tests exp3 exp4: the paper's exp3/exp4 beside ours and their mean, labelled as such;
    not its exp2/exp5 nor its printed 4-run mean."""
    folder, _ = generated
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(out),
                     "--tests", "exp3,exp4", "--clusters", "2"]) == 0
    table6 = pd.read_csv(out / "table6_rmse.csv").set_index(["clusters", "group"])
    assert list(table6.columns) == ["exp3", "exp4", "mean", "paper_exp3", "paper_exp4",
                                    "paper_mean_over_exp3_exp4"]
    _, exp3, exp4, _, _ = reference.RMSE_UM[2]["six_raw"]
    assert table6.loc[(2, "six_raw"), "paper_mean_over_exp3_exp4"] == pytest.approx(
        (exp3 + exp4) / 2)
    markdown = (out / "table6.md").read_text()
    assert "| paper exp3 | paper exp4 | **paper mean over exp3, exp4** |" in markdown
    assert "paper exp2" not in markdown and "**10.3**" not in markdown  # its 4-run mean
    assert "**6.7**" in markdown  # (10.6 + 2.7) / 2 = 6.65
    assert "for the experiments predicted here too (exp3, exp4)" in markdown
    assert "paper mean over exp3, exp4" in (out / "README.md").read_text()


def test_table6_without_a_common_experiment_shows_no_paper_numbers(caiviac_runs, tmp_path):
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(caiviac_runs), "--out", str(out),
                     "--config", str(caiviac_runs / caiviac.STUDY_FILE), "--clusters", "2"]) == 0
    table6 = pd.read_csv(out / "table6_rmse.csv")
    assert not [c for c in table6.columns if c.startswith("paper")]
    markdown = (out / "table6.md").read_text()
    assert "paper" not in markdown.splitlines()[0]
    assert "is not shown: none of the experiments predicted here (run1_1250rpm" in markdown


def test_table6_of_another_training_experiment_shows_no_paper_numbers(generated, tmp_path):
    folder, _ = generated
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(out), "--train", "exp2",
                     "--tests", "exp1,exp3", "--clusters", "2"]) == 0
    assert not [c for c in pd.read_csv(out / "table6_rmse.csv").columns if c.startswith("paper")]
    assert "this study trains on exp2" in (out / "table6.md").read_text()


def test_folder_study_file_is_used_without_config_and_named_in_errors(caiviac_runs, tmp_path,
                                                                      capsys):
    """The adapter's paper_study.toml is used when --config is not given (said on stderr and
    recorded in the command line); an experiment not found lists the folder's and points to
    the file."""
    own = caiviac_runs / caiviac.STUDY_FILE
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(caiviac_runs), "--out", str(out),
                     "--clusters", "2"]) == 0
    err = capsys.readouterr().err
    assert f"using {own} (the folder's own study file" in err
    provenance = json.loads((out / "provenance.json").read_text())
    assert f"--config {own}" in provenance["command"]
    assert provenance["study"]["train"] == "run4_5000rpm"
    with pytest.raises(SpindlebenchError) as info:
        run_study(caiviac_runs, study_config.load(None))
    message = str(info.value)
    assert "experiment 'exp1' not found (the folder has: run1_1250rpm, run2_2500rpm" in message
    assert message.endswith(f"describes this folder: pass --config {own}")


def test_list_flags_space_or_comma_separated_and_unused_columns_ignored(generated, tmp_path):
    """--tests/--clusters/--six take either separator; a gap in a column the study does not
    read (not the target, sensors_all or time_s) does not stop it."""
    folder, _ = generated
    recordings = tmp_path / "recordings"
    recordings.mkdir()
    for path in folder.glob("exp*.csv"):
        frame = pd.read_csv(path)
        frame["ch2_um"] = np.where(frame.index == 3, np.nan, 0.0)  # an unused channel
        frame.to_csv(recordings / path.name, index=False)
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(recordings), "--out", str(out),
                     "--tests", "exp3", "exp4", "--clusters", "2", "3",
                     "--six", "T1,T6,T8", "T10", "T13", "T16"]) == 0
    provenance = json.loads((out / "provenance.json").read_text())
    assert provenance["study"]["tests"] == ["exp3", "exp4"]
    assert provenance["study"]["clusters"] == [2, 3]
    assert provenance["study"]["six"] == list(PAPER_SIX)
    assert "--tests exp3,exp4 --six T1,T6,T8,T10,T13,T16 --clusters 2,3" in provenance["command"]


def test_figures_label_the_quantity_and_keep_legends_off_the_data(generated, monkeypatch):
    """Fig. 3/5 say 'thermal error (µm)' (the column in the title); legends sit right of the
    axes (inside they hid curves and branches); the dendrogram legend says each line is the
    cut for k, with its η."""
    from spindlebench.studies.paper import figures

    folder, _ = generated
    drawn = {}

    def keep(figure, path):
        figure.canvas.draw()
        drawn[path.name] = figure
        return path

    monkeypatch.setattr(figures, "_save", keep)
    result = run_study(folder, study_config.load(None, {"clusters": "2,3"}))
    figures.write_all(result, folder / "unused")
    for name in ("fig3_error_curves.png", "fig4_six_temperatures.png",
                 "fig5_measured_vs_predicted.png", "dendrogram_six_diff.png"):
        legends = [(ax, ax.get_legend()) for ax in drawn[name].axes if ax.get_legend()]
        assert legends, name
        for ax, legend in legends:
            assert legend.get_window_extent().x0 >= ax.get_window_extent().x1, name
    fig3 = drawn["fig3_error_curves.png"].axes[0]
    assert fig3.get_ylabel() == "thermal error (µm)" and "drift_um" in fig3.get_title()
    fig5 = drawn["fig5_measured_vs_predicted.png"].axes
    assert len(fig5) == len(result.config.tests) * 2  # every predicted run × k = 2, 3
    assert [ax.get_ylabel() for ax in fig5[::2]] == [
        f"{name}\nthermal error (µm)" for name in result.config.tests]
    fig4 = drawn["fig4_six_temperatures.png"].axes[0]
    assert fig4.get_ylabel() == "rise since the start (K)"
    assert all(line.get_ydata()[0] == 0 for line in fig4.lines)
    dendrogram = drawn["dendrogram_six_diff.png"].axes[0]
    assert dendrogram.get_ylabel() == "merge height 1 − t(R)"
    eta = result.cell("six_diff", 2).eta
    labels = [text.get_text() for text in dendrogram.get_legend().get_texts()]
    assert labels[0] == f"cut for k = 2\n(η = {eta:.4f})"


def test_paper_tables_4_and_5_only_beside_a_study_that_trains_like_the_paper(generated, tmp_path):
    folder, out = generated  # the default study trains on exp1, like the paper
    assert "paper_selected" in pd.read_csv(out / "table4_selected.csv").columns
    assert "paper_all_raw" in pd.read_csv(out / "table5_r2.csv").columns
    other = tmp_path / "other"
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(other),
                     "--train", "exp2", "--tests", "exp1,exp3"]) == 0
    assert not any(c.startswith("paper_")
                   for c in pd.read_csv(other / "table4_selected.csv").columns)
    assert not any(c.startswith("paper_") for c in pd.read_csv(other / "table5_r2.csv").columns)
    for number in (4, 5):
        text = (other / f"table{number}.md").read_text()
        assert "(paper)" not in text
        assert f"The paper's Table {number} (trained on its exp1) is not shown" in text


def test_a_folder_not_written_by_paper_is_refused_before_anything_is_written(generated,
                                                                              tmp_path, capsys):
    folder, _out = generated
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "README.md").write_text("someone else's")
    status = cli.main(["paper", "--recordings", str(folder), "--out", str(foreign)])
    err = capsys.readouterr().err
    assert status == 2
    assert err.count("\n") == 1 and "is not a paper-study folder" in err
    assert [p.name for p in foreign.iterdir()] == ["README.md"]
    assert (foreign / "README.md").read_text() == "someone else's"
    # a provenance.json of another command (a sweep's) does not make it a paper-study folder
    (foreign / "provenance.json").write_text('{"outputs": ["README.md"], "study": {}}')
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(foreign)]) == 2
    assert (foreign / "README.md").read_text() == "someone else's"


def test_a_folder_in_the_way_of_an_output_leaves_every_old_file_in_place(generated, tmp_path,
                                                                          capsys):
    folder, _out = generated
    out = tmp_path / "study"
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "table6.md").unlink()
    (out / "table6.md").mkdir()
    capsys.readouterr()
    status = cli.main(["paper", "--recordings", str(folder), "--out", str(out),
                       "--tests", "exp3,exp4"])
    err = capsys.readouterr().err
    assert status == 2
    assert err.count("\n") == 1 and "table6.md: is a folder" in err
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert after == {name: data for name, data in before.items() if name != "table6.md"}
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no staging left


@pytest.mark.parametrize(("toml", "match"), [
    ("clusters = [2, 2]", r"bad\.toml: key 'clusters': k = 2 is listed twice"),
    ('clusters = "2,,3"', r"bad\.toml: key 'clusters': empty item in '2,,3'"),
    ('tests = "exp2,,exp3"', r"bad\.toml: key 'tests': empty item"),
    ('train = "../good/exp1"', r"bad\.toml: key 'train': '\.\./good/exp1' is not an experiment"),
    ('tests = ["exp2", "sub/exp3"]', r"bad\.toml: key 'tests': 'sub/exp3' is not an experiment"),
    ('tests = ["exp2", ".."]', r"bad\.toml: key 'tests': '\.\.' is not an experiment name"),
    ('target = "time_s"', r"bad\.toml: key 'target': time_s is the time axis"),
    ('target = "T3"', r"bad\.toml: key 'target': 'T3' is also in sensors_all"),
    ('sensors_all = ["T1", "T2", "time_s"]\nsix = "auto"', r"key 'sensors_all': time_s is the"),
])
def test_config_values_that_were_accepted_silently_are_one_line_errors(tmp_path, toml, match):
    bad = tmp_path / "bad.toml"
    bad.write_text(toml + "\n")
    with pytest.raises(SpindlebenchError, match=match):
        study_config.load(bad)


def test_list_flags_with_an_empty_item_are_refused(generated, tmp_path, capsys):
    folder, _ = generated
    out = tmp_path / "study"
    status = cli.main(["paper", "--recordings", str(folder), "--out", str(out),
                       "--clusters", "2,,3"])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1
    assert "--clusters: empty item in '2,,3'" in err
    assert not out.exists()
    # a comma at the end of a word is a separator, as in evaluate --sensors
    assert cli.main(["paper", "--recordings", str(folder), "--out", str(out),
                     "--tests", "exp2,", "exp3", "--clusters", "2"]) == 0
    assert json.loads((out / "provenance.json").read_text())["study"]["tests"] == ["exp2", "exp3"]


def test_methods_compared_table(generated, tmp_path):
    """``methods`` in the config: every label on every group and k, the paper's from its own
    cells, the others equal to ``evaluate`` with that method; a table per group in the README."""
    folder, _ = generated
    config_path = tmp_path / "methods.toml"
    config_path.write_text('tests = ["exp2", "exp3"]\nclusters = [2]\n'
                           'methods = ["closure", "kmeans+grey", "greedy+ridge"]\nseed = 3\n')
    out = tmp_path / "out"
    assert cli.main(["paper", "--recordings", str(folder), "--config", str(config_path),
                     "--out", str(out)]) == 0
    table = pd.read_csv(out / "methods_rmse.csv")
    assert list(dict.fromkeys(table["method"])) == ["closure", "kmeans+grey", "greedy+ridge"]
    assert len(table) == 3 * len(GROUPS)
    paper = pd.read_csv(out / "table6_rmse.csv")
    closure = table[table["method"] == "closure"]
    assert set(closure["group"]) == set(GROUPS)
    assert np.all(np.isfinite(table["mean_rmse_um"]))
    at = table[(table["method"] == "kmeans+grey") & (table["group"] == "six_diff")].iloc[0]
    direct = evaluate(folder / "exp1.csv", [folder / "exp2.csv", folder / "exp3.csv"],
                      "drift_um", sensors=list(PAPER_SIX), k=2, differences=True,
                      method="kmeans", within="grey", seed=3)
    assert at["mean_rmse_um"] == pytest.approx(direct.mean_rmse_um, rel=1e-5)
    assert at["selected"] == ";".join(direct.selected)
    assert at["worst_um"] == pytest.approx(max(direct.rmse_um.values()), rel=1e-5)
    readme = (out / "README.md").read_text()
    assert "## Methods compared" in readme and "| k | closure | kmeans+grey | greedy+ridge |" \
        in readme
    assert len(paper) > 0
    for bad, message in (('methods = ["knn"]', "key 'methods': unknown method 'knn'"),
                         ('methods = ["lasso+grey"]', "has no clusters"),
                         ('methods = ["closure", "closure+psi"]', "listed twice"),
                         ('seed = -1', "key 'seed'")):
        config_path.write_text(bad + "\n")
        with pytest.raises(SpindlebenchError, match=message):
            study_config.load(config_path)
