"""Several inputs per model (issue 41, item 2): the cylinder declares its spool command and
its load force; an experiment drives the first by its quantity and the second by name
(``Experiment(..., drives={"load": signal})``), a record's ``load`` column drives it when
the cylinder is simulated against the record, and each input reaches the channel its
declaration names.

Known answers: the load driven as an input gives the run of the same load held by the
cylinder (``Cylinder(load=...)``) bit for bit; each input, driven at once, is what the run
writes back (its ``spool`` and ``load`` outputs); a record of a run drives the same run
again. Names or values the declarations do not allow are refused naming them.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import pneumact as pa
from conftest import load_quietly
from pneumact.core.signals import Constant, PiecewiseLinear, Step
from pneumact.experiments import Experiment, SpoolStep
from pneumact.identification import experiment_for
from pneumact.io.records import Record
from pneumact.models.cylinder import LOAD_INPUT, SPOOL_INPUT, SUPPLY_INPUT
from pneumact.simulation import Rodas4
from pneumact.simulation.simulate import check_drive
from reference import (
    CYLINDER_INPUT_ECHO_ATOL,
    CYLINDER_LOAD_ACTS_MIN,
    CYLINDER_LOOP_LOAD_RETURN_ATOL,
    CYLINDER_RECORD_DRIVE_ATOL,
    CYLINDER_RTOL,
)

pytestmark = pytest.mark.integration

SOLVER = Rodas4(rtol=CYLINDER_RTOL)
#: a load stepping against extension while the rod extends at half opening [N]
LOAD_STEP = Step(0.15, 0.0, 250.0)


@pytest.fixture(scope="module")
def cylinder_set():
    return load_quietly("iso15552-32")


def _loaded(experiment: Experiment, load) -> Experiment:
    """``experiment`` with the cylinder's load driven by name."""
    return Experiment(experiment.drive, experiment.quantity, experiment.t_end,
                      n_points=experiment.n_points, name="loaded", drives={"load": load})


def test_a_load_driven_as_an_input_runs_as_the_load_the_cylinder_holds(cylinder_set):
    """The same load step, as the experiment's input ``load`` or as the cylinder's
    ``load=``, gives the same trajectory bit for bit; and the load acts (the run without
    it differs)."""
    spool = SpoolStep(n_points=401)
    driven = pa.simulate(pa.Cylinder(cylinder_set), _loaded(spool, LOAD_STEP), SOLVER)
    held = pa.simulate(pa.Cylinder(cylinder_set, load=LOAD_STEP), spool, SOLVER)
    free = pa.simulate(pa.Cylinder(cylinder_set), spool, SOLVER)
    for name in ("position", "velocity", "pressure_a", "pressure_b", "load", "spool"):
        assert np.array_equal(driven[name], held[name]), name
    assert np.max(np.abs(driven["position"] - free["position"])) > CYLINDER_LOAD_ACTS_MIN


def test_both_inputs_driven_at_once_reach_their_channels(cylinder_set):
    """A spool command and a load force stepping at different times, driven together: the
    run's ``spool`` (the unlagged spool is the command) and ``load`` outputs are the two
    signals at every output time (constant between the steps, where the integrator
    stops: its interpolation between steps is then exact)."""
    spool, load = Step(0.2025, -0.4, 0.7), Step(0.6025, 20.0, 180.0)  # between samples
    experiment = Experiment(spool, SPOOL_INPUT.name, 1.0, n_points=201,
                            drives={LOAD_INPUT.name: load})
    run = pa.simulate(pa.Cylinder(cylinder_set), experiment, SOLVER)
    np.testing.assert_allclose(run["spool"], spool(run.time), rtol=0,
                               atol=CYLINDER_INPUT_ECHO_ATOL)
    np.testing.assert_allclose(run["load"], load(run.time), rtol=0,
                               atol=CYLINDER_INPUT_ECHO_ATOL * 1e3)


def test_each_declared_input_is_routed_to_its_channel(cylinder_set):
    """``channels`` puts the drive on the spool's channel and ``drives`` on the load's, a
    held load where no experiment drives one, zero on a free cylinder."""
    spool, load = Constant(0.3), Constant(80.0)
    free = pa.Cylinder(cylinder_set)
    layout = free.channel_names
    channels = free.channels(spool, {"load": load})
    assert channels[layout.index(SPOOL_INPUT.channel)] is spool
    assert channels[layout.index(LOAD_INPUT.channel)] is load
    held = pa.Cylinder(cylinder_set, load=load).channels(spool)
    assert held[layout.index(LOAD_INPUT.channel)] is load
    supply = replace(SUPPLY_INPUT, low=cylinder_set["p_atm"])
    assert free.inputs() == (SPOOL_INPUT, LOAD_INPUT, supply)
    assert pa.Cylinder(cylinder_set, load=load).inputs() == (SPOOL_INPUT, supply)


def test_a_record_with_a_load_column_drives_the_load(cylinder_set):
    """A run's record (spool, load, position) simulated against again through
    ``experiment_for`` (as ``fit`` and ``validate`` do) drives both inputs from the record
    and repeats the run; a cylinder holding its load keeps it."""
    t_knots = np.array([0.0, 0.1, 0.11, 0.5, 0.6, 1.0])
    spool = PiecewiseLinear(t_knots, [-1.0, -1.0, 0.5, 0.5, 0.5, 0.5])
    load = PiecewiseLinear(t_knots, [0.0, 0.0, 0.0, 0.0, 200.0, 200.0])
    experiment = Experiment(spool, SPOOL_INPUT.name, 1.0, n_points=201, drives={"load": load})
    model = pa.Cylinder(cylinder_set)
    run = pa.simulate(model, experiment, SOLVER)
    record = Record.from_arrays(run.time, {name: run[name] for name in
                                           ("spool", "load", "position")},
                                {"spool": "1", "load": "N", "position": "m"})
    for smooth in (False, True):
        again_experiment = experiment_for(model, record, smooth=smooth)
        assert set(again_experiment.drives) == {"load"}
        again = pa.simulate(model, again_experiment, SOLVER, t_eval=record.time)
        np.testing.assert_allclose(again["load"], run["load"], rtol=0,
                                   atol=CYLINDER_INPUT_ECHO_ATOL * 1e3)
        np.testing.assert_allclose(again["position"], run["position"], rtol=0,
                                   atol=CYLINDER_RECORD_DRIVE_ATOL)
    held = pa.Cylinder(cylinder_set, load=Constant(0.0))
    assert experiment_for(held, record).drives == {}


@pytest.mark.parametrize(("drives", "message"), [
    ({"pressure": Constant(2e5)},
     r"drives 'pressure', but the 5/3 valve of this Cylinder needs a 'spool' signal \(its "
     r"declared inputs: 'spool' \[1\] in \[-1, 1\], 'load' \[N\] in \[-1e\+06, 1e\+06\], "
     r"'supply' \[Pa\] in \[100000, 1e\+07\]\)"),
    ({"load": Step(0.5, 0.0, 2e6)},
     r"experiment 'probe': its load force spans 0 to 2e\+06; a load force on a pneumatic "
     r"cylinder must stay within \[-1e\+06, 1e\+06\] N"),
], ids=["undeclared", "out-of-range"])
def test_undeclared_inputs_and_values_out_of_range_are_refused(drives, message, cylinder_set):
    experiment = Experiment(Constant(0.0), "spool", 1.0, name="probe", drives=drives)
    with pytest.raises(pa.ExperimentError, match=message):
        check_drive(pa.Cylinder(cylinder_set), experiment)


def test_the_load_is_no_drive_and_no_input_of_a_cylinder_holding_one(cylinder_set):
    """The load driven as the experiment's quantity is refused naming the cylinder's
    drive; driven by name on a cylinder holding its load, refused saying so; an actuator,
    which declares no load, refuses it naming its inputs."""
    with pytest.raises(pa.ExperimentError, match=r"drives 'load' as its quantity, but the "
                                                 r"drive of this Cylinder is 'spool'"):
        check_drive(pa.Cylinder(cylinder_set), Experiment(Constant(10.0), "load", 1.0,
                                                          drives={"spool": Constant(0.0)}))
    loaded = _loaded(SpoolStep(), Constant(10.0))
    with pytest.raises(pa.ExperimentError, match=r"this Cylinder holds its load \(load = "):
        check_drive(pa.Cylinder(cylinder_set, load=Constant(5.0)), loaded)
    actuator = pa.Actuator(load_quietly("vgt-paper"), valve=pa.CommandValve())
    with pytest.raises(pa.ExperimentError, match=r"drives 'load'.*declared inputs: 'command'"):
        check_drive(actuator, _loaded(pa.CommandCycle(), Constant(10.0)))


@pytest.mark.parametrize(("drives", "error", "message"), [
    ({"spool": Constant(0.0)}, pa.ExperimentError, r"'spool' is the experiment's quantity"),
    ({"lode": Constant(0.0)}, pa.ExperimentError, r"drives = 'lode': allowed: .*did you "
                                                  r"mean 'load'"),
    ({"load": 3.0}, pa.ArgumentTypeError, r"drives\['load'\] = 3: must be a Signal"),
    ([("load", Constant(0.0))], pa.ArgumentTypeError, r"drives = .*: must be a dict"),
], ids=["its-quantity", "unknown", "no-signal", "no-mapping"])
def test_an_experiment_refuses_drives_it_cannot_apply(drives, error, message):
    with pytest.raises(error, match=message):
        Experiment(Constant(0.0), "spool", 1.0, drives=drives)


def test_the_fmu_takes_the_load_as_its_external_force_input(cylinder_set):
    """The exported cylinder's force input keeps its name and sits on the channel of the
    declared load input (a held load is refused there: it would be dropped)."""
    interface = pa.Cylinder(cylinder_set).fmu_interface()
    force = next(i for i in interface.inputs if i.name == "external_force")
    assert force.channel == LOAD_INPUT.channel
    assert force.unit == LOAD_INPUT.unit
    with pytest.raises(pa.ArgumentError, match="drive the input 'external_force'"):
        pa.Cylinder(cylinder_set, load=Constant(1.0)).fmu_form()


def test_a_closed_loop_drives_its_plants_load_by_name(cylinder_set):
    """A position loop around the cylinder declares the plant's load beside its set-point:
    driven by name, the load disturbs the loop exactly as the plant's held load does (bit
    for bit), and the PID's integral brings the rod back to the set-point after it."""
    from pneumact.control import PID, ClosedLoop
    from pneumact.experiments import SetpointStep

    pid = PID(kp=60.0, ki=300.0, kd=0.5, derivative="velocity", u_min=-1.0, u_max=1.0)
    push = Step(1.0, 0.0, 150.0)
    setpoint = SetpointStep(0.09, 0.11, t_step=0.2, t_end=2.0, n_points=801)
    loop = ClosedLoop(pa.Cylinder(cylinder_set), pid)
    assert loop.inputs()[1] == LOAD_INPUT
    driven = pa.simulate(loop, Experiment(setpoint.drive, setpoint.quantity, setpoint.t_end,
                                          n_points=801, drives={"load": push}))
    held = pa.simulate(ClosedLoop(pa.Cylinder(cylinder_set, load=push), pid), setpoint)
    for name in ("position", "velocity", "pressure_a", "pressure_b", "command", "load"):
        assert np.array_equal(driven[name], held[name]), name
    after = driven.time > 1.0
    assert np.max(np.abs(driven["position"][after] - 0.11)) > CYLINDER_LOAD_ACTS_MIN
    assert abs(driven["position"][-1] - 0.11) < CYLINDER_LOOP_LOAD_RETURN_ATOL


def test_an_experiment_stops_at_its_drives_corners_and_keeps_them_over_a_new_duration():
    """The integrator stops at every driven input's corners (the load's step too), and
    ``with_duration`` keeps the drives."""
    experiment = Experiment(Step(0.1, -1.0, 0.5), "spool", 1.0, drives={"load": LOAD_STEP})
    assert 0.15 in experiment.breakpoints() and 0.1 in experiment.breakpoints()
    longer = experiment.with_duration(2.0)
    assert longer.drives == {"load": LOAD_STEP} and longer.t_end == 2.0
    assert experiment.inputs == {"spool": experiment.drive, "load": LOAD_STEP}


def test_a_batch_drives_the_load_as_a_run_does(cylinder_set):
    """The batch engine runs an experiment's drives as ``simulate`` does: a row's motion
    features are the run's summary, and the load shows in them (the unloaded batch's top
    speed out differs)."""
    import pandas as pd

    model = pa.Cylinder(cylinder_set)
    loaded = _loaded(SpoolStep(n_points=401), LOAD_STEP)
    rows = pd.DataFrame({"Fc": [cylinder_set["Fc"]]})
    batch = pa.simulate_batch(model, loaded, rows).table.iloc[0]
    summary = pa.simulate(model, loaded).summary()
    for name, value in summary.items():
        assert batch[name] == value, name
    free = pa.simulate_batch(model, SpoolStep(n_points=401), rows).table.iloc[0]
    assert free["top_speed_out"] > batch["top_speed_out"]


#: a spool step and a load step (in kN, exact in binary) sampled for a CSV
CSV_TIME = np.array([0.0, 0.1, 0.12, 0.3, 0.31, 0.6])
CSV_SPOOL = np.array([-1.0, -1.0, 0.5, 0.5, 0.5, 0.5])
CSV_LOAD_KN = np.array([0.0, 0.0, 0.0, 0.0, 0.25, 0.25])


def write_cylinder_csv(path, columns: dict[str, np.ndarray]) -> None:
    """A CSV of ``time [s]`` and ``columns`` (header cell -> values), as a user writes it."""
    import pandas as pd

    pd.DataFrame({"time [s]": CSV_TIME, **columns}).to_csv(path, index=False)


def test_a_csv_drives_the_spool_and_its_load_in_kn_as_the_api_does(cylinder_set, tmp_path):
    """``from_csv(path, model=cylinder)``: the cylinder's declared inputs pick the columns
    (``spool``, and ``load`` converted from kN to N by its name); a measured position
    beside them is ignored; the run equals the API's run of the same PiecewiseLinear spool
    and load bit for bit."""
    path = tmp_path / "drive.csv"
    write_cylinder_csv(path, {"spool [1]": CSV_SPOOL, "load [kN]": CSV_LOAD_KN,
                              "position [mm]": np.zeros(CSV_TIME.size)})
    model = pa.Cylinder(cylinder_set)
    from_file = pa.experiments.from_csv(path, model=model)
    assert from_file.quantity == "spool" and set(from_file.drives) == {"load"}
    np.testing.assert_array_equal(from_file.drives["load"](CSV_TIME), 1e3 * CSV_LOAD_KN)
    api = Experiment(PiecewiseLinear(CSV_TIME, CSV_SPOOL), "spool", 0.6, 0.0, CSV_TIME.size,
                     drives={"load": PiecewiseLinear(CSV_TIME, 1e3 * CSV_LOAD_KN)})
    run, expected = pa.simulate(model, from_file, SOLVER), pa.simulate(model, api, SOLVER)
    for name in ("position", "velocity", "pressure_a", "pressure_b", "load", "spool"):
        assert np.array_equal(run[name], expected[name]), name
    assert run["load"][-1] == 250.0


@pytest.mark.parametrize(("columns", "error", "message"), [
    ({"command [1]": np.abs(CSV_SPOOL)}, pa.DataError,
     r"drive\.csv: has no spool column \(columns: time, command\); a Cylinder's input file "
     r"needs time and its drive spool, optionally the other inputs it declares \(columns "
     r"spool \[1\], load \[N\], supply \[Pa\]\)"),
    ({"spool [1]": CSV_SPOOL, "load [mm]": CSV_LOAD_KN}, pa.DataError,
     r"column 'load' has unit 'mm' of dimension \[length\]; load needs a force unit such "
     r"as N, kN or lbf"),
    ({"spool [1]": CSV_SPOOL, "load": CSV_LOAD_KN}, pa.DataError,
     r"column 'load' has no unit; write the header as 'load \[unit\]' with a force unit"),
], ids=["no-spool", "load-not-a-force", "load-without-unit"])
def test_a_csv_the_cylinder_cannot_run_is_refused_naming_the_column(
        columns, error, message, cylinder_set, tmp_path):
    path = tmp_path / "drive.csv"
    write_cylinder_csv(path, columns)
    with pytest.raises(error, match=message):
        pa.experiments.from_csv(path, model=pa.Cylinder(cylinder_set))


def test_a_csv_load_beyond_a_meganewton_is_refused_naming_the_file(cylinder_set, tmp_path):
    """2000 kN read as 2 MN: the load input's range refuses it, naming the file."""
    path = tmp_path / "drive.csv"
    write_cylinder_csv(path, {"spool [1]": CSV_SPOOL, "load [kN]": 8e3 * CSV_LOAD_KN})
    experiment = pa.experiments.from_csv(path, model=pa.Cylinder(cylinder_set))
    with pytest.raises(pa.ExperimentError, match=r"experiment 'drive\.csv': its load force "
                                                 r"spans 0 to 2e\+06; .* \[-1e\+06, 1e\+06\] N"):
        check_drive(pa.Cylinder(cylinder_set), experiment)
