"""Sensitivity studies of the actuator on the batch engine, and the command line."""

from __future__ import annotations

import numpy as np
from typer.testing import CliRunner

import pneumact as pa
from pneumact.cli import app
from pneumact.sensitivity import one_at_a_time

runner = CliRunner()
EXIT_USER_ERROR = 2


def test_one_at_a_time_with_zero_variation_returns_the_nominal_run(vgt):
    model = pa.Actuator(vgt, valve=pa.CommandValve())
    study = one_at_a_time(model, pa.CommandCycle(period=20.0), {"Fc": 0.0, "sigma0": 0.0})
    assert len(study.runs) == 3  # nominal, then one run per parameter (low = high)
    deltas = study.runs.filter(like="delta_").to_numpy()
    assert np.all(deltas == 0.0)
    assert np.all(study.runs["rms_position_change"] == 0.0)
    nominal = pa.simulate(model, pa.CommandCycle(period=20.0))
    assert np.array_equal(study.signals["position"][0], nominal["position"])


def test_one_at_a_time_ranks_coulomb_friction_first_for_loop_width(vgt):
    model = pa.Actuator(vgt, valve=pa.CommandValve())
    study = one_at_a_time(model, pa.CommandCycle(period=20.0))
    assert study.ranking("loop_width_pressure").index[0] == "Fc"
    assert study.plot_loops() is not None


def test_cli_sensitivity_oat_and_sobol(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["sensitivity", "oat", "--out", "oat"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "oat" / "loops.png").exists()
    result = runner.invoke(app, ["sensitivity", "sobol", "--n", "16", "--out", "sobol"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "sobol" / "indices.csv").exists()
    result = runner.invoke(app, ["sensitivity", "sobol", "--vary", "Fc=30%,Fs=30%",
                                 "--n", "16", "--out", "bad"])
    assert result.exit_code == EXIT_USER_ERROR
    assert "Fs" in result.output and "runs failed" in result.output
    assert not (tmp_path / "bad").exists()
