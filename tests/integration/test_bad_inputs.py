"""Every command and every public entry point against a table of bad values.

The command line: every option of every command (walked from the typer app, so a new
option must be classified here) gets the values it must refuse; each must end with exit
code 2, one clear message naming the option or the value, no traceback, and no file
left behind. The Python API: each entry point gets wrong types, NaN, infinities,
negative, zero, huge values, wrong units and unknown names; each must raise a
``PneumactError`` (nothing from numpy, scipy, numba or SALib). The bad files live in
``tests/data/bad``. Almost every mistake is refused before a kernel compiles, so the
whole table runs in seconds.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pandas as pd
import pytest
import typer
from typer.testing import CliRunner

import pneumact as pa
from pneumact import sensitivity as sa
from pneumact.cli import app, finite_float
from pneumact.errors import PassivityWarning, PlausibilityWarning, PneumactError
from pneumact.identification import inverse_friction

DATA = Path(__file__).resolve().parents[1] / "data"
BAD, GOOD = DATA / "bad", DATA / "good"
EXIT_USER_ERROR = 2
runner = CliRunner()

# --------------------------------------------------------------------------- the CLI
#: arguments that make each command valid, besides the option under test ("OUT": the
#: output folder of the case)
BASE = {
    "simulate": ["--out", "OUT"],
    "simulate-batch": [str(GOOD / "table.csv"), "--out", "OUT"],
    "campaign": ["--out", "OUT"],
    "fit": [str(GOOD / "record.csv"), "--free", "Fc", "--out", "OUT"],
    "compare": [str(GOOD / "record.csv"), "--laws", "coulomb-viscous", "--out", "OUT"],
    "sensitivity": ["sobol", "--n", "8", "--t-end", "2", "--out", "OUT"],
    "validate": [str(GOOD / "record.csv"), "--out", "OUT"],
    "reproduce": ["--quick", "--out", "OUT"],
    "friction-test steady-state": ["--out", "OUT"],
    "friction-test presliding": ["--out", "OUT"],
    "friction-test frictional-lag": ["--out", "OUT"],
    "friction-test break-away": ["--out", "OUT"],
    "friction-test stick-slip": ["--out", "OUT"],
    "params list": [],
    "params show": ["vgt-paper"],
    "params check": ["vgt-paper"],
    "identify paper": [str(GOOD / "record.csv"), "--out", "OUT"],
    "identify signature": [str(GOOD / "record.csv"), "--out", "OUT"],
    "identify friction": [str(GOOD / "force_record.csv"), "--out", "OUT"],
    "control step": ["--out", "OUT"],
    "control profile": [str(GOOD / "profile.csv"), "--out", "OUT"],
    "control hunting": ["--out", "OUT"],
    "control tune": ["--n-global", "0", "--max-evaluations", "1", "--rounds", "0",
                     "--out", "OUT"],
    "control compare": ["--out", "OUT"],
    "export fmu": ["--out", "OUT"],
}

#: option -> values it must refuse, beyond NaN, infinities and text (refused by the
#: parser of every number option: ``test_every_number_option_refuses_nan``). Keys are
#: "--option" (the same meaning in every command) or "command --option".
BAD_VALUES: dict[str, list[str]] = {
    # a folder that is not there, and one without the TU Delft seal records
    "reproduce --seal-data": [str(BAD / "missing"), str(BAD)],
    "--params": ["vgt-papr", str(BAD / "k_huge.toml"), str(BAD / "m_tiny.toml"),
                 str(BAD / "k_in_n_per_mm.toml"),
                 str(BAD / "p_atm_in_kpa_as_pa.toml"), str(BAD / "p_atm_nan.toml"),
                 str(BAD / "fs_below_fc.toml"), str(BAD / "not_toml.toml")],
    "--out": [str(GOOD / "record.csv")],  # a file where a folder is expected
    "--input-csv": [str(BAD / "negative_pressure.csv"), str(BAD / "huge_pressure.csv"),
                    str(BAD / "kpa_as_pa.csv"), str(BAD / "negative_time.csv"),
                    str(BAD / "missing.csv")],
    "--valve": ["butterfly"],
    "--model": ["piston"],
    "--friction": ["lugree"],
    # with the default pressure source: it would do nothing; a temperature state the
    # diaphragm's chamber does not have
    "--chamber": ["adiabatic", "heat-transfer"],
    "--exponent": ["0.5", "1.3"],  # out of [1, γ]; not --chamber polytropic
    "--spool-lag": ["1", "3"],  # the cylinder's spool: not the actuator's valves
    # the cylinder's valving: not the actuator's (nor the regulator loop's)
    "--valves": ["3/3", "two-3/2"],
    # no TIME; beyond the actuator's load input (±1 MN); before the run
    # (test_cli_cylinder, test_cli_actuator_load)
    "--load-step": ["300", "3e6,0.2", "300,-1"],
    "--decaying-damping": [],
    "--elements": ["0", "4"],  # with the default --friction lugre: not a GMS
    "--chunk-size": ["0"],
    "--t-end": ["0", "-1"],
    "--low": ["0", "-50", "200", "20000"],
    "--rtol": ["0", "-1e-6", "1"],
    "--features": ["loop_widht_pressure", "stroke,stroke"],
    "--signals": ["positon", "position,position"],
    "--scheduler": ["not-an-address"],
    "--workers": ["0", "-3"],
    "--resume": ["+--overwrite"],  # together: contradict each other
    "--overwrite": [],
    "--seed": ["-1"],
    "--spread": ["-1", "100", "150"],  # the prior's uncertainty, % in [0, 100)
    "--plan": [],
    "--round": ["0", "-2"],  # the first round is 1
    "--simulate": ["nowhere", "+--plan"],  # no plan there; with --plan: contradictory
    "--staged-only": [],
    "--partial": [],
    # no folder there; a folder without an identification's estimates.csv
    "--previous": [str(BAD / "missing"), str(BAD)],
    # behind the regulator of the set-point records: legal; but not the cylinder's law
    "identify paper --chamber": ["heat-transfer"],
    "--pressure-noise": ["-1"],
    "--position-noise": ["-1"],
    "--resolution": ["-1"],
    "--free": ["sigma0,sigma0", "Fcc", ""],
    "--per-record": ["sigma0"],  # not among the free parameters
    "--offsets": ["pressure"],  # not a fitted signal
    "--window": ["5,1", "1", "a,b"],
    "--multistart": ["-1"],
    "--profile": ["sigma1"],  # not free
    "--loss": ["foo"],
    "--points": ["2"],
    "--f-scale": ["0", "-1"],
    "validate --input": ["butterfly"],
    "sensitivity --variations": ["sigma0=abc%", "sigma0"],
    "sensitivity --conditions": ["period=0", "valve=butterfly", "period", "colour=red"],
    "--times": ["1"],
    "--n": ["3", "100"],
    "--second-order": ["+--convergence"],
    "--convergence": [],
    "validate --signals": ["positon"],
    "validate --train": [str(GOOD / "record.csv")],  # without --free
    "validate --free": ["Fc"],  # without --train
    "--smooth-input": [],
    "--quick": [],
    "--atol-factor": ["0", "-1"],
    "--speeds": ["0", "-1,1", "abc"],
    "--settle": ["0"],
    "--min-hold": ["-1"],
    "--link": ["0"],
    "--n-points": ["1"],
    "presliding --amplitude": ["0", "1.5"],
    "frictional-lag --amplitude": ["-1", "0.01"],
    "--frequencies": ["0", "-1"],
    "--mean": ["0"],
    "--periods": ["1"],
    "--samples-per-period": ["1"],
    "--rates": ["0", "-1"],
    "--final-force": ["-1"],
    "--threshold": ["0"],
    "stick-slip --t-end": ["0", "1e6"],  # 1e6 s at 1 kHz: too big for memory
    "presliding --t-end": ["0"],
    "--duration": ["-1"],  # the old name of --t-end
    "--v-drive": ["1e3"],
    "--samples-per-second": ["0"],
    "--sliding-speed": ["0", "-5"],
    "--fit-delta": [],
    "--format": ["matlab"],
    "--laws": ["friction", "gms:x", "lugre,lugre"],
    "--holdout": ["5", "a"],
    "--jacobian": ["exact"],
    "compare --multistart": ["-1", "many"],
    "--force": ["torque"],
    "--mass": [],
    "--asymmetric": [],
    "--cutoff": ["0", "-1"],
    "--decimate": ["0"],
    "--validate": [str(BAD / "missing.csv")],
    "--start": ["-1", "100"],
    "--stop": ["25"],
    "--t-step": ["-1", "5"],
    "--plant": ["piston"],
    "--controller": ["pd"],
    "--kp": ["-5"],
    "--ki": ["-1"],
    "--kd": ["-1"],
    "--derivative": ["sometimes"],
    "--filter-time": ["0"],
    "--kx": ["5"],  # with the default pid controller: not read
    "--kv": ["5"],
    "--u-min": ["200000"],  # above the upper limit
    "--u-max": ["1"],  # below the lower limit (regulator: Pa)
    "--anti-windup": ["sometimes"],
    "--tracking-time": ["0"],
    "--sample-time": ["0", "-1"],
    "--velocity-estimate": ["guess"],
    "--coulomb-ff": ["-1"],
    "--dither": ["1", "a,b"],
    "--observer": [],
    "--observer-gain": ["5"],  # without --observer
    "--column": ["speed"],
    "hunting --kp": ["-3"],
    "hunting --kv": ["-6"],
    "hunting --ki": ["-4"],
    "--position-setpoint": [],
    "hunting --t-end": ["0"],
    "--binary": [],
    "--spec": ["speed=3", "settling=-1", "overshoot=five", ""],
    "tune --gains": ["kx", ""],
    "--at": ["-1", "100"],
    "--uncertainty": ["missing.csv"],
    "--gain-spread": ["1", "0"],
    "--n-global": ["-1"],
    "--max-evaluations": ["-1"],
    "--rounds": ["-1"],
    "--margin": ["1", "-0.1"],
    "--gains-file": ["missing.toml", *sorted(str(p) for p in (BAD / "gains").glob("*.toml"))],
    "--regime": ["gliding"],
    "--velocity": ["0", "-5"],
    "--tuned": ["missing.toml", str(BAD / "not_toml.toml")],
    "--compiler": ["no-such-cc"],
    "--kind": ["hybrid"],
    "--fmi": ["1", "4"],
}
#: arguments (not options) and the bad values each command must refuse
BAD_ARGUMENTS: dict[str, list[str]] = {
    "simulate-batch": [str(BAD / "table_text_cell.csv"),
                       str(BAD / "table_unknown_column.csv"), str(BAD / "missing.csv")],
    "fit": [str(BAD / name) for name in (
        "negative_pressure.csv", "huge_pressure.csv", "kpa_as_pa.csv", "negative_time.csv",
        "nan_cell.csv", "time_backwards.csv", "no_header.csv", "position_in_metres.csv",
        "text_cell.csv", "empty.csv", "one_row.csv", "no_unit.csv", "wrong_dimension.csv",
        "not_utf8.csv", "missing.csv", "epoch_time.csv")],
    "validate": [str(BAD / "position_in_metres.csv"), str(BAD / "negative_pressure.csv")],
    "params show": ["vgt-papr", str(BAD / "k_huge.toml")],
    "params check": [str(BAD / name) for name in (
        "k_huge.toml", "k_in_n_per_mm.toml", "m_tiny.toml", "p_atm_in_kpa_as_pa.toml",
        "p_atm_nan.toml", "p_atm_gauge.toml", "fs_below_fc.toml", "unknown_parameter.toml",
        "bare_number.toml", "unknown_unit.toml", "not_toml.toml", "negative_volume.toml",
        "missing.toml", "params.json")] + [str(BAD)],  # a folder where a file is expected
    "control profile": [str(BAD / "negative_time.csv"), str(BAD / "missing.csv")],
    "identify paper": [str(BAD / "kpa_as_pa.csv"), str(BAD / "position_in_percent.csv")],
    "identify signature": [str(BAD / "kpa_as_pa.csv")],
    "identify friction": [str(BAD / "missing.csv"), str(BAD / "no_motion.csv")],
    "sensitivity": ["sobbol"],
}


def _commands():
    root = typer.main.get_command(app)

    def walk(cmd, path):
        subs = getattr(cmd, "commands", None)
        if subs:
            for name, sub in subs.items():
                yield from walk(sub, [*path, name])
        else:
            yield " ".join(path), cmd

    return list(walk(root, []))


COMMANDS = _commands()


def _bad_values(command: str, option: str) -> list[str] | None:
    for key in (f"{command} {option}", f"{command.split()[-1]} {option}", option):
        if key in BAD_VALUES:
            return BAD_VALUES[key]
    return None


def _option_cases():
    cases = []
    for command, cmd in COMMANDS:
        for param in cmd.params:
            if param.param_type_name != "option" or param.name == "help":
                continue
            option = max(param.opts, key=len)
            for value in _bad_values(command, option) or []:
                cases.append(pytest.param(command, option, value,
                                          id=f"{command} {option}={value}"))
    return cases


def _argument_cases():
    return [pytest.param(command, value, id=f"{command} {Path(value).name}")
            for command, values in BAD_ARGUMENTS.items() for value in values]


def _invoke(args: list[str], folder: Path):
    out = folder / "out"
    args = [str(out) if a == "OUT" else a for a in args]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        warnings.simplefilter("ignore", PlausibilityWarning)
        return runner.invoke(app, args)


def assert_refused(result, *names: str) -> None:
    """Exit 2, one message (ours, or the parser's usage error) naming the option or the
    value, and no traceback."""
    text = result.output
    assert result.exit_code == EXIT_USER_ERROR, text
    assert result.exception is None or isinstance(result.exception, SystemExit), text
    assert "Traceback" not in text and "internal error" not in text, text
    ours = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    parser = "Invalid value" in text or "No such option" in text or "Missing" in text
    assert len(ours) == 1 or (parser and not ours), text
    flat = " ".join(text.split())
    assert any(n and (n in flat or Path(n).name in flat) for n in names), text


@pytest.fixture()
def workdir(tmp_path, monkeypatch):
    """An empty working folder: anything left in it after a refusal is a failure."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_every_option_is_classified():
    """A new option must say here which values it refuses (booleans and choices: none,
    or the parser's)."""
    missing = sorted({f"{command} {max(p.opts, key=len)}" for command, cmd in COMMANDS
                      for p in cmd.params
                      if p.param_type_name == "option" and p.name != "help"
                      and _bad_values(command, max(p.opts, key=len)) is None})
    assert not missing, f"classify these options in BAD_VALUES: {missing}"
    assert set(BASE) == {command for command, _ in COMMANDS}


@pytest.mark.parametrize(("command", "option", "value"), _option_cases())
def test_bad_option_value_is_one_clear_line(workdir, command, option, value):
    args = [*command.split(), *BASE[command]]
    extra = [value[1:]] if value.startswith("+") else [value]  # "+--flag": a second flag
    flag = [option] if value.startswith("+") else []
    cmd = dict(COMMANDS)[command]
    param = next(p for p in cmd.params if option in p.opts)
    if getattr(param, "is_flag", False) and not value.startswith("+"):
        pytest.skip("a flag takes no value")
    result = _invoke([*args, *flag, *extra] if flag else [*args, f"{option}={value}"],
                     workdir)
    assert_refused(result, option, value.lstrip("+"), option.lstrip("-").replace("-", "_"))
    assert not any(workdir.iterdir()), "a refused command left files"


@pytest.mark.parametrize(("command", "value"), _argument_cases())
def test_bad_argument_is_one_clear_line(workdir, command, value):
    base = [a for a in BASE[command] if not a.endswith((".csv", "vgt-paper", "sobol"))]
    result = _invoke([*command.split(), value, *base], workdir)
    assert_refused(result, Path(value).name, value)
    assert not any(workdir.iterdir()), "a refused command left files"


def test_every_number_option_refuses_nan_infinity_and_text(workdir):
    """Every float option parses through ``finite_float``; one per command is run."""
    for command, cmd in COMMANDS:
        floats = [p for p in cmd.params
                  if p.param_type_name == "option" and getattr(p, "type_descriptor", None)
                  is not None and p.type_descriptor.annotation is float]
        for param in floats:
            info = param.type_descriptor.parameter_info
            assert info.parser is finite_float, f"{command} {param.opts}"
        if floats:
            option = max(floats[0].opts, key=len)
            for value in ("nan", "-inf", "abc"):
                result = _invoke([*command.split(), *BASE[command], f"{option}={value}"],
                                 workdir)
                assert_refused(result, option, value)
    assert not any(workdir.iterdir())


def test_help_shows_every_unit():
    """Rich markup must not eat '[kPa]', '[s]', '[mm]' ... from any option's help."""
    import re

    for command, cmd in COMMANDS:
        result = runner.invoke(app, [*command.split(), "--help"], env={"COLUMNS": "250"})
        assert result.exit_code == 0, result.output
        shown = " ".join(result.output.replace("│", " ").split())
        for param in cmd.params:
            help_text = getattr(param, "help", None) or ""
            for unit in re.findall(r"\\?\[([^\],]{1,20})\]", help_text):
                assert f"[{unit}]" in shown, f"{command} {param.opts}: [{unit}]"


def test_batch_row_with_an_impossible_value_fails_alone(workdir):
    """A row that cannot be run (p_atm typed in kPa) is that row's error, with the likely
    mistake; the batch itself finishes."""
    table = workdir / "table.csv"
    table.write_text("p_atm [Pa]\n100\n1e5\n", encoding="utf-8")
    result = _invoke(["simulate-batch", str(table), "--t-end", "2", "--out", "OUT"], workdir)
    assert result.exit_code == 0, result.output
    rows = pd.read_csv(workdir / "out" / "summary.csv")
    assert rows["status"].tolist() == ["invalid", "ok"]
    assert "kPa typed as Pa" in rows["error"].iloc[0]


def test_friction_test_says_t_end_and_accepts_the_old_name(workdir):
    for command, cmd in COMMANDS:
        names = {o for p in cmd.params for o in p.opts if not getattr(p, "hidden", False)}
        assert "--duration" not in names, command
    result = _invoke(["friction-test", "presliding", "--duration", "0.5", "--n-points", "51",
                      "--out", "OUT"], workdir)
    assert result.exit_code == 0, result.output
    assert "--duration is deprecated" in result.stderr


def test_passivity_is_said_by_params_not_by_every_command(workdir):
    shown = _invoke(["params", "show", "vgt-paper"], workdir)
    assert "PassivityWarning" in shown.stderr
    checked = _invoke(["params", "check", "vgt-paper"], workdir)
    assert checked.exit_code == 0 and "PassivityWarning" in checked.stderr
    with warnings.catch_warnings():
        warnings.simplefilter("always", PassivityWarning)  # as a fresh process would
        result = runner.invoke(app, ["simulate", "--t-end", "1", "--out", "OUT"])
    assert result.exit_code == 0, result.output
    assert "Passivity" not in result.output


def test_a_failure_of_pneumact_s_own_is_one_line_without_traceback(workdir, monkeypatch):
    import importlib

    command = importlib.import_module("pneumact.cli.simulate")  # the module, not the command

    def broken(*args, **kwargs):
        raise RuntimeError("a bug")

    monkeypatch.setattr(command, "build_experiment", broken)
    result = _invoke(["simulate", "--out", "OUT"], workdir)
    assert result.exit_code == 1
    assert result.stderr.startswith("internal error: RuntimeError: a bug")
    assert "Traceback" not in result.output and "report it" in result.stderr
    assert not any(workdir.iterdir())


def test_errors_speak_the_command_line(workdir):
    headless = _invoke(["fit", str(BAD / "no_header.csv"), "--free", "Fc", "--out", "OUT"],
                       workdir)
    assert_refused(headless, "no_header.csv")
    assert "names=" not in headless.output and "header" in headless.output
    missing = workdir / "nopos.csv"
    missing.write_text("time [s],pressure [kPa],x [mm]\n0,100,0\n1,90,1\n", encoding="utf-8")
    result = _invoke(["fit", str(missing), "--free", "Fc", "--out", "OUT"], workdir)
    assert_refused(result, "position")
    assert "columns=" not in result.output


def test_a_record_given_twice_is_refused(workdir):
    """The same file twice (named twice, or once by its folder) or the same data under a
    second name would count as new data and narrow every interval: refused, naming it."""
    bench = workdir / "bench"
    bench.mkdir()
    text = (GOOD / "record.csv").read_text(encoding="utf-8")
    (bench / "record.csv").write_text(text, encoding="utf-8")
    twice = _invoke(["fit", str(bench / "record.csv"), str(bench / "record.csv"),
                     "--free", "Fc", "--out", "OUT"], workdir)
    assert_refused(twice, "record.csv")
    assert "given twice" in twice.stderr
    by_folder = _invoke(["identify", "paper", str(bench), str(bench / "record.csv"),
                         "--out", "OUT"], workdir)
    assert_refused(by_folder, "record.csv")
    assert "given twice" in by_folder.stderr
    (bench / "copy.csv").write_text(text, encoding="utf-8")
    copied = _invoke(["fit", str(bench), "--free", "Fc", "--out", "OUT"], workdir)
    assert_refused(copied, "copy.csv")
    assert "identical data" in copied.stderr
    assert sorted(p.name for p in workdir.iterdir()) == ["bench"]


# --------------------------------------------------------------------------- the API
@pytest.fixture(scope="module")
def api():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        vgt = pa.load_params("vgt-paper")
    actuator = pa.Actuator(vgt)
    record = pa.read_record(GOOD / "record.csv")
    return vgt, actuator, record


def _api_cases(vgt, actuator, record, folder: Path):
    """(label, call): each must raise a PneumactError."""
    cycle = pa.PressureCycle(period=2.0, n_points=11)
    problem = sa.Problem.around(vgt, {"Fc": "10%"})
    table = pd.DataFrame({"Fc": [2.6]})
    a_file = folder / "a_file.txt"
    a_file.write_text("x", encoding="utf-8")
    nan, inf = float("nan"), float("inf")
    return [
        ("load_params(5)", lambda: pa.load_params(5)),
        ("load_params('vgt-papr')", lambda: pa.load_params("vgt-papr")),
        ("Actuator(5)", lambda: pa.Actuator(5)),
        ("Actuator(dict)", lambda: pa.Actuator({"m": 1.0})),
        ("friction='lugre'", lambda: pa.Actuator(vgt, friction="lugre")),
        ("valve='command'", lambda: pa.Actuator(vgt, valve="command")),
        ("chamber=Adiabatic with a source", lambda: pa.Actuator(vgt, chamber=pa.Adiabatic())),
        ("LuGre('yes')", lambda: pa.LuGre("yes")),
        ("Polytropic(nan)", lambda: pa.Polytropic(nan)),
        ("Polytropic(0.5)", lambda: pa.Polytropic(0.5)),
        ("FrictionRig(drive=5)", lambda: pa.FrictionRig(vgt, drive=5)),
        ("simulate(act, 'cycle')", lambda: pa.simulate(actuator, "cycle")),
        ("simulate(params, cycle)", lambda: pa.simulate(vgt, cycle)),
        ("solver='rodas'", lambda: pa.simulate(actuator, cycle, solver="rodas")),
        ("t_eval NaN", lambda: pa.simulate(actuator, cycle, t_eval=[0.0, nan, 1.0])),
        ("t_eval beyond", lambda: pa.simulate(actuator, cycle, t_eval=[0.0, 5.0])),
        ("t_eval text", lambda: pa.simulate(actuator, cycle, t_eval="abc")),
        ("y0 NaN", lambda: pa.simulate(actuator, cycle, y0=[nan, 0.0, 0.0])),
        ("values text", lambda: pa.simulate(actuator, cycle, values={"Fc": "2"})),
        ("values unknown", lambda: pa.simulate(actuator, cycle, values={"Fcc": 2.0})),
        ("progress not callable", lambda: pa.simulate(actuator, cycle, progress=3)),
        ("command drives a source", lambda: pa.simulate(actuator, pa.CommandCycle())),
        ("Rodas4(rtol='1e-6')", lambda: pa.Rodas4(rtol="1e-6")),
        ("Rodas4(rtol=nan)", lambda: pa.Rodas4(rtol=nan)),
        ("Rodas4(rtol=0)", lambda: pa.Rodas4(rtol=0.0)),
        ("Rodas4(atol=-1)", lambda: pa.Rodas4(atol=-1.0)),
        ("Rodas4(h_max=nan)", lambda: pa.Rodas4(h_max=nan)),
        ("Rodas4(max_steps=2.5)", lambda: pa.Rodas4(max_steps=2.5)),
        ("PressureCycle kPa as Pa", lambda: pa.PressureCycle(high=100, low=20)),
        ("PressureCycle negative", lambda: pa.PressureCycle(low=-50e3)),
        ("PressureCycle huge", lambda: pa.PressureCycle(high=1e12)),
        ("PressureCycle period inf", lambda: pa.PressureCycle(period=inf)),
        ("PressureCycle cycles 0", lambda: pa.PressureCycle(cycles=0)),
        ("CommandCycle(0, 5)", lambda: pa.CommandCycle(0, 5)),
        ("CommandCycle text", lambda: pa.CommandCycle("0", 1)),
        ("Experiment negative start", lambda: pa.Experiment(
            pa.experiments.Constant(5e4), "pressure", 1.0, t_start=-1.0)),
        ("Experiment quantity", lambda: pa.Experiment(
            pa.experiments.Constant(5e4), "presure", 1.0)),
        ("Experiment drives=5", lambda: pa.Experiment(
            pa.experiments.Constant(5e4), "pressure", 1.0, drives=5)),
        ("Experiment drives unknown", lambda: pa.Experiment(
            pa.experiments.Constant(5e4), "pressure", 1.0,
            drives={"lode": pa.experiments.Constant(1.0)})),
        ("Experiment drives its quantity", lambda: pa.Experiment(
            pa.experiments.Constant(5e4), "pressure", 1.0,
            drives={"pressure": pa.experiments.Constant(1e5)})),
        ("Experiment drives a number", lambda: pa.Experiment(
            pa.experiments.Constant(5e4), "pressure", 1.0, drives={"load": 3.0})),
        ("a load drives an actuator", lambda: pa.simulate(actuator, pa.Experiment(
            pa.experiments.Constant(5e4), "pressure", 1.0,
            drives={"load": pa.experiments.Constant(1.0)}))),
        ("SetpointStep beyond the stroke", lambda: pa.simulate(
            pa.control.ClosedLoop(pa.Actuator(vgt, valve=pa.PressureRegulator()),
                                  pa.PID(kp=5e6, u_min=1e4, u_max=1e5)),
            pa.SetpointStep(0.004, 0.1, t_step=0.1, t_end=0.2))),
        ("PID kp=-1", lambda: pa.PID(kp=-1.0)),
        ("PID kp=nan", lambda: pa.PID(kp=nan)),
        ("read_record(5)", lambda: pa.read_record(5)),
        ("read_record missing", lambda: pa.read_record(folder / "missing.csv")),
        ("read_record p_atm='abc'", lambda: pa.read_record(GOOD / "record.csv", p_atm="abc")),
        ("read_record p_atm=100", lambda: pa.read_record(GOOD / "record.csv", p_atm=100)),
        ("read_record p_atm=nan", lambda: pa.read_record(GOOD / "record.csv", p_atm=nan)),
        ("read_record columns=5", lambda: pa.read_record(GOOD / "record.csv", columns=5)),
        ("read_records(5)", lambda: pa.read_records(5)),
        ("read_records(a file twice)", lambda: pa.read_records([GOOD / "record.csv"] * 2)),
        ("fit(a record twice)", lambda: pa.fit(actuator, [record, record], ["Fc"])),
        ("validate(a record twice)", lambda: pa.validate(actuator, [record, record])),
        *[(f"read_record {p.name}", lambda p=p: pa.read_record(p))
          for p in sorted(BAD.glob("*.csv")) if not p.name.startswith("table_")
          and p.name not in ("command_five.csv", "position_in_metres.csv", "no_motion.csv",
                             "position_in_percent.csv", "saturated_position.csv")],
        ("identify_paper(positions in %)", lambda: pa.identify_paper(
            [pa.read_record(BAD / "position_in_percent.csv")], vgt)),
        ("inverse_friction(no motion)", lambda: inverse_friction(
            pa.read_record(BAD / "no_motion.csv"))),
        ("command record of 5", lambda: pa.read_record(BAD / "command_five.csv")),
        ("Record.from_arrays negative pressure", lambda: pa.Record.from_arrays(
            [0.0, 1.0], {"pressure": [1e5, -1.0]})),
        *[(f"load_params {p.name}", lambda p=p: pa.load_params(p))
          for p in sorted(BAD.glob("*.toml"))],
        ("load_params a JSON file", lambda: pa.load_params(BAD / "params.json")),
        ("load_params a folder", lambda: pa.load_params(BAD)),
        ("replace k=1e300", lambda: vgt.replace(k=1e300)),
        ("replace k='12850 N/mm'", lambda: vgt.replace(k="12850 N/mm")),
        ("replace m=1e-30", lambda: vgt.replace(m=1e-30)),
        ("replace p_atm=nan", lambda: vgt.replace(p_atm=nan)),
        ("replace p_atm=100", lambda: vgt.replace(p_atm=100.0)),
        ("simulate_batch table=dict", lambda: pa.simulate_batch(actuator, cycle, {"Fc": 1})),
        ("simulate_batch executor=0", lambda: pa.simulate_batch(actuator, cycle, table,
                                                                executor=0)),
        ("Executor(workers=0)", lambda: pa.Executor(workers=0)),
        ("Executor(workers=1.5)", lambda: pa.Executor(workers=1.5)),
        ("simulate_batch executor=[]", lambda: pa.simulate_batch(actuator, cycle, table,
                                                                 executor=[])),
        ("Checkpoint resume+overwrite", lambda: pa.Checkpoint(folder / "b", resume=True,
                                                              overwrite=True)),
        ("Checkpoint(resume='yes')", lambda: pa.Checkpoint(folder / "b", resume="yes")),
        ("simulate_batch checkpoint=a file", lambda: pa.simulate_batch(
            actuator, cycle, table, checkpoint=a_file)),
        ("simulate_batch scheduler", lambda: pa.simulate_batch(
            actuator, cycle, table, executor="not-an-address")),
        ("simulate_batch signals", lambda: pa.simulate_batch(actuator, cycle, table,
                                                             signals=["positon"])),
        ("Executor(chunk_size=0)", lambda: pa.Executor(chunk_size=0)),
        ("simulate_sensitivities names", lambda: pa.simulate_sensitivities(
            actuator, cycle, ["Fcc"])),
        ("sobol(n=8.5)", lambda: sa.sobol(problem, lambda x: x, n=8.5)),
        ("sobol(n=3)", lambda: sa.sobol(problem, lambda x: x, n=3)),
        ("sobol(n=100)", lambda: sa.sobol(problem, lambda x: x, n=100)),
        ("sobol(problem=dict)", lambda: sa.sobol({"names": ["Fc"]}, lambda x: x, n=8)),
        ("sobol(seed=-1)", lambda: sa.sobol(problem, lambda x: x, n=8, seed=-1)),
        ("morris(trajectories=1)", lambda: sa.morris(problem, lambda x: x, 1)),
        ("src(n=2)", lambda: sa.src(problem, lambda x: x, 2)),
        ("rbd_fast(n=5)", lambda: sa.rbd_fast(problem, lambda x: x, 5)),
        ("sobol_convergence(n_min=3)", lambda: sa.sobol_convergence(
            problem, lambda x: x, n_max=64, n_min=3)),
        ("Problem.around bad amount", lambda: sa.Problem.around(vgt, {"Fc": "abc%"})),
        ("fit(records=5)", lambda: pa.fit(actuator, 5, ["Fc"])),
        ("fit(free=[])", lambda: pa.fit(actuator, record, [])),
        ("fit(free twice)", lambda: pa.fit(actuator, record, ["Fc", "Fc"])),
        ("fit(optimizer='foo')", lambda: pa.fit(actuator, record, ["Fc"], optimizer="foo")),
        ("Optimizer(jacobian='exact')", lambda: pa.Optimizer(jacobian="exact")),
        ("Optimizer(max_nfev=0)", lambda: pa.Optimizer(max_nfev=0)),
        ("fit(multistart=-1)", lambda: pa.fit(actuator, record, ["Fc"], multistart=-1)),
        ("Multistart(seed=-1)", lambda: pa.Multistart(2, seed=-1)),
        ("fit(multistart='4')", lambda: pa.fit(actuator, record, ["Fc"], multistart="4")),
        ("Profile(points=2)", lambda: pa.Profile(["Fc"], points=2)),
        ("Offsets(records=[-1])", lambda: pa.Offsets(["position"], records=[-1])),
        ("Weights(records=[0])", lambda: pa.Weights(records=[0.0])),
        ("fit(window=(5, 1))", lambda: pa.fit(actuator, record, ["Fc"], window=(5.0, 1.0))),
        ("fit(window=(0, nan))", lambda: pa.fit(actuator, record, ["Fc"], window=(0.0, nan))),
        ("Optimizer(f_scale=0)", lambda: pa.Optimizer(f_scale=0.0)),
        ("Bounds(log=5)", lambda: pa.Bounds(log=5)),
        ("fit(bounds bad)", lambda: pa.fit(actuator, record, ["Fc"], bounds={"Fc": (3, 1)})),
        ("fit(weights<0)", lambda: pa.fit(actuator, record, ["Fc"],
                                          weights={"position": -1.0})),
        ("fit(weights for an unfitted signal)", lambda: pa.fit(
            actuator, record, ["Fc"], weights={"velocity": 1.0})),
        ("fit(solver='rodas')", lambda: pa.fit(actuator, record, ["Fc"], solver="rodas")),
        ("fit(unknown parameter)", lambda: pa.fit(actuator, record, ["Fcc"])),
        ("fit(position in metres)", lambda: pa.fit(actuator, _metres_record(record), ["Fc"])),
        ("validate(position file in metres)", lambda: pa.validate(
            actuator, pa.read_record(BAD / "position_in_metres.csv"))),
        ("validate(records=5)", lambda: pa.validate(actuator, 5)),
        ("validate(signals twice)", lambda: pa.validate(actuator, record,
                                                        signals=["position", "position"])),
        ("identify_paper(records, 5)", lambda: pa.identify_paper([record], 5)),
        ("identify_paper([], name)", lambda: pa.identify_paper([], "vgt-paper")),
        ("reproduce(out_dir=a file)", lambda: pa.reproduce(a_file)),
        ("reproduce(seed=-1)", lambda: pa.reproduce(folder / "r", seed=-1)),
        ("write_files to a file", lambda: _write_files(a_file)),
    ]


def _metres_record(record):
    """The good record with its positions a thousand times too large (mm read as m)."""
    return pa.Record.from_arrays(record.time, {"pressure": record["pressure"],
                                               "position": record["position"] * 1e3})


def _write_files(target):
    from pneumact.io.tables import write_files

    return write_files(target, {"a.txt": lambda p: p.write_text("a")})


def test_public_entry_points_raise_pneumact_errors(api, tmp_path):
    """Each bad call raises a PneumactError (a TypeError too for a wrong type), never an
    error from deep inside numpy, scipy, numba or SALib, and writes nothing."""
    vgt, actuator, record = api
    failures = []
    for label, call in _api_cases(vgt, actuator, record, tmp_path):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PassivityWarning)
            warnings.simplefilter("ignore", PlausibilityWarning)
            try:
                call()
            except PneumactError as exc:
                if not str(exc).strip():
                    failures.append(f"{label}: empty message")
                continue
            except Exception as exc:  # the point of the test: nothing else may escape
                failures.append(f"{label}: {type(exc).__name__}: {exc}")
                continue
        failures.append(f"{label}: accepted")
    assert not failures, "\n".join(failures)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file.txt"]


def test_fit_weights_name_the_signal_and_what_is_allowed(api):
    """A weight for a signal the fit does not fit is named, with the fitted signals (it
    was a bare KeyError: 'position')."""
    _, actuator, record = api
    with pytest.raises(PneumactError) as error:
        pa.fit(actuator, record, ["Fc"], weights={"velocity": 1.0})
    text = str(error.value)
    assert "weights for velocity" in text and "fitted signals (position)" in text, text
    assert "'" not in text, text


def test_friendlier_readings(api):
    vgt = api[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        by_name = pa.Actuator("vgt-paper")
    assert by_name.params.values == vgt.values
    assert isinstance(pa.Actuator(vgt, valve=pa.CommandValve).valve, pa.CommandValve)
    with pytest.raises(TypeError, match=r"pa\.LuGre\(\)"):  # a TypeError says the type
        pa.Actuator(vgt, friction="lugre")
    with pytest.raises(PneumactError, match="kPa typed as Pa"):
        pa.PressureCycle(high=100, low=20)


def test_bad_files_corpus_is_complete():
    """Every bad file is used by a test above (a file nobody reads proves nothing)."""
    used = " ".join(str(v) for values in (*BAD_VALUES.values(), *BAD_ARGUMENTS.values())
                    for v in values)
    api_used = {p.name for p in BAD.glob("*.csv")} | {p.name for p in BAD.glob("*.toml")}
    for path in BAD.iterdir():
        assert path.name in used or path.name in api_used, path.name


#: options that would do nothing where they are given (issue 42, finding 10), and a word
#: each refusal must say besides the option: refused, not silently ignored
USELESS_OPTIONS: dict[str, tuple[list[str], str]] = {
    "fit --f-scale with the linear loss": (
        ["fit", str(GOOD / "record.csv"), "--free", "Fc", "--f-scale", "2", "--out", "OUT"],
        "--f-scale"),
    "fit --seed without multistart": (
        ["fit", str(GOOD / "record.csv"), "--free", "Fc", "--seed", "3", "--out", "OUT"],
        "--seed"),
    "fit --points without a profile": (
        ["fit", str(GOOD / "record.csv"), "--free", "Fc", "--points", "5", "--out", "OUT"],
        "--points"),
    "fit --per-record with one record": (
        ["fit", str(GOOD / "record.csv"), "--free", "sigma0", "--per-record", "sigma0",
         "--out", "OUT"], "one record"),
    "campaign --plan --seed": (["campaign", "--plan", "--seed", "3", "--out", "OUT"],
                               "--seed"),
    "campaign --plan --pressure-noise": (
        ["campaign", "--plan", "--pressure-noise", "0.1", "--out", "OUT"],
        "--pressure-noise"),
    "validate --input setpoint --valve source": (
        ["validate", str(GOOD / "record.csv"), "--input", "pressure", "--valve", "source",
         "--out", "OUT"], "--valve"),
    "validate --train the test record": (
        ["validate", str(GOOD / "record.csv"), "--train", str(GOOD / "record.csv"),
         "--free", "Fc", "--out", "OUT"], "training record"),
    "control step --sample-time longer than the run": (
        ["control", "step", "--sample-time", "10", "--out", "OUT"], "sample_time = 10 s"),
    "control step without a step": (
        ["control", "step", "--start", "4", "--stop", "4", "--out", "OUT"], "no step"),
    "control step --u-min/--u-max in kPa": (
        ["control", "step", "--u-min", "10", "--u-max", "100", "--out", "OUT"],
        "looks like kPa"),
}


@pytest.mark.parametrize("case", list(USELESS_OPTIONS))
def test_an_option_that_would_do_nothing_is_refused(workdir, case):
    args, words = USELESS_OPTIONS[case]
    result = _invoke(args, workdir)
    assert_refused(result, words)
    assert not any(workdir.iterdir()), "a refused command left files"


def test_epoch_timestamps_are_refused_naming_the_offset(workdir):
    """t = 1.7e9 s (issue 42, finding 9): a message about the time offset, not the
    solver's "step size underflow"."""
    result = _invoke(["fit", str(BAD / "epoch_time.csv"), "--free", "Fc", "--out", "OUT"],
                     workdir)
    assert_refused(result, "epoch_time.csv")
    assert "timestamp" in result.stderr and "starts at 1.7e+09 s" in result.stderr
    assert "underflow" not in result.stderr


@pytest.mark.parametrize("args", [["simulate", "--t-end", "abc"], ["simulate", "--nope"],
                                  ["batch"]])
def test_usage_errors_end_in_the_one_error_prefix(workdir, args):
    """The parser's mistakes speak like every command's refusals (issue 42): one
    ``error:`` line after the usage, not a box titled "Error"."""
    result = _invoke(args, workdir)
    assert result.exit_code == EXIT_USER_ERROR
    assert [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert "Error" not in result.output and "╭" not in result.output


def test_messages_carry_no_python_reprs(workdir, monkeypatch):
    """numpy's reprs of numbers and a KeyError's quotes never reach a message."""
    import importlib

    import numpy as np

    from pneumact.cli.common import plain_message

    assert plain_message(f"Fc = {np.float64(np.nan)!r}, n = {np.int64(3)!r}") == "Fc = nan, n = 3"
    command = importlib.import_module("pneumact.cli.simulate")

    def broken(*args, **kwargs):
        raise KeyError("position")

    monkeypatch.setattr(command, "build_experiment", broken)
    result = _invoke(["simulate", "--out", "OUT"], workdir)
    assert "KeyError: position (" in result.stderr and "'position'" not in result.stderr


def test_a_study_beyond_the_memory_limit_is_refused_before_any_run(workdir, monkeypatch):
    """oat --times 10000000 (issue 42, finding 8): its estimate, the stated limit and how
    to raise it, before the features run (not minutes later at 3.5 GB)."""
    from pneumact.simulation import memory

    monkeypatch.delenv(memory.MEMORY_LIMIT_ENV, raising=False)
    monkeypatch.setattr(memory, "available_memory", lambda: 1 << 40)  # any machine
    result = _invoke(["sensitivity", "oat", "--signals", "position", "--times", "10000000",
                      "--out", "OUT"], workdir)
    assert_refused(result, "--times")
    assert "GiB of memory, above the limit of 4 GiB" in result.stderr
    assert "PNEUMACT_MEMORY_LIMIT" in result.stderr and "largest change" not in result.output


def test_identify_paper_refuses_positions_beyond_the_stroke_as_validate_does(workdir):
    """Positions in % labelled [mm] (54 'mm' on a 20 mm stroke; issue 42, finding 6):
    the unit named, not "0 of 8 identified"."""
    for command in (["identify", "paper"], ["validate"]):
        result = _invoke([*command, str(BAD / "position_in_percent.csv"), "--out", "OUT"],
                         workdir)
        assert_refused(result, "position_in_percent.csv")
        assert "position spans" in result.stderr and "position unit" in result.stderr


@pytest.mark.parametrize("command", [["fit", "--free", "Fc"], ["validate"]])
def test_a_saturated_position_sensor_is_named(workdir, command):
    """A position clipped at 6 mm while the pressure goes on (issue 42, finding 6): the
    run names the saturated sensor, whatever it concludes."""
    result = _invoke([command[0], str(BAD / "saturated_position.csv"), *command[1:],
                      "--out", "OUT"], workdir)
    assert "saturated position sensor" in result.stderr, result.output
    assert "from t = 0.65 to 1.35 s" in result.stderr
    assert "Traceback" not in result.output
