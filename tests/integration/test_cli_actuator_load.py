"""``--load-step FORCE,TIME`` on the diaphragm actuator (issue 41, item 5): ``simulate``
and the control commands load it as they load the cylinder, with the actuator's own load
input (``models.actuator.LOAD_INPUT``: a force against larger x, as its spring's; within
±1 MN) and its sign convention: a positive force moves its rest by −F/k.

Known answers: open loop at a constant pressure, a load step moves the diaphragm by −F/k
to within the band of rest positions friction allows (±Fs/k), as ``pa.simulate`` runs
``Actuator(load=Step(...))``; in the pressure-regulator loop the load pushes it back
towards smaller x and the integral brings it back to the set-point."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import pneumact as pa
import reference as ref
from pneumact.cli import app
from pneumact.core.signals import Constant, Step

pytestmark = pytest.mark.integration

runner = CliRunner()
#: a constant absolute pressure that holds vgt-paper mid-stroke [Pa] (as
#: test_actuator.py's load step: the same loaded kernel)
MID_STROKE_PRESSURE = 60e3
LOAD, T_LOAD, T_END = 60.0, 0.5, 2.0  # N (about 20 Fs), s, s
#: the actuator's load input's message for a force beyond it
BEYOND = "a load force on a diaphragm actuator must stay within [-1e+06, 1e+06] N"


def invoke(*args: str):
    result = runner.invoke(app, list(args))
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


def test_simulate_moves_the_actuator_by_the_load_over_its_spring_rate(tmp_path, vgt):
    """A constant 60 kPa (--input-csv) and --load-step 60,0.5: the run of
    ``Actuator(load=Step(0.5, 0, 60))`` (rtol apart: the CLI runs in chunks), held still
    until the load, then moved towards smaller x by F/k to within ±Fs/k (friction holds
    the rest of it) and at rest there; a force beyond 1 MN is refused naming the option,
    the value and the actuator's range, nothing written."""
    time = np.linspace(0.0, T_END, 201)
    drive = tmp_path / "drive.csv"
    pd.DataFrame({"time [s]": time, "pressure [kPa]": np.full_like(time, 60.0)}).to_csv(
        drive, index=False)
    out = tmp_path / "out"
    result = invoke("simulate", "--input-csv", str(drive), "--load-step",
                    f"{LOAD:g},{T_LOAD:g}", "--out", str(out))
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(out / "simulation.csv")
    api = pa.simulate(pa.Actuator(vgt, load=Step(T_LOAD, 0.0, LOAD)),
                      pa.Experiment(Constant(MID_STROKE_PRESSURE), "pressure", T_END,
                                    n_points=time.size), t_eval=time)
    np.testing.assert_array_equal(frame["load [N]"], api["load"])
    position = frame["position [m]"].to_numpy()
    assert np.abs(position - api["position"]).max() <= (ref.CLI_CHUNKED_RUN_RTOL
                                                        * np.ptp(api["position"]))
    before = time < T_LOAD
    assert np.ptp(position[before]) <= ref.EQUILIBRIUM_DRIFT_POSITION
    shift = position[-1] - position[0]
    k, fs = float(vgt["k"]), float(vgt["Fs"])
    assert shift < -0.5 * LOAD / k  # it moved, towards smaller x
    assert abs(shift + LOAD / k) <= fs / k
    assert abs(position[-1] - position[-20]) <= ref.EQUILIBRIUM_DRIFT_POSITION  # at rest
    refused = invoke("simulate", "--input-csv", str(drive), "--load-step", "3e6,0.5",
                     "--out", str(tmp_path / "refused"))
    said = " ".join(refused.output.split())
    assert refused.exit_code != 0 and "--load-step 3e6,0.5" in said and BEYOND in said, said
    assert not (tmp_path / "refused").exists()


def test_control_step_rejects_a_load_step_on_the_held_actuator(tmp_path, vgt):
    """--plant regulator, --start = --stop = 6 mm, --load-step 20,0.3: the diaphragm held
    exactly until the load, pushed towards smaller x by it (a good share of F/k: the
    regulator's loop pushes back only as fast as it moves the pressure), then brought
    back to the set-point by the integral; the load column is the step. A force beyond the
    actuator's load input is refused naming its range, nothing written."""
    load, t_load, start = 20.0, 0.3, 6e-3
    result = invoke("control", "step", "--start", "6", "--stop", "6", "--load-step",
                    f"{load:g},{t_load:g}", "--t-end", "1", "--out", str(tmp_path / "out"))
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(tmp_path / "out" / "signals.csv")
    time, position = frame["time [s]"].to_numpy(), frame["position [m]"].to_numpy()
    away = np.abs(time - t_load) > 1e-9  # at the step itself a run writes either side
    np.testing.assert_array_equal(frame["load [N]"][away], np.where(time < t_load, 0.0,
                                                                     load)[away])
    assert np.abs(position[time < t_load] - start).max() <= ref.EQUILIBRIUM_DRIFT_POSITION
    push = start - position.min()
    assert push > ref.ACTUATOR_LOOP_LOAD_PUSH_SHARE * load / float(vgt["k"])
    assert abs(position[-1] - start) < ref.ACTUATOR_LOOP_LOAD_RETURN_SHARE * push
    refused = invoke("control", "step", "--start", "6", "--stop", "6", "--load-step",
                     "3e6,0.3", "--out", str(tmp_path / "refused"))
    said = " ".join(refused.output.split())
    assert refused.exit_code != 0 and BEYOND in said, said
    assert not (tmp_path / "refused").exists()
