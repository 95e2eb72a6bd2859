"""The cylinder on every command that takes a model (issue 41, item 5): ``--model
cylinder`` (``--plant cylinder`` for the closed loop) runs what the API runs, and what
belongs to the actuator alone is refused in one line naming the option."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.cli import app
from pneumact.core.signals import PiecewiseLinear, Step
from pneumact.experiments import SpoolStep

pytestmark = pytest.mark.integration

runner = CliRunner()
#: the commands with --model that these tests run on the cylinder (simulate: test_cli.py)
TESTED = {"simulate", "simulate-batch", "sensitivity", "fit", "export fmu"}
T_END = "0.3"  # s: the spool steps at 0.1 s, the piston reaches the stop at about 0.27 s


def invoke(*args: str):
    result = runner.invoke(app, list(args))
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


def _commands(group=app, words=()):
    """(words, click command) of every command."""
    import typer.main

    click_group = typer.main.get_command(group) if not hasattr(group, "commands") else group
    for name, command in click_group.commands.items():
        if hasattr(command, "commands"):
            yield from _commands(command, (*words, name))
        else:
            yield " ".join((*words, name)), command


def test_every_command_with_a_model_option_is_run_on_the_cylinder():
    with_model = {words for words, command in _commands()
                  if any("--model" in p.opts for p in command.params)}
    assert with_model == TESTED, f"run these on the cylinder here: {with_model - TESTED}"


def test_simulate_batch_runs_the_cylinder(tmp_path):
    """Each row's features are the cylinder's motion, as the API's batch computes them."""
    table = tmp_path / "table.csv"
    table.write_text("Fc,sigma2\n20,50\n15,80\n", encoding="utf-8")
    result = invoke("simulate-batch", str(table), "--model", "cylinder", "--t-end", T_END,
                    "--workers", "1", "--out", str(tmp_path / "batch"))
    assert result.exit_code == 0, result.output
    cli = pd.read_parquet(tmp_path / "batch" / "results.parquet")
    api = pa.simulate_batch(pa.Cylinder(load_quietly("iso15552-32")),
                            SpoolStep(t_end=float(T_END)),
                            pd.DataFrame({"Fc": [20.0, 15.0], "sigma2": [50.0, 80.0]}),
                            executor=1).table
    for name in ("travel", "overshoot", "top_speed_out", "top_speed_in"):
        np.testing.assert_allclose(cli[name], api[name], rtol=ref.META_BATCH_RTOL,
                                   err_msg=name)


def test_sensitivity_runs_the_cylinder_and_refuses_the_actuator_s_conditions(tmp_path):
    out = tmp_path / "src"
    result = invoke("sensitivity", "src", "--model", "cylinder", "--t-end", T_END,
                    "--variations", "sigma2=20%,valve_C=10%,chamber_a.V_dead=10%", "--n", "8",
                    "--workers", "1", "--out", str(out))
    assert result.exit_code == 0, result.output
    indices = pd.read_csv(out / "indices.csv").set_index("parameter")
    assert "chamber_a.V_dead" in indices.index  # an instance's parameter, by its name
    assert set(indices["output"]) == {"top_speed_out"}  # the cylinder's default feature
    assert indices.loc["valve_C", "SRC"] > 0  # a wider valve, a faster piston
    for args, words in (
            (("--conditions", "period=2"), "--conditions varies the actuator's pressure"),
            (("--features", "loop_width_pressure"), "--features: features "
                                                    "['loop_width_pressure'] need a pressure")):
        refused = invoke("sensitivity", "sobol", "--model", "cylinder", *args,
                         "--out", str(tmp_path / "refused"))
        assert refused.exit_code != 0 and words in " ".join(refused.output.split())
        assert not (tmp_path / "refused").exists()


def test_fit_runs_the_cylinder_on_its_record(tmp_path):
    """Fc and σ2 found again from the cylinder's own record (its spool command and
    position), started from the set's values moved by --params."""
    cylinder = pa.Cylinder(load_quietly("iso15552-32"))
    spool = pa.experiments.PiecewiseLinear([0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3])
    run = pa.simulate(cylinder, pa.Experiment(spool, "spool", 0.3, n_points=301))
    record = tmp_path / "cylinder.csv"
    pa.Record.from_arrays(run.time, {"position": run["position"], "spool": run["spool"]},
                          {"position": "m", "spool": "1"}, "cylinder").save(record)
    truth = {"Fc": float(cylinder.params["Fc"]), "sigma2": float(cylinder.params["sigma2"])}
    start = cylinder.params.replace(Fc=1.3 * truth["Fc"], sigma2=0.7 * truth["sigma2"])
    start_file = tmp_path / "start.toml"
    pa.write_params(start, start_file)
    result = invoke("fit", str(record), "--model", "cylinder", "--params", str(start_file),
                    "--free", "Fc,sigma2", "--out", str(tmp_path / "fit"))
    assert result.exit_code == 0, result.output
    found = pd.read_csv(tmp_path / "fit" / "estimates.csv").set_index("parameter")["value"]
    for name, value in truth.items():
        assert found[name] == pytest.approx(value, rel=ref.META_FIT_RTOL), name


def test_fit_runs_the_two_valve_cylinder_on_the_record_simulate_writes(tmp_path):
    """``simulate --model cylinder --valves two-3/2`` driven by a CSV of both valves'
    commands (valve A's ramp, valve B's its mirror) writes a record that ``fit --model
    cylinder --valves two-3/2`` reads as it is (both commands as its inputs, from their
    columns): Fc and σ2 found again from the set's values moved by --params."""
    time = np.linspace(0.0, 0.3, 301)
    command_a = np.interp(time, [0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3])
    drive = tmp_path / "drive.csv"
    pd.DataFrame({"time [s]": time, "command_a [1]": command_a,
                  "command_b [1]": -command_a}).to_csv(drive, index=False)
    two = ("--model", "cylinder", "--valves", "two-3/2")
    result = invoke("simulate", *two, "--input-csv", str(drive), "--out",
                    str(tmp_path / "run"))
    assert result.exit_code == 0, result.output
    record = tmp_path / "run" / "simulation.csv"
    assert np.ptp(pd.read_csv(record)["position [m]"]) > 0.05, "the piston must travel"
    params = load_quietly("iso15552-32")
    truth = {"Fc": float(params["Fc"]), "sigma2": float(params["sigma2"])}
    start_file = tmp_path / "start.toml"
    pa.write_params(params.replace(Fc=1.3 * truth["Fc"], sigma2=0.7 * truth["sigma2"]),
                    start_file)
    result = invoke("fit", str(record), *two, "--params", str(start_file), "--free",
                    "Fc,sigma2", "--out", str(tmp_path / "fit"))
    assert result.exit_code == 0, result.output
    found = pd.read_csv(tmp_path / "fit" / "estimates.csv").set_index("parameter")["value"]
    for name, value in truth.items():
        assert found[name] == pytest.approx(value, rel=ref.META_FIT_RTOL), name


def test_export_fmu_writes_the_cylinder(tmp_path):
    result = invoke("export", "fmu", "--model", "cylinder", "--no-binary", "--out",
                    str(tmp_path))
    assert result.exit_code == 0, result.output
    assert (tmp_path / "cylinder.fmu").is_file()
    assert "spool_command" in result.output


def test_control_step_holds_the_cylinder_at_its_start(tmp_path):
    """--plant cylinder: the piston placed at --start (it rests on a stop wherever its
    chambers balance), then stepped; --valves two-3/2, the one command mirrored to both
    valves (``Cylinder(valves="two-3/2", mirrored=True)``), is the 5/3 loop bit for bit,
    its metrics the same, valve A driven by the command and valve B by its negative; a
    valving not there, and --valves on the actuator's loop, are refused in one line naming
    the option, the value and what is allowed, nothing written."""
    step = ("control", "step", "--plant", "cylinder", "--start", "90", "--stop", "110",
            "--kd", "0.5", "--derivative", "velocity", "--t-end", "0.5")
    runs = {}
    for valves in ("5/3", "two-3/2"):
        out = tmp_path / valves.replace("/", "_")
        result = invoke(*step, "--valves", valves, "--out", str(out))
        assert result.exit_code == 0, result.output
        runs[valves] = (pd.read_csv(out / "signals.csv"), pd.read_csv(out / "metrics.csv"))
    signals, metrics = runs["5/3"]
    position = signals["position [m]"].to_numpy()
    before = signals["time [s]"].to_numpy() < 0.1  # the step is at 0.1 s
    assert np.abs(position[before] - 0.09).max() < ref.CYLINDER_LOOP_STEP * 0.01
    assert abs(position[-1] - 0.11) < ref.CYLINDER_LOOP_BAND * ref.CYLINDER_LOOP_STEP
    two_signals, two_metrics = runs["two-3/2"]
    pd.testing.assert_frame_equal(two_metrics, metrics, check_exact=True)
    for name in ("position [m]", "velocity [m/s]", "pressure_a [Pa]", "pressure_b [Pa]",
                 "command [1]"):
        np.testing.assert_allclose(two_signals[name], signals[name], err_msg=name,
                                   rtol=ref.CYLINDER_VALVES_5_3_RTOL, atol=0.0)
    np.testing.assert_array_equal(two_signals["command_a [1]"], signals["spool [1]"])
    np.testing.assert_array_equal(two_signals["command_b [1]"], -signals["spool [1]"])
    for args, said in ((("--plant", "cylinder", "--valves", "3/3"),
                        "--valves 3/3: must be one of 5/3, two-3/2"),
                       (("--valves", "two-3/2"), "--valves two-3/2 is the cylinder's "
                                                 "valving (--plant cylinder); --plant "
                                                 "regulator has no cylinder")):
        refused = invoke("control", "step", *args, "--out", str(tmp_path / "refused"))
        assert refused.exit_code != 0 and said in " ".join(refused.output.split()), (
            refused.output)
    assert not (tmp_path / "refused").exists()


def test_control_tune_and_compare_run_the_two_valve_cylinder(tmp_path, monkeypatch):
    """--valves two-3/2 on control tune (one evaluation, no round: its gains and every
    move's metrics those of the 5/3 cylinder, exactly) and control compare (its linear
    design the API's on the 5/3 loop, the mirrored plant linearising as the 5/3 one, run
    on the nonlinear two-valve loop); each on ``Cylinder(valves="two-3/2",
    mirrored=True)``, as its report (tune) and the loop it compares on (compare) say."""
    from pneumact.cli import control
    from pneumact.control import PID, ClosedLoop, Specs, linear_design

    tune = ("control", "tune", "--plant", "cylinder", "--n-global", "0",
            "--max-evaluations", "1", "--rounds", "0", "--workers", "1")
    tuned = {}
    for valves in ("5/3", "two-3/2"):
        out = tmp_path / f"tune_{valves.replace('/', '_')}"
        result = invoke(*tune, "--valves", valves, "--out", str(out))
        # one evaluation does not meet the default specs: exit 3, the files written
        assert result.exit_code == 3, result.output
        tuned[valves] = [pd.read_csv(out / name) for name in ("gains.csv", "metrics.csv")]
    for two, five in zip(tuned["two-3/2"], tuned["5/3"], strict=True):
        pd.testing.assert_frame_equal(two, five, check_exact=True)
    report = (tmp_path / "tune_two-3_2" / "report.html").read_text(encoding="utf-8")
    assert "valves=&#39;two-3/2&#39;, mirrored=True" in report
    plants = []

    def compare(loop, *args):
        plants.append(loop.plant)
        return original(loop, *args)

    original = control._compare
    monkeypatch.setattr(control, "_compare", compare)
    out = tmp_path / "compare"
    result = invoke("control", "compare", "--plant", "cylinder", "--valves", "two-3/2",
                    "--out", str(out))
    assert result.exit_code == 0, result.output
    assert [(p.valves, p.mirrored) for p in plants] == [("two-3/2", True)]
    summary = pd.read_csv(out / "summary.csv")  # a valve command: no static force map,
    # so the linear PID alone (friction_designs), on the four reference moves
    assert list(summary["design"]) == ["linear (python-control)"]
    assert list(summary["moves"]) == [4]
    gains = pd.read_csv(out / "linear_gains.csv").set_index("gain")["value"]
    params = load_quietly("iso15552-32")
    at = 0.5 * float(params["x_max"])  # the default operating point: mid-stroke
    pid = PID(kp=60.0, ki=300.0, u_min=-1.0, u_max=1.0)
    five = pa.Cylinder(params)
    loop = ClosedLoop(five, pid, bias=ClosedLoop(five, pid).holding_input(at))
    design = linear_design(loop, Specs.parse("settling=0.3,overshoot=5%,error=20um,"
                                             "no-hunting"), at=at).controller
    for name in ("kp", "ki", "kd", "filter_time"):
        assert gains[name] == getattr(design, name), name


@pytest.mark.parametrize(("command", "words"), [
    (("simulate",), "this command models the diaphragm actuator"),
    (("campaign", "--plan"), "the paper's identification is the diaphragm's"),
])
def test_a_cylinder_s_set_on_a_diaphragm_command_is_refused(tmp_path, command, words):
    """One line naming the set, why, and where the cylinder runs instead."""
    result = invoke(*command, "--params", "iso15552-32", "--out", str(tmp_path / "out"))
    said = " ".join(result.output.split())
    assert result.exit_code != 0 and said.count("error:") == 1, said
    assert "--params iso15552-32: a double-acting cylinder's set" in said and words in said
    assert "--model cylinder" in said and not (tmp_path / "out").exists()


def test_simulate_drives_the_cylinder_from_a_csv_of_spool_and_load(tmp_path):
    """--input-csv with time, spool and 'load [kN]': the run of the API's PiecewiseLinear
    spool and load in N (the CLI runs in chunks for its progress: rtol apart); a file
    without a spool column or with a load beyond 1 MN is refused in one line, nothing
    written."""
    time = np.array([0.0, 0.1, 0.12, 0.3, 0.31, 0.6])
    spool = np.array([-1.0, -1.0, 0.5, 0.5, 0.5, 0.5])
    load_kn = np.array([0.0, 0.0, 0.0, 0.0, 0.25, 0.25])
    drive = tmp_path / "drive.csv"
    pd.DataFrame({"time [s]": time, "spool [1]": spool, "load [kN]": load_kn}).to_csv(
        drive, index=False)
    out = tmp_path / "out"
    result = invoke("simulate", "--model", "cylinder", "--input-csv", str(drive), "--out",
                    str(out))
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(out / "simulation.csv")
    api = pa.simulate(pa.Cylinder(load_quietly("iso15552-32")), pa.Experiment(
        PiecewiseLinear(time, spool), "spool", 0.6, 0.0, time.size,
        drives={"load": PiecewiseLinear(time, 1e3 * load_kn)}))
    np.testing.assert_array_equal(frame["load [N]"], api["load"])
    for name, unit in (("position", "m"), ("pressure_a", "Pa"), ("pressure_b", "Pa")):
        cli = frame[f"{name} [{unit}]"].to_numpy()
        assert np.abs(cli - api[name]).max() <= ref.CLI_CHUNKED_RUN_RTOL * np.ptp(api[name])
    for columns, said in (({"command [1]": np.abs(spool)}, "has no spool column (columns: "
                                                           "time, command)"),
                          ({"spool [1]": spool, "load [kN]": 8e3 * load_kn},
                           "its load force spans 0 to 2e+06")):
        bad = tmp_path / "bad.csv"
        pd.DataFrame({"time [s]": time, **columns}).to_csv(bad, index=False)
        refused = invoke("simulate", "--model", "cylinder", "--input-csv", str(bad), "--out",
                         str(tmp_path / "refused"))
        assert refused.exit_code != 0 and said in refused.output, refused.output
        assert not (tmp_path / "refused").exists()


def test_simulate_loads_the_cylinder_with_a_load_step(tmp_path):
    """--load-step 300,0.3: the API's run of ``Cylinder(load=Step(0.3, 0, 300))`` (rtol
    apart: the CLI runs in chunks); a force beyond 1 MN, a time outside the run and a load
    column beside it are refused in one line, nothing written; on the actuator the force
    is checked against its own load input (test_cli_actuator_load.py runs it)."""
    out = tmp_path / "out"
    result = invoke("simulate", "--model", "cylinder", "--load-step", "300,0.3", "--t-end",
                    "0.6", "--out", str(out))
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(out / "simulation.csv")
    api = pa.simulate(pa.Cylinder(load_quietly("iso15552-32"), load=Step(0.3, 0.0, 300.0)),
                      SpoolStep(t_end=0.6))
    np.testing.assert_array_equal(frame["load [N]"], api["load"])
    for name, unit in (("position", "m"), ("pressure_a", "Pa"), ("pressure_b", "Pa")):
        cli = frame[f"{name} [{unit}]"].to_numpy()
        assert np.abs(cli - api[name]).max() <= ref.CLI_CHUNKED_RUN_RTOL * np.ptp(api[name])
    drive = tmp_path / "drive.csv"
    drive.write_text("time [s],spool [1],load [N]\n0,0.5,0\n0.5,0.5,10\n")
    for args, said in ((["--load-step", "3e6,0.3"], "its load force spans 0 to 3e+06"),
                       (["--load-step", "300,2"], "--load-step TIME = 2 s: must be in (0, 1)"),
                       (["--load-step", "300"], "give FORCE,TIME"),
                       (["--load-step", "300,0.2", "--input-csv", str(drive)],
                        "both drive the load; drop one")):
        refused = invoke("simulate", "--model", "cylinder", *args, "--out",
                         str(tmp_path / "refused"))
        assert refused.exit_code != 0 and said in refused.output, refused.output
    refused = invoke("simulate", "--load-step", "3e6,0.2", "--out", str(tmp_path / "refused"))
    said = " ".join(refused.output.split())
    assert refused.exit_code != 0 and "a load force on a diaphragm actuator must stay within "\
        "[-1e+06, 1e+06] N" in said, said  # the actuator's own load input
    assert not (tmp_path / "refused").exists()


def test_control_step_rejects_a_load_step_on_the_held_cylinder(tmp_path):
    """--load-step 150,0.3 with --start = --stop: the loop's load-disturbance rejection, the
    API's run of ``ClosedLoop(Cylinder(load=Step(0.3, 0, 150)), PID(...))`` held at its
    start (the step rtol apart: the CLI runs in chunks); the piston held exactly until the
    load, pushed back by it, then brought back by the integral."""
    from pneumact.control import PID, ClosedLoop
    from pneumact.control.study import run_loop
    from pneumact.experiments import SetpointStep

    result = invoke("control", "step", "--plant", "cylinder", "--start", "100", "--stop",
                    "100", "--kd", "0.5", "--derivative", "velocity", "--load-step",
                    "150,0.3", "--t-end", "1", "--out", str(tmp_path))
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(tmp_path / "signals.csv")
    load = Step(0.3, 0.0, 150.0)
    plant = pa.Cylinder(load_quietly("iso15552-32"), load=load)
    pid = PID(kp=60.0, ki=300.0, kd=0.5, derivative="velocity", u_min=-1.0, u_max=1.0)
    loop = ClosedLoop(plant, pid, bias=ClosedLoop(plant, pid).holding_input(0.1))
    api = run_loop(loop, SetpointStep(0.1, 0.1, 0.1, 1.0), y0={"position": 0.1}).result
    np.testing.assert_array_equal(frame["load [N]"], api["load"])
    position = frame["position [m]"].to_numpy()
    assert np.abs(position - api["position"]).max() <= (ref.CLI_CHUNKED_RUN_RTOL
                                                        * np.ptp(api["position"]))
    before = frame["time [s]"].to_numpy() < 0.3
    assert np.abs(position[before] - 0.1).max() < ref.CYLINDER_LOAD_REST_ATOL
    assert position.min() < 0.1 - ref.CYLINDER_LOAD_ACTS_MIN
    assert abs(position[-1] - 0.1) < ref.CYLINDER_LOAD_ACTS_MIN


def test_the_load_step_of_control_is_refused_as_simulate_refuses_it(tmp_path):
    """The same parser and messages as ``simulate --load-step``; on the rig, which has no
    load input, it names the plants that have one; nothing written."""
    profile = tmp_path / "profile.csv"
    profile.write_text("time [s],reference [mm]\n0,90\n0.5,110\n", encoding="utf-8")
    cylinder = ["--plant", "cylinder"]
    for args, said in (
            (["step", *cylinder, "--load-step", "3e6,0.3"], "its load force spans 0 to 3e+06"),
            (["step", *cylinder, "--load-step", "150,2"],
             "--load-step TIME = 2 s: must be in (0, 1)"),
            (["step", *cylinder, "--load-step", "150"], "give FORCE,TIME"),
            (["step", "--plant", "rig", "--load-step", "150,0.3"],
             "give --plant cylinder, regulator, command or source"),
            (["step", *cylinder, "--start", "90", "--stop", "90"], "or a --load-step"),
            (["profile", str(profile), "--plant", "rig", "--load-step", "150,0.3"],
             "give --plant cylinder, regulator, command or source"),
            (["profile", str(profile), *cylinder, "--load-step", "150,0.5"],
             "--load-step TIME = 0.5 s: must be in (0, 0.5)")):
        refused = invoke("control", *args, "--out", str(tmp_path / "refused"))
        assert refused.exit_code != 0 and said in " ".join(refused.output.split()), (
            args, refused.output)
    assert not (tmp_path / "refused").exists()


def test_simulate_batch_and_sensitivity_load_the_cylinder_with_a_load_step(tmp_path):
    """--load-step on the batch: each row the API's batch of the loaded cylinder (slower
    out than without the load); on the actuator, its force checked against the
    actuator's own load input; with sensitivity's --conditions (which vary the pressure
    cycle under a load fixed in time) refused; one line each, nothing written."""
    table = tmp_path / "table.csv"
    table.write_text("Fc,sigma2\n20,50\n15,80\n", encoding="utf-8")
    result = invoke("simulate-batch", str(table), "--model", "cylinder", "--t-end", T_END,
                    "--load-step", "300,0.15", "--workers", "1", "--out",
                    str(tmp_path / "batch"))
    assert result.exit_code == 0, result.output
    cli = pd.read_parquet(tmp_path / "batch" / "results.parquet")
    sets = pd.DataFrame({"Fc": [20.0, 15.0], "sigma2": [50.0, 80.0]})
    loaded = pa.Cylinder(load_quietly("iso15552-32"), load=Step(0.15, 0.0, 300.0))
    api = pa.simulate_batch(loaded, SpoolStep(t_end=float(T_END)), sets, executor=1).table
    free = pa.simulate_batch(pa.Cylinder(load_quietly("iso15552-32")),
                             SpoolStep(t_end=float(T_END)), sets, executor=1).table
    for name in ("travel", "top_speed_out"):
        np.testing.assert_allclose(cli[name], api[name], rtol=ref.META_BATCH_RTOL,
                                   err_msg=name)
    assert (api["top_speed_out"] < free["top_speed_out"]).all()  # the load slows the rod
    for command, said in (
            (["simulate-batch", str(table), "--load-step", "3e6,0.2"],
             "a load force on a diaphragm actuator must stay within"),
            (["sensitivity", "src", "--load-step", "3e6,0.2"],
             "a load force on a diaphragm actuator must stay within"),
            (["sensitivity", "src", "--t-end", "2", "--conditions", "period=1,2",
              "--load-step", "5,0.5"], "--load-step 5,0.5 with --conditions")):
        refused = invoke(*command, "--out", str(tmp_path / "refused"))
        flat = " ".join(refused.output.split())
        assert refused.exit_code != 0 and said in flat, flat
    assert not (tmp_path / "refused").exists()


def _read_run(folder) -> pd.DataFrame:
    """simulation.csv with its columns named without units."""
    frame = pd.read_csv(folder / "simulation.csv")
    return frame.rename(columns=lambda column: column.split(" [")[0])


def test_simulate_runs_the_cylinder_on_two_3_2_valves(tmp_path):
    """--valves two-3/2: command_a steps as the spool does and command_b mirrors it; the
    shipped set's two 3/2 valves are the 5/3 valve's paths, so the run is the 5/3 run bit
    for bit, and the API's two-valve run; a valving not there, and --valves on the
    actuator, are refused in one line naming the option, the value and the choices."""
    t_end = 0.3
    five, two = tmp_path / "five", tmp_path / "two"
    for folder, valves in ((five, "5/3"), (two, "two-3/2")):
        result = invoke("simulate", "--model", "cylinder", "--valves", valves, "--t-end",
                        str(t_end), "--out", str(folder))
        assert result.exit_code == 0, result.output
    cli_five, cli_two = _read_run(five), _read_run(two)
    assert np.ptp(cli_two["position"]) > 0.1, "the piston must travel for this to bite"
    np.testing.assert_array_equal(cli_two["command_a"], cli_five["spool"])
    np.testing.assert_array_equal(cli_two["command_b"], -cli_five["spool"])
    step = Step(0.1, -1.0, 0.5)
    api = pa.simulate(pa.Cylinder(load_quietly("iso15552-32"), valves="two-3/2"),
                      pa.Experiment(step, "command_a", t_end,
                                    drives={"command_b": Step(0.1, 1.0, -0.5)}))
    for name in ("position", "velocity", "pressure_a", "pressure_b"):
        np.testing.assert_allclose(cli_two[name], cli_five[name], err_msg=name,
                                   rtol=ref.CYLINDER_VALVES_5_3_RTOL, atol=0.0)
        scale = np.ptp(api[name])
        assert np.abs(cli_two[name] - api[name]).max() <= ref.CLI_CHUNKED_RUN_RTOL * scale
    for args, said in ((("--model", "cylinder", "--valves", "3/3"),
                        "--valves 3/3: must be one of 5/3, two-3/2"),
                       (("--valves", "two-3/2"), "--valves two-3/2 is the cylinder's")):
        refused = invoke("simulate", *args, "--out", str(tmp_path / "refused"))
        assert refused.exit_code != 0 and said in " ".join(refused.output.split()), (
            refused.output)
        assert not (tmp_path / "refused").exists()
