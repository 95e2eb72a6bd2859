"""``pneumact control step|profile|hunting``: files, metrics and user mistakes, and the
command line against the API (the same loop gives the same numbers)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import pneumact as pa
import reference as ref
from pneumact.cli import app
from pneumact.control import canudas_hunting, loop_metrics

runner = CliRunner()
FILES = ("signals.csv", "metrics.csv", "loop.png", "report.html")


def invoke(*args: str):
    result = runner.invoke(app, list(args))
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


def _metric(folder, name) -> float:
    frame = pd.read_csv(folder / "metrics.csv")
    return float(frame.set_index("metric").loc[name, "value"])


def test_hunting_command_writes_everything_and_agrees_with_the_api(tmp_path, canudas):
    out = tmp_path / "hunt"
    result = invoke("control", "hunting", "--t-end", "60", "--out", str(out))
    assert result.exit_code == 0, result.output
    for name in FILES:
        assert (out / name).stat().st_size > 0
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "pneumact control hunting --t-end 60.0" in report
    loop, experiment = canudas_hunting(canudas, t_end=60.0)
    metrics = loop_metrics(pa.simulate(loop, experiment))
    # the command runs in chunks for its progress bar: the steps differ, not the answer
    assert _metric(out, "limit_cycle_amplitude") == \
        pytest.approx(metrics.limit_cycle_amplitude, rel=ref.CLI_API_RTOL)
    assert _metric(out, "limit_cycle_amplitude") > ref.HUNTING_MIN_SWING / 2


def test_step_command_with_a_sampled_pid_on_the_valve(tmp_path):
    out = tmp_path / "step"
    result = invoke("control", "step", "--plant", "command", "--start", "4", "--stop", "8",
                    "--t-end", "0.6", "--sample-time", "1e-3", "--out", str(out))
    assert result.exit_code == 0, result.output
    signals = pd.read_csv(out / "signals.csv")
    command = signals["command [1]"]
    assert command.min() >= 0.0 and command.max() <= 1.0
    assert abs(signals["position [m]"].iloc[-1] - 0.008) < ref.CLI_STEP_FINAL_ERROR
    assert _metric(out, "rise_time") > 0


def test_profile_command_follows_a_csv_profile(tmp_path):
    profile = tmp_path / "profile.csv"
    profile.write_text("time [s],reference [mm]\n0,4\n0.2,4\n0.5,7\n0.9,7\n1.2,5\n1.8,5\n",
                       encoding="utf-8")
    out = tmp_path / "profile"
    # the plant and controller of the step test above: one closed-loop kernel for both
    result = invoke("control", "profile", str(profile), "--plant", "command",
                    "--sample-time", "1e-3", "--out", str(out))
    assert result.exit_code == 0, result.output
    signals = pd.read_csv(out / "signals.csv")
    assert np.allclose(signals["position_setpoint [m]"].iloc[0], 0.004)
    assert abs(signals["position [m]"].iloc[-1] - 0.005) < ref.CLI_STEP_FINAL_ERROR
    metrics = pd.read_csv(out / "metrics.csv")["metric"].tolist()  # a profile, not a step:
    assert "rms_tracking_error" in metrics and "overshoot" not in metrics  # no step metrics
    assert "overshoot" not in result.stdout and "rms_tracking_error" in result.stdout


def test_mistakes_are_one_line_and_leave_nothing(tmp_path):
    out = tmp_path / "bad"
    result = invoke("control", "step", "--anti-windup", "sometimes", "--out", str(out))
    assert result.exit_code == 2
    assert "anti_windup" in result.output and "back-calculation" in result.output
    assert not out.exists()
    result = invoke("control", "step", "--plant", "command", "--start", "40",
                    "--out", str(out))
    assert result.exit_code == 2 and "--start = 40 mm" in result.output
    assert "x_max = 20 mm" in result.output  # beyond the stroke
    assert not out.exists()
    profile = tmp_path / "p.csv"
    profile.write_text("time [s],speed [m/s]\n0,1\n1,2\n", encoding="utf-8")
    result = invoke("control", "profile", str(profile), "--out", str(out))
    assert result.exit_code == 2 and "set-point column" in result.output
