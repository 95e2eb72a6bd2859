"""Validation against records: API, train/test, CLI, report, bad input."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import pneumact as pa
import reference as ref
from pneumact.cli import app
from pneumact.errors import DataError
from pneumact.identification import Noise, paper_campaign, synthetic_campaign
from pneumact.validation import train_test, validate

runner = CliRunner()
EXIT_USER_ERROR = 2


@pytest.fixture(scope="module")
def sweep(vgt):
    tests = paper_campaign(vgt, speeds=(), sweep_period=30.0)[:1]
    return synthetic_campaign(vgt, tests, noise=Noise(0.0, 0.0, 0.0))[0]


def test_the_model_validates_perfectly_on_its_own_noise_free_record(vgt, sweep):
    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    validation = validate(model, sweep, signals=("position", "pressure"))
    metrics = validation.metrics()
    assert (metrics["fit_percent"] > ref.PERFECT_FIT_PERCENT).all()
    loops = validation.loops()
    assert np.all(np.abs(loops["relative"]) < 1e-3)
    frame = validation.to_pandas()
    assert set(frame.columns) == {"record", "time", "signal", "measured", "model", "residual"}
    np.testing.assert_allclose(frame["residual"], frame["measured"] - frame["model"])


def test_a_wrong_friction_shows_in_the_metrics_and_loop_widths(vgt, sweep):
    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    validation = validate(model, sweep, values={"Fc": 1.5 * vgt["Fc"]})
    loops = validation.loops().set_index("measure")
    assert loops.loc["loop_width_pressure", "difference"] > 0  # more friction, wider loop
    assert validation.metrics()["fit_percent"].iloc[0] < ref.PERFECT_FIT_PERCENT


def test_train_test_puts_both_sets_side_by_side(vgt, sweep, tmp_path):
    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    tests = [t for t in paper_campaign(vgt, speeds=(1e-3,)) if t.kind == "ramp"]
    ramps = synthetic_campaign(vgt, tests, seed=1)
    result = train_test(model, ramps, [sweep], ["Fc"], start={"Fc": 2.0})
    assert result.fit.values["Fc"] == pytest.approx(vgt["Fc"], rel=0.02)
    table = result.metrics()
    assert set(table["set"]) == {"training", "test"}
    assert result.summary().shape[0] == 1
    written = result.write(tmp_path / "tt")
    assert (tmp_path / "tt" / "report.html") in written


def test_cli_validate_writes_a_report_and_refuses_bad_records(vgt, sweep, tmp_path,
                                                              monkeypatch):
    monkeypatch.chdir(tmp_path)
    sweep.save(tmp_path / "sweep.csv")
    result = runner.invoke(app, ["validate", "sweep.csv", "--signals", "position,pressure",
                                 "--out", "val"])
    assert result.exit_code == 0, result.output
    html = (tmp_path / "val" / "report.html").read_text(encoding="utf-8")
    assert "data:image/png;base64," in html and "pneumact validate" in html
    metrics = pd.read_csv(tmp_path / "val" / "metrics.csv")
    assert set(metrics["signal"]) == {"position", "pressure"}
    pd.DataFrame({"time [s]": [0.0, 1.0], "pressure [kPa]": [100.0, 90.0]}).to_csv(
        tmp_path / "nopos.csv", index=False)
    result = runner.invoke(app, ["validate", "nopos.csv", "--valve", "source", "--input", "model",
                                 "--out", "bad"])
    assert result.exit_code == EXIT_USER_ERROR
    assert "position" in result.output
    assert not (tmp_path / "bad").exists()
    result = runner.invoke(app, ["validate", "sweep.csv", "--free", "Fc", "--out", "bad"])
    assert result.exit_code == EXIT_USER_ERROR and "--train" in result.output
    assert not (tmp_path / "bad").exists()


def test_validate_needs_records(vgt):
    with pytest.raises(DataError, match="at least one record"):
        validate(pa.Actuator(vgt), [])


@pytest.fixture(scope="module")
def presliding(vgt):
    tests = [t for t in paper_campaign(vgt) if t.kind == "presliding"]
    return synthetic_campaign(vgt, tests, seed=3)[0]


def test_a_model_that_fits_the_time_series_but_misses_the_loop_is_inadequate(vgt, sweep):
    """Issue #19: Fc 46 % low still scores a high fit %, but the loop is half as wide."""
    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    validation = validate(model, sweep, signals=("position", "pressure"),
                          values={"Fc": (1 - ref.MISSED_LOOP_FC_ERROR) * vgt["Fc"]})
    metrics = validation.metrics()
    assert (metrics["fit_percent"] > ref.MISSED_LOOP_FIT_PERCENT).all()  # fit % is fooled
    assert (metrics["verdict"] == "inadequate").all()
    verdict = validation.verdicts().iloc[0]
    assert "loop width in pressure" in verdict["reasons"]
    assert verdict["loop_width_pressure_error"] > validation.criteria.loop_width
    right = validate(model, sweep, signals=("position", "pressure")).verdicts()
    assert right["verdict"].iloc[0] != "inadequate", right["reasons"].iloc[0]


def test_each_record_drives_the_valve_it_was_made_with(vgt, sweep, presliding):
    from pneumact.validation import drive_for

    model = pa.Actuator(vgt, valve=pa.PressureRegulator())
    validation = validate(model, [sweep, presliding])
    table = validation.verdicts().set_index("record")
    assert table.loc[sweep.source, "input"] == "setpoint"
    assert table.loc[sweep.source, "valve"] == "PressureRegulator"
    assert table.loc[presliding.source, "input"] == "pressure"
    assert table.loc[presliding.source, "valve"] == "PressureSource"
    assert drive_for(model, sweep)[0] is model  # the model's own valve when it fits
    with pytest.raises(DataError, match=r"lacks; it carries pressure, so it can drive "
                                        r"PressureSource \(--valve source\)"):
        validate(model, presliding, input="model")
    with pytest.raises(DataError, match="input = 'command'"):
        validate(model, presliding, input="command")


def test_cli_validate_drives_each_record_its_own_way_and_flags_verdicts(
        vgt, sweep, presliding, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for record in (sweep, presliding):
        record.save(tmp_path / "bench" / f"{record.source}.csv",
                    units={"pressure": "kPa", "position": "mm", "setpoint": "kPa"})
    result = runner.invoke(app, ["validate", "bench", "--out", "val"])
    assert result.exit_code == 0, result.output
    assert "driven by its pressure, PressureSource" in result.output
    assert "driven by its setpoint, PressureRegulator" in result.output
    metrics = pd.read_csv(tmp_path / "val" / "metrics.csv")
    assert "verdict" in metrics.columns
    result = runner.invoke(app, ["validate", "bench", "--valve", "regulator", "--input", "model",
                                 "--out", "bad"])
    assert result.exit_code == EXIT_USER_ERROR
    assert "--valve source" in result.output
    assert not (tmp_path / "bad").exists()
    wrong = pa.write_params(vgt.replace(Fc=(1 - ref.MISSED_LOOP_FC_ERROR) * vgt["Fc"]),
                            tmp_path / "wrong.toml")
    result = runner.invoke(app, ["validate", "bench/sweep.csv", "--params", str(wrong),
                                 "--out", "wrong"])
    assert result.exit_code == 0, result.output
    assert "inadequate" in result.output
    html = (tmp_path / "wrong" / "report.html").read_text(encoding="utf-8")
    assert "the model is inadequate for this record" in html
