"""Units a person reads (issue #42): tables and reports show mm or µm, kPa and N with the
unit in the header; the files stay SI."""

from __future__ import annotations

import pandas as pd
import pytest

from pneumact.io.display import display_frame, display_unit, display_value
from pneumact.validation.metrics import metrics_for_reading


@pytest.mark.parametrize(("si", "values", "shown", "factor"), [
    ("m", [3.1e-6, 9e-6], "µm", 1e6),  # a residual of micrometres
    ("m", [2e-3, 3e-6], "mm", 1e3),  # a column with millimetres stays in mm
    ("Pa", [1780.0], "kPa", 1e-3),
    ("Pa*m", [29.8], "kPa*mm", 1.0),  # a loop area
    ("Pa^2*s", [2.8e8], "kPa^2*s", 1e-6),  # a pressure command's effort
    ("N", [2.6], "N", 1.0),
    ("N*s/m", [214.0], "N*s/m", 1.0),  # parameters stay as the sets write them
])
def test_display_unit(si, values, shown, factor):
    assert display_unit(si, values) == (shown, pytest.approx(factor))


def test_display_value_is_written_for_a_person():
    assert display_value(2.036e-5, "m") == (pytest.approx(20.36), "µm")
    assert display_value(2.816e8, "Pa^2*s") == (pytest.approx(281.6), "kPa²·s")


def test_a_long_table_shows_each_row_in_its_unit_and_headers_carry_theirs():
    loops = pd.DataFrame({"measure": ["loop_width_pressure", "loop_area"],
                          "unit": ["Pa", "Pa*m"], "measured": [1780.0, 29.8],
                          "model": [1800.0, 30.1], "relative": [0.011, 0.01]})
    shown = display_frame(loops)
    assert shown["unit"].tolist() == ["kPa", "kPa·mm"]
    assert shown["measured"].tolist() == pytest.approx([1.78, 29.8])
    assert shown["relative"].tolist() == [0.011, 0.01]  # a ratio is not converted
    assert loops["measured"].iloc[0] == 1780.0  # the table itself stays SI
    frame = pd.DataFrame({"time [s]": [0.0, 1.0], "position [m]": [0.004, 0.008]})
    assert list(display_frame(frame).columns) == ["time [s]", "position [mm]"]


def test_validation_metrics_read_per_signal_with_units_in_the_headers():
    metrics = pd.DataFrame({"record": ["a", "a"], "signal": ["position", "pressure"],
                            "rms": [3.122e-6, 250.0], "max": [9e-6, 900.0],
                            "nrmse": [0.001, 0.01], "fit_percent": [99.9, 99.0],
                            "r2": [1.0, 1.0], "n": [100, 100]})
    tables = metrics_for_reading(metrics)
    assert list(tables) == ["position", "pressure"]
    assert "rms [µm]" in tables["position"] and "fit [%]" in tables["position"]
    assert tables["position"]["rms [µm]"].iloc[0] == pytest.approx(3.122)
    assert tables["pressure"]["max [kPa]"].iloc[0] == pytest.approx(0.9)
