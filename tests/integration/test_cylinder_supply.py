"""The cylinder's supply pressure as a declared input (issue 41, item 2): a channel of the
cylinder's own (``supply``, after the fixed channels), driven by name like its load.

Known answers: undriven, the supply is the parameter p_supply (the run equals the run
with the supply driven at p_supply bit for bit, and p_supply acts); with the spool fully
open towards A and the rod on its end stop, chamber A's pressure settles at the supply's
level before and after a 6 -> 4 bar step, chamber B's at the atmosphere, and the pressure
force on the resting piston is (p_sup - p_atm)·A_a, carried by the stop; forward
sensitivities on a run with a driven supply agree with central differences (p_supply's
is zero there: the parameter does not act). A record's ``supply`` column, a batch, a
closed loop and the C engine drive it as ``simulate`` does; a value outside [p_atm,
1e7 Pa] is refused naming it and the range.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.core.assembly import assemble
from pneumact.core.signals import Constant, PiecewiseLinear, Ramp, Step
from pneumact.experiments import Experiment, SpoolStep
from pneumact.identification import experiment_for
from pneumact.io.records import Record
from pneumact.models.cylinder import SUPPLY_INPUT
from pneumact.simulation import Rodas4
from pneumact.simulation.simulate import check_drive

pytestmark = pytest.mark.integration

SOLVER = Rodas4(rtol=ref.CYLINDER_RTOL)
#: the supply stepping down from 6 to 4 bar (absolute) while the rod extends
SUPPLY_STEP = Step(0.3, ref.CYLINDER_SUPPLY_HIGH, ref.CYLINDER_SUPPLY_LOW)
SIGNALS = ("position", "velocity", "pressure_a", "pressure_b", "friction", "mass_flow_a",
           "mass_flow_b", "stop_force")


@pytest.fixture(scope="module")
def cylinder_set():
    return load_quietly("iso15552-32")


def _supplied(experiment: Experiment, supply) -> Experiment:
    """``experiment`` with the cylinder's supply pressure driven by name."""
    return Experiment(experiment.drive, experiment.quantity, experiment.t_end,
                      n_points=experiment.n_points, name="supplied",
                      drives={**experiment.drives, "supply": supply})


def test_the_supply_rides_on_the_cylinder_s_own_channel(cylinder_set):
    """The cylinder's layout is the fixed channels, then ``supply`` (its kernel reads it
    as CH_SUPPLY); a loop around it puts its own channels after that; the actuator, which
    declares none, keeps the fixed ones (and its kernel no CH_ constant)."""
    from pneumact.control import PID, ClosedLoop
    from pneumact.core.channels import CHANNELS, LOOP_CHANNELS, LOOP_OWN

    cylinder = pa.Cylinder(cylinder_set)
    assert cylinder.channel_names == (*CHANNELS, SUPPLY_INPUT.channel)
    assert assemble(cylinder).channels == cylinder.channel_names
    assert ("CH_SUPPLY", len(CHANNELS)) in assemble(cylinder).kernel_spec().constants
    loop = ClosedLoop(cylinder, PID(kp=1.0, u_min=-1.0, u_max=1.0))
    assert assemble(loop).channels == (*CHANNELS, "supply", *LOOP_OWN)
    constants = dict(assemble(loop).kernel_spec().constants)
    assert constants["CH_SETPOINT"] == len(CHANNELS) + 1
    actuator = pa.Actuator(load_quietly("vgt-paper"))
    assert assemble(actuator).channels == CHANNELS
    assert assemble(ClosedLoop(actuator, PID(kp=1.0))).channels == LOOP_CHANNELS
    assert not any(name.startswith("CH_")
                   for name, _ in assemble(actuator).kernel_spec().constants)
    signal = Constant(5e5)
    channels = cylinder.channels(Constant(0.2), {"supply": signal})
    assert channels[assemble(cylinder).channel_index("supply")] is signal
    assert cylinder.channels(Constant(0.2))[assemble(cylinder).channel_index("supply")] is None
    with pytest.raises(pa.PneumactError, match="has no channel 'setpoint'; its channels are "
                                                "drive, load_t, load_x, map_res, map_atm, "
                                                "supply"):
        assemble(cylinder).channel_index("setpoint")


def test_an_undriven_supply_is_p_supply_bit_for_bit(cylinder_set):
    """Without the input the kernel reads p_supply: the run equals the run with the supply
    driven at p_supply to the last bit; and p_supply acts (another value moves the rod)."""
    spool = SpoolStep(n_points=401)
    model = pa.Cylinder(cylinder_set)
    free = pa.simulate(model, spool, SOLVER)
    driven = pa.simulate(model, _supplied(spool, Constant(cylinder_set["p_supply"])), SOLVER)
    for name in SIGNALS:
        assert np.array_equal(free[name], driven[name]), name
    lower = pa.simulate(pa.Cylinder(cylinder_set.replace({"p_supply": ref.CYLINDER_SUPPLY_LOW})),
                        spool, SOLVER)
    assert np.max(np.abs(lower["position"] - free["position"])) > ref.CYLINDER_LOAD_ACTS_MIN


def test_a_supply_step_resets_the_rest_balance_on_the_end_stop(cylinder_set):
    """Spool fully open towards A (no leakage: A sees only the supply, B only the
    exhaust), the rod resting on its rod-end stop: chamber A's pressure is the supply's
    6 bar, then its 4 bar after the step; B's the atmosphere; the pressure force
    (p_sup − p_atm)·A_a, which the stop (and the stuck friction) carries."""
    params = cylinder_set.replace({"valve_leak": 0.0})
    step = Step(1.0, ref.CYLINDER_SUPPLY_HIGH, ref.CYLINDER_SUPPLY_LOW)
    run = pa.simulate(pa.Cylinder(params), Experiment(Constant(1.0), "spool", 2.0,
                                                      n_points=401, drives={"supply": step}),
                      SOLVER)
    p_atm, area_a = params["p_atm"], math.pi / 4.0 * params["D_bore"] ** 2
    for t, supply in ((0.99, ref.CYLINDER_SUPPLY_HIGH), (2.0, ref.CYLINDER_SUPPLY_LOW)):
        i = int(np.argmin(np.abs(run.time - t)))
        assert run["position"][i] > params["x_max"]  # on the stop's spring
        assert run["pressure_a"][i] == pytest.approx(supply, rel=ref.CYLINDER_SUPPLY_REST_RTOL)
        assert run["pressure_b"][i] == pytest.approx(p_atm, rel=ref.CYLINDER_SUPPLY_REST_RTOL)
        force = (supply - p_atm) * area_a
        assert run["pressure_force"][i] == pytest.approx(force,
                                                         rel=ref.CYLINDER_SUPPLY_REST_RTOL)
        left = run["pressure_force"][i] + run["stop_force"][i] - run["friction"][i]
        assert abs(left) < ref.CYLINDER_SUPPLY_BALANCE_ATOL


@pytest.mark.parametrize("name", ["valve_C", "chamber_a.V_dead", "D_bore"])
def test_sensitivities_with_a_driven_supply_match_central_differences(name, cylinder_set):
    """∂(p_a, x)/∂θ through a spool step while the supply falls from 6 to 4 bar, against
    central differences of two runs with the same driven supply."""
    spool = SpoolStep(before=-0.3, after=0.4, t_step=0.02, t_end=0.15, n_points=151)
    experiment = _supplied(spool, Ramp(ref.CYLINDER_SUPPLY_HIGH, ref.CYLINDER_SUPPLY_LOW,
                                       0.05, t_start=0.05))
    sens = pa.simulate_sensitivities(pa.Cylinder(cylinder_set), experiment, [name],
                                     Rodas4(rtol=ref.SENS_RTOL))
    value = cylinder_set[name]
    step = ref.SENS_FD_REL_STEP * value
    runs = [pa.simulate(pa.Cylinder(cylinder_set.replace({name: value + sign * step})),
                        experiment, Rodas4(rtol=ref.SENS_REFERENCE_RTOL)) for sign in (1, -1)]
    for signal in ("pressure_a", "position"):
        difference = (runs[0][signal] - runs[1][signal]) / (2.0 * step)
        size = np.abs(difference).max()
        rms = np.sqrt(np.mean((sens[signal][:, 0] - difference) ** 2))
        assert size > 0.0 and rms <= ref.SENS_RMS_FRACTION * size, (name, signal, rms, size)


def test_p_supply_has_no_sensitivity_where_the_supply_is_driven(cylinder_set):
    """Driven, the supply is the input's: p_supply's sensitivity is zero throughout; held,
    it is the parameter's, and not zero."""
    spool = SpoolStep(before=-0.3, after=0.4, t_step=0.02, t_end=0.15, n_points=151)
    model, solver = pa.Cylinder(cylinder_set), Rodas4(rtol=ref.SENS_RTOL)
    driven = pa.simulate_sensitivities(model, _supplied(spool, Constant(5e5)), ["p_supply"],
                                       solver)
    held = pa.simulate_sensitivities(model, spool, ["p_supply"], solver)
    for signal in ("pressure_a", "position"):
        assert not np.any(driven[signal][:, 0]), signal
        assert np.any(held[signal][:, 0]), signal


@pytest.mark.parametrize(("values", "message"), [
    ((5e4, 6e5), r"experiment 'probe': its supply pressure spans 50000 to 600000 Pa; a 5/3 "
                 r"valve's supply pressure must stay within \[100000, 1e\+07\] Pa absolute"),
    ((6e5, 2e7), r"its supply pressure spans 600000 to 2e\+07 Pa; .* within \[100000, "
                 r"1e\+07\]"),
    ((6.0, 6.0), r"its supply pressure spans 6 to 6 Pa; .*\(from the atmosphere p_atm up; in "
                 r"Pa: 6 bar is 6e5\)"),
], ids=["below-the-atmosphere", "above-1e7", "in-bar"])
def test_a_supply_outside_its_range_is_refused_naming_it(values, message, cylinder_set):
    """Below the cylinder's p_atm, above 1e7 Pa, or in bar: one ExperimentError naming
    the input, the values and the range (from p_atm)."""
    experiment = Experiment(Constant(0.0), "spool", 1.0, name="probe",
                            drives={"supply": PiecewiseLinear([0.0, 1.0], list(values))})
    with pytest.raises(pa.ExperimentError, match=message):
        check_drive(pa.Cylinder(cylinder_set), experiment)


def test_a_record_with_a_supply_column_drives_the_supply(cylinder_set, tmp_path):
    """A run's record (spool, supply, position) simulated again through ``experiment_for``
    (as ``fit`` and ``validate`` do) drives the supply from the record and repeats the
    run; a CSV's ``supply [bar]`` column is read as absolute pressure in Pa."""
    import pandas as pd

    t_knots = np.array([0.0, 0.1, 0.11, 0.3, 0.31, 0.6])
    spool = PiecewiseLinear(t_knots, [-1.0, -1.0, 0.5, 0.5, 0.5, 0.5])
    supply = PiecewiseLinear(t_knots, [6e5, 6e5, 6e5, 6e5, 4e5, 4e5])
    experiment = Experiment(spool, "spool", 0.6, n_points=121, drives={"supply": supply})
    model = pa.Cylinder(cylinder_set)
    run = pa.simulate(model, experiment, SOLVER)
    record = Record.from_arrays(run.time, {"spool": run["spool"], "supply": supply(run.time),
                                           "position": run["position"]},
                                {"spool": "1", "supply": "Pa", "position": "m"})
    again_experiment = experiment_for(model, record)
    assert set(again_experiment.drives) == {"supply"}
    again = pa.simulate(model, again_experiment, SOLVER, t_eval=record.time)
    np.testing.assert_allclose(again["position"], run["position"], rtol=0,
                               atol=ref.CYLINDER_RECORD_DRIVE_ATOL)
    path = tmp_path / "drive.csv"
    pd.DataFrame({"time [s]": t_knots, "spool [1]": spool(t_knots),
                  "supply [bar]": supply(t_knots) / 1e5}).to_csv(path, index=False)
    from_file = pa.experiments.from_csv(path, model=model)
    assert set(from_file.drives) == {"supply"}
    np.testing.assert_allclose(from_file.drives["supply"](t_knots), supply(t_knots), rtol=1e-15)


def test_a_fit_on_a_record_with_a_supply_column_finds_the_valve_s_conductance(cylinder_set):
    """A run with the supply falling from 6 to 4 bar while the rod extends, recorded
    (spool, supply, position; their corners on samples): started 30 % off, ``fit`` finds
    the valve_C that made it, its runs driven by the record's supply (measured 7e-8 off);
    from the record without that column (the supply then p_supply) it does not (5 %)."""
    spool = PiecewiseLinear([0.0, 0.05, 0.06, 0.6], [-1.0, -1.0, 0.2, 0.2])
    supply = PiecewiseLinear([0.0, 0.3, 0.31, 0.6], [ref.CYLINDER_SUPPLY_HIGH] * 2
                             + [ref.CYLINDER_SUPPLY_LOW] * 2)
    model = pa.Cylinder(cylinder_set)
    run = pa.simulate(model, Experiment(spool, "spool", 0.6, n_points=301,
                                        drives={"supply": supply}), SOLVER)
    columns = {"spool": run["spool"], "supply": supply(run.time), "position": run["position"]}
    units = {"spool": "1", "supply": "Pa", "position": "m"}
    truth = cylinder_set["valve_C"]
    found = {}
    for name, kept in (("with", tuple(columns)), ("without", ("spool", "position"))):
        record = Record.from_arrays(run.time, {k: columns[k] for k in kept},
                                    {k: units[k] for k in kept})
        result = pa.fit(model, [record], ["valve_C"], start={"valve_C": 1.3 * truth},
                        smooth_input=False)
        found[name] = float(result.to_pandas()["value"]["valve_C"])
    assert found["with"] == pytest.approx(truth, rel=ref.META_FIT_RTOL)
    assert found["without"] != pytest.approx(truth, rel=100 * ref.META_FIT_RTOL)


def test_a_batch_drives_the_supply_as_a_run_does(cylinder_set):
    """The batch engine runs the driven supply as ``simulate`` does (a row's motion
    features are the run's summary), and it shows in them."""
    import pandas as pd

    model = pa.Cylinder(cylinder_set)
    spool = SpoolStep(n_points=401)
    supplied = _supplied(spool, SUPPLY_STEP)
    rows = pd.DataFrame({"Fc": [cylinder_set["Fc"]]})
    batch = pa.simulate_batch(model, supplied, rows).table.iloc[0]
    summary = pa.simulate(model, supplied).summary()
    for name, value in summary.items():
        assert batch[name] == value, name
    free = pa.simulate_batch(model, spool, rows).table.iloc[0]
    assert free["top_speed_out"] > batch["top_speed_out"]


def test_a_closed_loop_drives_its_plant_s_supply_by_name(cylinder_set):
    """A position loop around the cylinder declares the plant's supply beside its
    set-point: driven at p_supply the loop runs as without it (bit for bit: its own
    channels sit after the supply's, where its kernel reads them), a supply falling to
    4 bar changes the run, and the PID still brings the rod to the set-point."""
    from pneumact.control import PID, ClosedLoop
    from pneumact.experiments import SetpointStep

    pid = PID(kp=60.0, ki=300.0, kd=0.5, derivative="velocity", u_min=-1.0, u_max=1.0)
    setpoint = SetpointStep(0.09, 0.11, t_step=0.2, t_end=1.5, n_points=601)
    loop = ClosedLoop(pa.Cylinder(cylinder_set), pid)
    assert "supply" in {i.name for i in loop.inputs()}
    free = pa.simulate(loop, setpoint)
    held = pa.simulate(loop, _supplied(setpoint, Constant(cylinder_set["p_supply"])))
    for name in ("position", "velocity", "pressure_a", "pressure_b", "command"):
        assert np.array_equal(free[name], held[name]), name
    lower = pa.simulate(loop, _supplied(setpoint, Step(0.1, cylinder_set["p_supply"],
                                                       ref.CYLINDER_SUPPLY_LOW)))
    assert np.max(np.abs(lower["pressure_a"] - free["pressure_a"])) > 1e3  # Pa: it acts
    assert abs(lower["position"][-1] - 0.11) < ref.CYLINDER_LOOP_LOAD_RETURN_ATOL


@pytest.mark.numba
def test_the_c_engine_follows_numba_with_a_driven_supply(cylinder_set):
    """The C back end translates the same kernel: a run with the supply driven equals
    numba's to ``ENGINE_AGREEMENT`` of each signal's range."""
    from pneumact.core.c_build import compiler_path

    if compiler_path() is None:
        pytest.skip("no C compiler: the C engine cannot run here")
    model = pa.Cylinder(cylinder_set)
    experiment = _supplied(SpoolStep(n_points=401), SUPPLY_STEP)
    c = pa.simulate(model, experiment, engine="c")
    numba = pa.simulate(model, experiment, engine="numba")
    assert c.meta["steps"] == numba.meta["steps"]
    a, b = c.to_pandas(), numba.to_pandas()
    span = np.maximum(np.ptp(b.to_numpy(), axis=0), np.finfo(float).tiny)
    assert np.max(np.abs(a.to_numpy() - b.to_numpy()) / span) <= ref.ENGINE_AGREEMENT
