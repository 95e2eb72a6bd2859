"""The cylinder fed by two proportional 3/2 valves, one per chamber (issue 41, items 1 and
2): each valve a component instance (``valve_a.*``, ``valve_b.*``) with its own declared
command input (``command_a``, ``command_b``). Known answers: identical valves driven
u_a = u, u_b = -u are the 5/3 cylinder driven by u; each chamber alone, its valve fully
open to the supply or the exhaust, settles at that pressure; forward sensitivities to each
valve's parameters against central differences; a batch over them equals single runs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.core.signals import Constant
from pneumact.experiments import Experiment, PiecewiseLinear
from pneumact.parameters.catalogue import catalogue

pytestmark = pytest.mark.integration

TWO = "two-3/2"
#: held retracted, then the valves opened over 50 ms: A fills, B vents, the piston extends
TIMES, COMMAND = [0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3]
SIGNALS = ("position", "pressure_a", "pressure_b")
#: released mid-stroke, both chambers at 4 bar
START = {"position": 0.1, "velocity": 0.0, "pressure_a": 4e5, "pressure_b": 4e5}
VALVE_PARAMETERS = tuple(f"valve_{c}.{k}" for c in "ab" for k in ("C", "leak", "overlap"))


def _mirrored(times=TIMES, command=COMMAND, t_end: float = 0.3,
              n_points: int = 301) -> Experiment:
    """command_a = u, command_b = −u."""
    return Experiment(PiecewiseLinear(times, command), "command_a", t_end, n_points=n_points,
                      drives={"command_b": PiecewiseLinear(times, [-u for u in command])})


@pytest.fixture(scope="module")
def params():
    """The set with unequal dead volumes, an overlapped spool and each 3/2 valve as one
    chamber's two paths of the 5/3 valve (a valve reading the other's block shows)."""
    base = load_quietly("iso15552-32")
    base = base.replace({"chamber_b.V_dead": 2.5 * base["chamber_a.V_dead"],
                         "spool_overlap": 0.05})
    return base.replace({f"valve_{c}.{k}": base[five] for c in "ab" for k, five in (
        ("C", "valve_C"), ("leak", "valve_leak"), ("overlap", "spool_overlap"))})


def test_identical_valves_driven_opposite_are_the_5_3_cylinder(params):
    """u_a = u, u_b = −u through two 3/2 valves with the 5/3 valve's paths: the 5/3
    cylinder's trajectory and flows (the same arithmetic: bit-equal)."""
    spool = Experiment(PiecewiseLinear(TIMES, COMMAND), "spool", 0.3, n_points=301)
    five = pa.simulate(pa.Cylinder(params), spool)
    two = pa.simulate(pa.Cylinder(params, valves=TWO), _mirrored())
    assert np.ptp(five["position"]) > 0.05, "the piston must travel for this test to bite"
    for signal in (*SIGNALS, "velocity", "mass_flow_a", "mass_flow_b"):
        np.testing.assert_allclose(two[signal], five[signal], err_msg=signal,
                                   rtol=ref.CYLINDER_VALVES_5_3_RTOL, atol=0.0)
    np.testing.assert_array_equal(two["command_a"], five["spool"])
    np.testing.assert_array_equal(two["command_b"], -five["spool"])


@pytest.mark.parametrize("extend", [True, False])
def test_each_chamber_alone_settles_at_its_valve_s_port(extend, params):
    """One valve fully open to the supply, the other to the exhaust, no leakage: released
    mid-stroke, the piston runs onto the stop and the filled chamber settles at the supply
    pressure, the vented one at the atmosphere; the other chamber's valve is not read."""
    tight = params.replace({"valve_a.leak": 0.0, "valve_b.leak": 0.0,
                            "valve_b.C": 0.5 * params["valve_a.C"]})
    u = 1.0 if extend else -1.0
    experiment = Experiment(Constant(u), "command_a", 1.0, n_points=101,
                            drives={"command_b": Constant(-u)})
    run = pa.simulate(pa.Cylinder(tight, valves=TWO), experiment,
                      pa.Rodas4(rtol=ref.CYLINDER_RTOL), y0=START)
    full, empty = ("pressure_a", "pressure_b") if extend else ("pressure_b", "pressure_a")
    assert run["position"][-1] == pytest.approx(tight["x_max"] if extend else 0.0, abs=1e-5)
    assert run[full][-1] == pytest.approx(tight["p_supply"], rel=ref.CYLINDER_VALVES_REST_RTOL)
    assert run[empty][-1] == pytest.approx(tight["p_atm"], rel=ref.CYLINDER_VALVES_REST_RTOL)


def test_an_undriven_command_b_closes_valve_b(params):
    """An experiment that drives command_a only leaves valve B closed (command_b = 0, no
    leakage): while A's valve moves the piston, chamber B's gas mass p_b·V_b/(R·T) stays
    (isothermal), and valve A's commands reach chamber A alone."""
    closed = params.replace({"valve_b.leak": 0.0})
    model = pa.Cylinder(closed, valves=TWO)
    run = pa.simulate(model, Experiment(PiecewiseLinear(TIMES, COMMAND), "command_a", 0.3,
                                        n_points=301), pa.Rodas4(rtol=ref.CYLINDER_RTOL),
                      y0=START)
    assert np.all(run["command_b"] == 0.0) and np.all(run["mass_flow_b"] == 0.0)
    assert np.ptp(run["position"]) > 0.01, "the piston must travel for this test to bite"
    area_b = np.pi * (closed["D_bore"] ** 2 - closed["d_rod"] ** 2) / 4.0
    volume_b = closed["chamber_b.V_dead"] + area_b * (closed["x_max"] - run["position"])
    gas_b = run["pressure_b"] * volume_b
    np.testing.assert_allclose(gas_b, gas_b[0], rtol=ref.CYLINDER_POLYTROPIC_RTOL)


@pytest.mark.parametrize("name", VALVE_PARAMETERS)
def test_forward_sensitivities_to_each_valve_match_differences(name, params):
    """∂(x, p_a, p_b)/∂ each valve's C, leak and overlap carried through the run against
    central differences of two runs given the value by name."""
    model = pa.Cylinder(params, valves=TWO)
    sens = pa.simulate_sensitivities(model, _mirrored(), [name],
                                     pa.Rodas4(rtol=ref.SENS_RTOL))
    assert sens.units[name] == catalogue()[name].unit
    value = float(params[name])
    step = ref.SENS_FD_REL_STEP * value
    tight = pa.Rodas4(rtol=ref.SENS_REFERENCE_RTOL)
    up, down = (pa.simulate(model, _mirrored(), tight, values={name: value + s})
                for s in (step, -step))
    for signal in SIGNALS:
        difference = (up[signal] - down[signal]) / (2.0 * step)
        size = np.abs(difference).max()
        rms = np.sqrt(np.mean((sens[signal][:, 0] - difference) ** 2))
        assert size > 0.0 and rms <= ref.SENS_RMS_FRACTION * size, (name, signal, rms, size)


def test_a_batch_over_the_valves_equals_single_runs(params):
    """Rows of valve_a.C and valve_b.overlap: each row's signals are those of a run of the
    set with those values."""
    model = pa.Cylinder(params, valves=TWO)
    c = params["valve_a.C"]
    table = pd.DataFrame({"valve_a.C": [0.5 * c, c, 1.5 * c],
                          "valve_b.overlap": [0.0, 0.05, 0.1]})
    batch = pa.simulate_batch(model, _mirrored(), table, signals=list(SIGNALS),
                              t_eval=np.linspace(0.0, 0.3, 301), executor=1)
    assert list(batch.table["status"]) == ["ok"] * 3, batch.table["error"].tolist()
    for i, row in table.iterrows():
        run = pa.simulate(pa.Cylinder(params.replace(row.to_dict()), valves=TWO),
                          _mirrored(), t_eval=batch.time)
        for signal in SIGNALS:
            np.testing.assert_allclose(batch.signals[signal][i], run[signal],
                                       rtol=ref.BATCH_FEATURE_RTOL, err_msg=(i, signal))
    assert np.ptp(batch.signals["position"][:, -1]) > 1e-3


def test_the_valves_are_instances_of_one_kind_with_their_own_commands(params):
    """valve_a.* and valve_b.* carry the kind's catalogue entry; the commands are declared
    inputs (unit 1, range [-1, 1], record columns of their names) refused outside it."""
    entries = catalogue()
    for local in ("C", "leak", "overlap"):
        a, b = entries[f"valve_a.{local}"], entries[f"valve_b.{local}"]
        assert (a.unit, a.default, a.minimum, a.maximum, a.plausible) == (
            b.unit, b.default, b.minimum, b.maximum, b.plausible)
        assert a.description.startswith(b.description.partition(";")[0])
    model = pa.Cylinder(params, valves=TWO)
    commands = model.inputs()[:2]
    assert [(c.name, c.unit, c.low, c.high, c.record_signals) for c in commands] == [
        ("command_a", "1", -1.0, 1.0, ("command_a",)),
        ("command_b", "1", -1.0, 1.0, ("command_b",))]
    bad = Experiment(Constant(0.5), "command_a", 0.1, drives={"command_b": Constant(1.5)})
    with pytest.raises(pa.ExperimentError, match=r"command_b spans 1.5 to 1.5; a 3/2 "
                                                 r"valve's command must stay within \[-1, 1\]"):
        pa.simulate(model, bad)
    with pytest.raises(pa.ArgumentError, match="valves = 'two': must be '5/3'"):
        pa.Cylinder(params, valves="two")
    with pytest.raises(pa.ArgumentError, match="spool's lag and HeatTransfer"):
        pa.Cylinder(params, valves=TWO, spool_lag=1)


def test_a_closed_loop_around_two_valves_is_refused(params):
    """A position controller has one output: the two-valve cylinder (two commands) is no
    plant of a ClosedLoop yet, refused saying which cylinder is."""
    from pneumact.control import PID, ClosedLoop

    with pytest.raises(pa.ParameterError, match=r"valves='two-3/2'\); allowed: .*a Cylinder "
                                                r"fed by its 5/3 valve"):
        ClosedLoop(pa.Cylinder(params, valves=TWO), PID(kp=60.0, u_min=-1.0, u_max=1.0))


# ------------------------------------------- mirrored: one command, u_a = u and u_b = -u
#: a 20 mm set-point step from 90 mm: PID with integral action, and state feedback with
#: pressure feedback (u = kp·(r − x) − kd·v − kdp·Δp), both limited to [-1, 1]
LOOP_CONTROLLERS = {
    "pid": {"kp": 60.0, "ki": 300.0, "kd": 0.5},
    "pressure_feedback": {"kp": 100.0, "kd": 0.5, "kdp": 3e-6},
}


def _pair(params) -> tuple[pa.Cylinder, pa.Cylinder]:
    """(the 5/3 cylinder, the cylinder of two identical 3/2 valves driven mirrored)."""
    return pa.Cylinder(params), pa.Cylinder(params, valves=TWO, mirrored=True)


def test_mirrored_valves_are_the_5_3_cylinder(params):
    """mirrored=True: one declared drive, the spool command's, feeding valve A with u and
    valve B with −u inside the kernel: the 5/3 cylinder's run bit for bit; mirrored
    without two 3/2 valves is refused naming both options."""
    five, mirrored = _pair(params)
    assert [i.name for i in mirrored.inputs()] == ["spool", "load", "supply"]
    spool = Experiment(PiecewiseLinear(TIMES, COMMAND), "spool", 0.3, n_points=301)
    runs = [pa.simulate(model, spool) for model in (five, mirrored)]
    assert np.ptp(runs[0]["position"]) > 0.05, "the piston must travel for this test to bite"
    for signal in (*SIGNALS, "velocity", "mass_flow_a", "mass_flow_b"):
        np.testing.assert_allclose(runs[1][signal], runs[0][signal], err_msg=signal,
                                   rtol=ref.CYLINDER_VALVES_5_3_RTOL, atol=0.0)
    np.testing.assert_array_equal(runs[1]["command_a"], runs[0]["spool"])
    np.testing.assert_array_equal(runs[1]["command_b"], -runs[0]["spool"])
    with pytest.raises(pa.ArgumentError, match=r"mirrored = True with valves = '5/3'.*"
                                               r"give valves='two-3/2'"):
        pa.Cylinder(params, mirrored=True)


@pytest.mark.parametrize("controller", sorted(LOOP_CONTROLLERS))
def test_mirrored_valves_in_a_loop_are_the_5_3_loop(params, controller):
    """Position control through the valve command (the PID; state feedback with pressure
    feedback): the mirrored two-valve loop is the 5/3 loop, its holding input and every
    signal bit for bit."""
    from pneumact.control import PID, ClosedLoop
    from pneumact.experiments import SetpointStep

    def loop(cylinder, bias: float = 0.0) -> ClosedLoop:
        return ClosedLoop(cylinder, PID(**LOOP_CONTROLLERS[controller], derivative="velocity",
                                        u_min=-1.0, u_max=1.0), bias=bias)

    step = SetpointStep(0.09, 0.11, t_step=0.05, t_end=0.4, n_points=401)
    holds = [loop(model).holding_input(0.09) for model in _pair(params)]
    assert holds[1] == holds[0]
    five, mirrored = (pa.simulate(loop(model, hold), step)
                      for model, hold in zip(_pair(params), holds, strict=True))
    assert np.ptp(five["position"]) > 0.015, "the loop must move the piston to bite"
    for signal in (*SIGNALS, "velocity", "command", "plant_input", "mass_flow_a",
                   "mass_flow_b"):
        np.testing.assert_allclose(mirrored[signal], five[signal], err_msg=signal,
                                   rtol=ref.CYLINDER_VALVES_5_3_RTOL, atol=0.0)


def test_mirrored_valves_linearise_as_the_5_3_cylinder(params):
    """Linearised mid-stroke at the command that balances the chambers there: the 5/3
    cylinder's A, B, C, D."""
    from pneumact.control import PID, ClosedLoop, linearise

    plants = []
    for model in _pair(params):
        held = ClosedLoop(model, PID(kp=100.0, kd=0.5, derivative="velocity", u_min=-1.0,
                                     u_max=1.0)).holding_input(0.1)
        plants.append(linearise(model, held, position=0.1))
    assert plants[1].input_name == plants[0].input_name == "spool"
    for name in ("A", "B", "C", "D"):
        np.testing.assert_allclose(getattr(plants[1], name), getattr(plants[0], name),
                                   rtol=ref.CYLINDER_VALVES_5_3_RTOL, atol=0.0, err_msg=name)
    assert np.abs(plants[0].B).max() > 0, "the valve command must act for this to bite"
