"""The diaphragm actuator's external force as a declared input (issue 41, item 2): built
with ``load=LOAD_INPUT`` it declares ``load`` beside its valve's drive, an experiment
drives it by name (``Experiment(..., drives={"load": signal})``) and a record's ``load``
column drives it; built without, it declares only its valve's input and its kernel is the
load-free one of the paper's actuator.

Known answers: a constant load F on the actuator at rest moves its equilibrium by −F/k
(the load opposes motion towards larger x, as the spring does) and the run is the one of
the same load held as ``Actuator(load=...)`` bit for bit; the batch engine runs the load
as ``simulate`` does; a record of a run drives the same run again. Names or values the
declarations do not allow are refused naming them.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
from pneumact.core import codegen
from pneumact.core.assembly import assemble
from pneumact.core.channels import CHANNELS
from pneumact.core.signals import Constant, PiecewiseLinear, Step
from pneumact.experiments import Experiment
from pneumact.identification import experiment_for
from pneumact.io.records import Record
from pneumact.models.actuator import LOAD_INPUT
from pneumact.models.cylinder import LOAD_INPUT as CYLINDER_LOAD_INPUT
from pneumact.models.valves import PRESSURE_INPUT
from pneumact.simulation import Rodas4
from pneumact.simulation.simulate import check_drive
from reference import (
    ACTUATOR_RECORD_DRIVE_ATOL,
    EQUILIBRIUM_DRIFT_POSITION,
    LOAD_SHIFT_RTOL,
    TIGHT_RTOL,
)

pytestmark = pytest.mark.integration

SOLVER = Rodas4(rtol=TIGHT_RTOL)
#: a constant absolute pressure that holds the paper's actuator mid-stroke [Pa]
MID_STROKE_PRESSURE = 60e3
#: a constant load against larger x [N] (about 3 Fs: the shift is 0.8 mm of 20 mm)
LOAD = 10.0
#: outputs a loaded run writes, compared bit for bit
COMPARED = ("position", "velocity", "pressure", "load", "friction")


def _at_rest(drives=None) -> Experiment:
    return Experiment(Constant(MID_STROKE_PRESSURE), PRESSURE_INPUT.name, t_end=2.0,
                      n_points=201, name="probe", drives=drives or {})


def test_a_constant_load_input_moves_the_rest_by_load_over_stiffness(vgt):
    """``drives={"load": F}`` on an actuator declaring its load: the rest position is
    −F/k from the load-free one (towards smaller x) and stays there, and the run is the
    one of the same load held (``load=Constant(F)``) bit for bit."""
    driven = pa.simulate(pa.Actuator(vgt, load=LOAD_INPUT),
                         _at_rest({LOAD_INPUT.name: Constant(LOAD)}), SOLVER)
    held = pa.simulate(pa.Actuator(vgt, load=Constant(LOAD)), _at_rest(), SOLVER)
    free = pa.simulate(pa.Actuator(vgt), _at_rest(), SOLVER)
    shift = driven["position"][0] - free["position"][0]
    assert shift < 0.0
    assert shift == pytest.approx(-LOAD / vgt["k"], rel=LOAD_SHIFT_RTOL)
    assert np.ptp(driven["position"]) <= EQUILIBRIUM_DRIFT_POSITION
    for name in COMPARED:
        assert np.array_equal(driven[name], held[name]), name
    assert np.all(driven["load"] == LOAD)


def test_the_load_is_declared_only_when_asked_for(vgt):
    """The default actuator declares its valve's input alone and keeps its load-free
    kernel; ``load=LOAD_INPUT`` declares the load after it, on the load-against-time
    channel, and shares the kernel of any loaded actuator (so a driven load runs as a held
    one); an undriven load input is zero."""
    default, declared = pa.Actuator(vgt), pa.Actuator(vgt, load=LOAD_INPUT)
    assert default.inputs() == (default.drive_input,)
    assert default.kernel_constants() == {"HAS_LOAD": False}
    assert declared.inputs() == (declared.drive_input, LOAD_INPUT)
    assert declared.drive_input == default.drive_input

    def key(model):
        return codegen.kernel_key(assemble(model).kernel_spec())

    assert key(declared) == key(pa.Actuator(vgt, load=Constant(LOAD))) != key(default)
    drive, load = Constant(MID_STROKE_PRESSURE), Constant(LOAD)
    channels = declared.channels(drive, {LOAD_INPUT.name: load})
    assert channels[CHANNELS.index(LOAD_INPUT.channel)] is load
    undriven = declared.channels(drive)[CHANNELS.index(LOAD_INPUT.channel)]
    assert np.all(undriven(np.array([0.0, 1.0, 1e3])) == 0.0)
    assert default.channels(drive)[CHANNELS.index(LOAD_INPUT.channel)] is None


def test_a_batch_drives_the_load_as_a_run_does(vgt):
    """The batch engine runs an experiment's load as ``simulate`` does: the position and
    load signals of a row are the run's bit for bit."""
    model = pa.Actuator(vgt, load=LOAD_INPUT)
    experiment = _at_rest({LOAD_INPUT.name: Step(0.5, 0.0, 6.0 * LOAD)})
    rows = pd.DataFrame({"Fc": [vgt["Fc"]]})
    batch = pa.simulate_batch(model, experiment, rows, signals=["position", "load"],
                           solver=SOLVER, executor=1)
    run = pa.simulate(model, experiment, SOLVER)
    for name in ("position", "load"):
        assert np.array_equal(batch.signals[name][0], run[name]), name
    assert run["position"][-1] < run["position"][0]  # the load pushed it back


def test_a_record_with_a_load_column_drives_the_load(vgt):
    """A run's record (pressure, load, position) simulated against again through
    ``experiment_for`` (as ``fit`` and ``validate`` do) drives both inputs from the record
    and repeats the run; the default actuator, which declares no load, ignores the
    column."""
    t_knots = np.array([0.0, 0.5, 0.6, 1.2, 1.3, 2.0])
    pressure = PiecewiseLinear(t_knots, [60e3, 60e3, 50e3, 50e3, 50e3, 50e3])
    load = PiecewiseLinear(t_knots, [0.0, 0.0, 0.0, 0.0, 60.0, 60.0])
    model = pa.Actuator(vgt, load=LOAD_INPUT)
    experiment = Experiment(pressure, PRESSURE_INPUT.name, 2.0, n_points=201,
                            drives={LOAD_INPUT.name: load})
    run = pa.simulate(model, experiment, SOLVER)
    record = Record.from_arrays(run.time, {name: run[name] for name in
                                           ("pressure", "load", "position")},
                                {"pressure": "Pa", "load": "N", "position": "m"})
    again_experiment = experiment_for(model, record)
    assert set(again_experiment.drives) == {LOAD_INPUT.name}
    again = pa.simulate(model, again_experiment, SOLVER, t_eval=record.time)
    assert np.array_equal(again["load"], run["load"])
    np.testing.assert_allclose(again["position"], run["position"], rtol=0,
                               atol=ACTUATOR_RECORD_DRIVE_ATOL)
    assert experiment_for(pa.Actuator(vgt), record).drives == {}


def test_a_csv_with_a_load_column_drives_the_declared_load(vgt, tmp_path):
    """``from_csv(path, model=actuator)``: an actuator declaring its load reads the
    ``load`` column (kN converted to N by its name), one without ignores it."""
    time = np.array([0.0, 0.5, 1.0])
    path = tmp_path / "drive.csv"
    pd.DataFrame({"time [s]": time, "pressure [kPa]": [60.0, 55.0, 50.0],
                  "load [kN]": [0.0, 0.01, 0.02]}).to_csv(path, index=False)
    loaded = pa.experiments.from_csv(path, model=pa.Actuator(vgt, load=LOAD_INPUT))
    assert loaded.quantity == PRESSURE_INPUT.name and set(loaded.drives) == {"load"}
    np.testing.assert_array_equal(loaded.drives["load"](time), [0.0, 10.0, 20.0])
    assert pa.experiments.from_csv(path, model=pa.Actuator(vgt)).drives == {}


@pytest.mark.parametrize(("load", "message"), [
    (None, r"experiment 'probe' drives 'load', but this Actuator declares no load input "
           r"\(its declared inputs: 'pressure' \[Pa\] in \[1000, 1e\+07\]\); it is built "
           r"without one: give load=LOAD_INPUT \(pneumact.models.actuator\) to drive the "
           r"input 'load' \[N\] in \[-1e\+06, 1e\+06\]"),
    (Constant(5.0), r"drives 'load', but this Actuator declares no load input .*it holds "
                    r"its load \(load = Constant\(terms=1\)\): give load=LOAD_INPUT "
                    r"instead"),
], ids=["without-load", "holding-its-load"])
def test_a_load_the_actuator_does_not_declare_is_refused(load, message, vgt):
    with pytest.raises(pa.ExperimentError, match=message):
        check_drive(pa.Actuator(vgt, load=load), _at_rest({"load": Constant(LOAD)}))


def test_a_load_out_of_range_and_a_foreign_input_are_refused(vgt):
    """A load beyond 1 MN (a force in mN or kN mistaken for N) is refused naming the
    experiment, the values and the range; the cylinder's load input is no actuator's."""
    with pytest.raises(pa.ExperimentError, match=r"experiment 'probe': its load force spans "
                                                 r"0 to 2e\+06; a load force on a diaphragm "
                                                 r"actuator must stay within \[-1e\+06, "
                                                 r"1e\+06\] N"):
        check_drive(pa.Actuator(vgt, load=LOAD_INPUT),
                    _at_rest({"load": Step(0.5, 0.0, 2e6)}))
    with pytest.raises(pa.ArgumentError, match=r"Actuator: load = the input 'load' \[N\] .*"
                                               r"\(external force on the rod, against "
                                               r"extension\): .*give that, a Signal the "
                                               r"actuator holds, or None"):
        pa.Actuator(vgt, load=CYLINDER_LOAD_INPUT)
    with pytest.raises(pa.ArgumentTypeError, match=r"load = 3.*LOAD_INPUT"):
        pa.Actuator(vgt, load=3.0)


def test_a_closed_loop_and_the_fmu_take_the_declared_load(vgt):
    """A position loop around an actuator declaring its load declares it beside its
    set-point; the FMU takes it as its external force input (only a held load is
    refused there)."""
    from pneumact.control import PID, ClosedLoop

    loop = ClosedLoop(pa.Actuator(vgt, valve=pa.CommandValve(), load=LOAD_INPUT),
                      PID(kp=50.0, u_min=0.0, u_max=1.0))
    assert loop.inputs()[1] == LOAD_INPUT
    form = pa.Actuator(vgt, load=LOAD_INPUT).fmu_form()
    assert form.held_load is not None and form.held_load(np.array([0.0]))[0] == 0.0
    with pytest.raises(pa.ArgumentError, match="drive the input 'external_force'"):
        pa.Actuator(vgt, load=Constant(1.0)).fmu_form()


def test_a_linearisation_holds_the_declared_load_as_the_held_one(vgt):
    """``linearise(actuator, p, inputs={"load": F})`` on an actuator declaring its load is
    the linearisation of the actuator holding F, bit for bit; refused on one without."""
    from pneumact.control import linearise

    driven = linearise(pa.Actuator(vgt, load=LOAD_INPUT), MID_STROKE_PRESSURE,
                       inputs={LOAD_INPUT.name: LOAD})
    held = linearise(pa.Actuator(vgt, load=Constant(LOAD)), MID_STROKE_PRESSURE)
    assert np.array_equal(driven.A, held.A) and np.array_equal(driven.B, held.B)
    free = linearise(pa.Actuator(vgt), MID_STROKE_PRESSURE)
    shift = driven.operating_point["position"] - free.operating_point["position"]
    assert shift == pytest.approx(-LOAD / vgt["k"], rel=LOAD_SHIFT_RTOL)
    with pytest.raises(pa.ExperimentError, match=r"declares no input 'load' beside its "
                                                 r"drive; allowed: none"):
        linearise(pa.Actuator(vgt), MID_STROKE_PRESSURE, inputs={LOAD_INPUT.name: LOAD})
