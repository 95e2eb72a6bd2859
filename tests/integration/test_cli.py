"""The ``pneumact`` command line end to end: outputs, summaries and user mistakes."""

from __future__ import annotations

import os
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pneumact.cli import app
from pneumact.io.tables import RUN_LISTING

# --- reference values (one block) ----------------------------------------------------
EXIT_USER_ERROR = 2
EXIT_CHECK_FAILED = 2  # the README promises 2 for every user error
SIM_COLUMNS = ("time [s]", "pressure [Pa]", "position [m]", "velocity [m/s]", "friction [N]")
RIG_COLUMNS = ("time [s]", "position [m]", "velocity [m/s]", "friction [N]")
SHORT_T_END = "5"  # s: keeps each run short
SRC = Path(__file__).resolve().parents[2] / "src"

runner = CliRunner()


def shipped_toml() -> str:
    return (resources.files("pneumact") / "parameters/sets/vgt-paper.toml").read_text(
        encoding="utf-8")


def header(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()[0].split(",")


def invoke(*args: str):
    result = runner.invoke(app, list(args))
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


def test_default_simulate_writes_csv_and_png_and_summarises(tmp_path):
    out = tmp_path / "run"
    result = invoke("simulate", "--out", str(out))
    assert result.exit_code == 0, result.output
    columns = header(out / "simulation.csv")
    assert columns[0] == "time [s]"
    assert set(SIM_COLUMNS) <= set(columns)
    assert (out / "hysteresis.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "loop width" in result.stdout
    assert "kPa of vacuum" in result.stdout
    hidden = [p.name for p in out.iterdir() if p.name.startswith(".")]
    assert hidden == [RUN_LISTING]  # the list of what the run wrote; no temporary left
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]  # nor beside


@pytest.mark.parametrize(("chamber", "spool_lag"), [("adiabatic", 0), ("heat-transfer", 2)])
def test_simulate_the_cylinder_writes_its_step_response(tmp_path, chamber, spool_lag):
    """--model cylinder: the shipped cylinder set, a spool step, the API's run as CSV
    (with --chamber heat-transfer, the chambers' gas temperatures too; --spool-lag 2, a
    second-order spool); --spool-lag beyond 2 is refused."""
    import numpy as np
    import pandas as pd

    import pneumact as pa
    from conftest import load_quietly
    from reference import CLI_CHUNKED_RUN_RTOL

    out = tmp_path / "cylinder"
    result = invoke("simulate", "--model", "cylinder", "--chamber", chamber, "--spool-lag",
                    str(spool_lag), "--t-end", "0.5", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "95 % of the stroke" in result.stdout
    assert (out / "response.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    frame = pd.read_csv(out / "simulation.csv")
    law = pa.Adiabatic() if chamber == "adiabatic" else pa.HeatTransfer()
    api = pa.simulate(pa.Cylinder(load_quietly("iso15552-32"), chamber=law,
                                  spool_lag=spool_lag),
                      pa.experiments.SpoolStep(t_end=0.5))
    signals = [("position", "m"), ("pressure_a", "Pa"), ("pressure_b", "Pa")]
    if spool_lag:
        signals += [("spool_position", "1")]
    if chamber == "heat-transfer":
        signals += [("temperature_a", "K"), ("temperature_b", "K")]
    for name, unit in signals:
        cli = frame[f"{name} [{unit}]"].to_numpy()  # run in chunks (its progress): rtol apart
        assert np.abs(cli - api[name]).max() <= CLI_CHUNKED_RUN_RTOL * np.ptp(api[name]), name
    refused = invoke("simulate", "--model", "cylinder", "--valve", "command")
    assert refused.exit_code != 0 and "own 5/3 valve" in refused.output
    refused = invoke("simulate", "--model", "cylinder", "--spool-lag", "3")
    assert refused.exit_code != 0 and "order 0" in refused.output


@pytest.mark.parametrize("valve", ["command", "iso6358"])
def test_command_valve_runs(tmp_path, valve):
    """Both command-driven valves run the command cycle; --low, which sets a pressure
    cycle, is refused with either."""
    result = invoke("simulate", "--valve", valve, "--t-end", SHORT_T_END,
                    "--out", str(tmp_path))
    assert result.exit_code == 0, result.output
    assert set(SIM_COLUMNS) <= set(header(tmp_path / "simulation.csv"))
    refused = invoke("simulate", "--valve", valve, "--low", "30", "--out",
                     str(tmp_path / "low"))
    assert refused.exit_code == EXIT_CHECK_FAILED
    assert f"with --valve {valve} the default cycle is the command" in refused.output


def test_pressure_input_csv(tmp_path):
    csv = tmp_path / "pressure.csv"
    csv.write_text("time [s],pressure [kPa]\n0,100\n2.5,20\n5,100\n", encoding="utf-8")
    out = tmp_path / "out"
    result = invoke("simulate", "--input-csv", str(csv), "--out", str(out))
    assert result.exit_code == 0, result.output
    lines = (out / "simulation.csv").read_text(encoding="utf-8").splitlines()
    last_time = float(lines[-1].split(",")[0])
    assert last_time == pytest.approx(5.0)


def test_friction_test_stick_slip(tmp_path):
    result = invoke("friction-test", "stick-slip", "--t-end", SHORT_T_END,
                    "--out", str(tmp_path))
    assert result.exit_code == 0, result.output
    assert set(RIG_COLUMNS) <= set(header(tmp_path / "friction_test.csv"))
    assert any(c.startswith("drive_") for c in header(tmp_path / "friction_test.csv"))
    assert (tmp_path / "friction_test.png").exists()


def test_params_list_show_check(tmp_path):
    listing = invoke("params", "list")
    assert listing.exit_code == 0
    assert "vgt-paper" in listing.stdout and "canudas1995" in listing.stdout

    shown = invoke("params", "show", "vgt-paper")
    assert shown.exit_code == 0
    assert "60 cm^3" in shown.stdout  # as the file gave it
    assert "6e-05 m^3" in shown.stdout  # and in SI

    good = tmp_path / "good.toml"
    good.write_text(shipped_toml(), encoding="utf-8")
    checked = invoke("params", "check", str(good))
    assert checked.exit_code == 0
    assert "OK" in checked.stdout
    assert "PassivityWarning" in checked.stderr  # the paper's sigma1 is not passive

    bad = tmp_path / "bad.toml"
    bad.write_text(shipped_toml().replace("Fc = {", "Fcc = {", 1), encoding="utf-8")
    failed = invoke("params", "check", str(bad))
    assert failed.exit_code == EXIT_CHECK_FAILED
    assert "error:" in failed.stderr and "Fcc" in failed.stderr


BAD_TOML = {
    "misspelled": (("Fc = {", "Fcc = {"), "unknown parameter 'Fcc'"),
    "unknown unit": (('"0.63 kg"', '"0.63 kgg"'), "unknown unit 'kgg'"),
    "Fs below Fc": (('"3.2 N"', '"2.0 N"'), "Fs = 2 N: must be >= Fc"),
    "negative mass": (('"0.63 kg"', '"-0.63 kg"'), "m = -0.63 kg: must be >= 1e-09 kg"),
}

BAD_CSV = {
    "NaN": ("time [s],pressure [kPa]\n0,100\n1,nan\n2,80\n", "NaN"),
    "non-increasing time": ("time [s],pressure [kPa]\n0,100\n1,90\n1,80\n",
                            "not strictly increasing"),
    "missing time column": ("t [s],pressure [kPa]\n0,100\n1,90\n", "'time' is missing"),
}


def assert_user_error(result, message: str, out: Path) -> None:
    assert result.exit_code == EXIT_USER_ERROR, result.output
    lines = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(lines) == 1, result.stderr
    assert message in lines[0]
    assert "Traceback" not in result.output
    assert not out.exists()


def test_unknown_params_name(tmp_path):
    out = tmp_path / "out"
    result = invoke("simulate", "--params", "vgt-papr", "--out", str(out))
    assert_user_error(result, "did you mean 'vgt-paper'", out)


@pytest.mark.parametrize("case", list(BAD_TOML))
def test_bad_parameter_file(tmp_path, case):
    (old, new), message = BAD_TOML[case]
    toml = tmp_path / "params.toml"
    text = shipped_toml()
    assert old in text
    toml.write_text(text.replace(old, new, 1), encoding="utf-8")
    out = tmp_path / "out"
    result = invoke("simulate", "--params", str(toml), "--out", str(out))
    assert_user_error(result, message, out)


@pytest.mark.parametrize("case", list(BAD_CSV))
def test_bad_input_csv(tmp_path, case):
    text, message = BAD_CSV[case]
    csv = tmp_path / "input.csv"
    csv.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    result = invoke("simulate", "--input-csv", str(csv), "--out", str(out))
    assert_user_error(result, message, out)


def test_t_end_beyond_input_data(tmp_path):
    csv = tmp_path / "input.csv"
    csv.write_text("time [s],pressure [kPa]\n0,100\n1,90\n", encoding="utf-8")
    out = tmp_path / "out"
    result = invoke("simulate", "--input-csv", str(csv), "--t-end", "3", "--out", str(out))
    assert_user_error(result, "beyond the input data", out)


def test_missing_input_file(tmp_path):
    out = tmp_path / "out"
    result = invoke("simulate", "--input-csv", str(tmp_path / "nope.csv"), "--out", str(out))
    assert_user_error(result, "not found", out)


def test_failed_plot_leaves_no_csv(tmp_path, monkeypatch):
    import pneumact.plotting

    def broken(fig, path):
        raise OSError(f"{path}: no space left on device")

    monkeypatch.setattr(pneumact.plotting, "save_figure", broken)
    out = tmp_path / "out"
    result = invoke("simulate", "--t-end", SHORT_T_END, "--out", str(out))
    assert_user_error(result, "no space left on device", out)


def test_version_and_simulate_through_python_module(tmp_path):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(SRC), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)}
    version = subprocess.run([sys.executable, "-m", "pneumact.cli", "--version"],
                             capture_output=True, text=True, env=env, check=False)
    assert version.returncode == 0, version.stderr
    assert version.stdout.startswith("pneumact ")
    run = subprocess.run(
        [sys.executable, "-m", "pneumact.cli", "simulate", "--t-end", SHORT_T_END, "--out",
         str(tmp_path / "sub")], capture_output=True, text=True, env=env, check=False)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "sub" / "simulation.csv").exists()
    assert (tmp_path / "sub" / "hysteresis.png").exists()


# ------------------------------------------------------------------ CLI and API in parity
def _command(path: list[str]):
    import typer.main

    group = typer.main.get_command(app)
    for name in path:
        group = group.commands[name]
    return group


def _options(command) -> dict[str, object]:
    return {opt: param.default for param in command.params for opt in param.opts
            if opt.startswith("--")}


def test_every_friction_test_setting_is_an_option():
    from dataclasses import fields

    from pneumact.cli.friction_test import option_name
    from pneumact.experiments.friction import FRICTION_TESTS

    for kind, cls in FRICTION_TESTS.items():
        options = _options(_command(["friction-test", kind]))
        for field in fields(cls):
            assert option_name(field.name) in options, f"{kind}: {field.name} has no option"
        assert {"--params", "--friction", "--out"} <= set(options)


def test_simulate_and_batch_share_model_options_and_defaults():
    simulate, batch = _options(_command(["simulate"])), _options(_command(["simulate-batch"]))
    shared = ("--params", "--valve", "--friction", "--chamber", "--t-end", "--low", "--input-csv",
              "--rtol")
    for option in shared:
        assert option in simulate and option in batch, option
        assert simulate[option] == batch[option], option


def test_friction_test_options_reach_the_api(tmp_path):
    """The CSV of a CLI run equals the API run with the same settings."""
    import numpy as np
    import pandas as pd

    from conftest import load_quietly
    from pneumact.analysis.friction_tests import run_friction_test
    from pneumact.experiments.friction import Presliding

    result = invoke("friction-test", "presliding", "--amplitude", "0.5", "--t-end", "1",
                    "--n-points", "101", "--rtol", "1e-6", "--out", str(tmp_path))
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(tmp_path / "friction_test.csv")
    api = run_friction_test(Presliding(amplitude=0.5, t_end=1.0, n_points=101, rtol=1e-6),
                            load_quietly("canudas1995"))
    np.testing.assert_array_equal(frame["position [m]"].to_numpy(), api.result["position"])


def test_bad_friction_test_setting_is_one_clear_line(tmp_path):
    result = invoke("friction-test", "presliding", "--amplitude", "1.5", "--out",
                    str(tmp_path))
    assert result.exit_code == EXIT_USER_ERROR
    assert "amplitude = 1.5" in result.output and "(0, 1)" in result.output
    result = invoke("friction-test", "break-away", "--rates", "1,x", "--out", str(tmp_path))
    assert result.exit_code == EXIT_USER_ERROR and "--rates" in result.output
    assert not any(tmp_path.iterdir())
