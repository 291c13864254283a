"""The Modelica package: accepted by two independent front ends; errors point at file:line."""

from pathlib import Path

import pytest
from conftest import MODELS
from spindlebench.core.errors import SpindlebenchError
from spindlebench.model import MODEL_FILE
from spindlebench.model.equations import flat_name
from spindlebench.model.frontend import model_source, translate, validate


def broken_copy(tmp_path: Path, old: str, new: str) -> Path:
    text = (MODELS / MODEL_FILE).read_text()
    assert old in text
    (tmp_path / MODEL_FILE).write_text(text.replace(old, new, 1))
    return tmp_path


def line_of(path: Path, fragment: str) -> int:
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if fragment in line:
            return number
    raise AssertionError(fragment)


def test_rumoca_accepts_the_package():
    assert validate(MODELS / MODEL_FILE) == []


def test_rumoca_reports_a_syntax_error_with_its_line(tmp_path):
    folder = broken_copy(
        tmp_path, 'Real T(unit = "K") "Port temperature";', 'Real T(unit = "K") "Port temperature"'
    )
    problems = validate(folder / MODEL_FILE)
    assert problems
    assert problems[0].startswith(
        f"{folder / MODEL_FILE}:{line_of(folder / MODEL_FILE, 'flow Real Q_flow')}:"
    )


def test_pymoca_translates_the_machine_with_the_requested_segments():
    translated = translate(MODELS, segments=3)
    shapes = {flat_name(v.symbol.name(), assemblies=translated.assemblies): v.symbol.shape
              for v in translated.model.states}
    for part in ("spindle_shaft", "housing", "column", "bed", "table"):
        assert shapes[f"{part}_T"] == (3, 1)
    assert translated.assemblies == {"spindle_unit", "headstock", "column_unit", "bed_and_table",
                                     "test_setup", "z_drive", "x_drive", "y_drive"}
    assert translated.symbols["drift_um"].unit == "um"
    assert translated.symbols["h_nat"].description


def test_syntax_error_is_one_line_with_file_and_line(tmp_path):
    folder = broken_copy(tmp_path, "T1_C = sensor_T1.T - 273.15;", "T1_C = sensor_T1.T - 273.15 +;")
    with pytest.raises(SpindlebenchError) as info:
        translate(folder, segments=3)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(
        f"{folder / MODEL_FILE}:{line_of(folder / MODEL_FILE, 'T1_C = sensor_T1.T')}:"
    )
    assert "syntax error" in message


def test_unknown_name_is_located(tmp_path):
    folder = broken_copy(tmp_path, "Q_flow = G * dT;", "Q_flow = G * dTT;")
    with pytest.raises(SpindlebenchError) as info:
        translate(folder, segments=3)
    expected = f"{folder / MODEL_FILE}:{line_of(folder / MODEL_FILE, 'G * dTT')}:"
    assert str(info.value).startswith(expected)
    assert "dTT" in str(info.value)


def test_missing_model_file_is_named(tmp_path):
    with pytest.raises(SpindlebenchError, match=str(tmp_path / MODEL_FILE)):
        translate(tmp_path, segments=3)


@pytest.mark.parametrize("segments", [1, 0, 2.5, True])
def test_segments_must_be_an_integer_of_at_least_two(segments):
    with pytest.raises(SpindlebenchError, match="segments"):
        translate(MODELS, segments=segments)


def test_missing_equation_is_reported_with_the_file(tmp_path):
    from spindlebench.model.equations import explicit_ode

    folder = broken_copy(tmp_path, "    T2_C = sensor_T2.T - 273.15;\n", "")
    with pytest.raises(SpindlebenchError, match=r"not balanced.*no equation for: T2_C"):
        explicit_ode(folder, segments=2)


def test_non_utf8_model_file_is_one_line_with_file_and_line(tmp_path):
    """rumoca and pymoca both gave a traceback ('stream did not contain valid UTF-8')."""
    text = (MODELS / MODEL_FILE).read_text(encoding="utf-8")
    (tmp_path / MODEL_FILE).write_bytes(text.encode("utf-8")
                                        + b"\n// caf\xe9\n")
    line = text.count("\n") + 2
    with pytest.raises(SpindlebenchError) as info:
        translate(tmp_path, segments=3)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{tmp_path / MODEL_FILE}:{line}: Modelica source is not UTF-8")
    with pytest.raises(SpindlebenchError, match="is not UTF-8"):
        model_source(tmp_path)


@pytest.mark.parametrize("segments", [51, 100_000])
def test_segments_have_an_upper_bound(segments):
    with pytest.raises(SpindlebenchError, match="from 2 to 50"):
        translate(MODELS, segments=segments)
