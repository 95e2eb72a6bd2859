"""The double-acting cylinder holding a position under a constant external load (issue 41,
item 2): ``linearise(..., inputs={"load": F})`` and ``ClosedLoop.holding_input(...,
inputs={"load": F})`` hold the plant's other declared inputs at constant values.

Known answers: at rest under a load F [N, against extension] the chambers balance it,
(p_a − p_atm)·A_a − (p_b − p_atm)·A_b = F (the cylinder has no spring); the holding spool
command and p_a rise with F, p_b falls; a load of 0 is today's linearisation bit for bit,
and a load given as an input is the one the cylinder holds (``Cylinder(load=...)``) bit for
bit; at the spool command that balances no load, the load is the force left, −F = m·v̇;
the presliding DC gain Δx/Δu is the slope of the holding force over the spool command,
divided by the bristle stiffness σ0 (central differences of ``holding_input``); the
nonlinear cylinder, started there, stays put, and swept there (``frequency_response``
with the same ``position`` and ``inputs``) has the loaded linearisation's gain and phase.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.control import PID, ClosedLoop, linearise
from pneumact.core.signals import Constant, Step
from pneumact.errors import ExperimentError, ParameterError
from pneumact.experiments import Experiment

pytestmark = pytest.mark.integration

#: mid-stroke [m] and the loads [N] the cylinder holds there (against extension, and
#: pulling it out)
POSITION = 0.1
LOADS = (0.0, 150.0, 300.0, -300.0)


@pytest.fixture(scope="module")
def cylinder():
    return pa.Cylinder(load_quietly("iso15552-32"))


def _loop(cylinder) -> ClosedLoop:
    return ClosedLoop(cylinder, PID(kp=100.0, kd=0.5, derivative="velocity", u_min=-1.0,
                                    u_max=1.0))


@pytest.fixture(scope="module")
def holding(cylinder):
    """load -> (its holding spool command, the linearisation there)."""
    loop = _loop(cylinder)
    points = {}
    for load in LOADS:
        spool = loop.holding_input(POSITION, inputs={"load": load})
        points[load] = spool, linearise(cylinder, spool, position=POSITION,
                                        inputs={"load": load})
    return points


def _pressure_force(params, point) -> float:
    """(p_a − p_atm)·A_a − (p_b − p_atm)·A_b at the point [N]."""
    bore, rod, p_atm = float(params["D_bore"]), float(params["d_rod"]), float(params["p_atm"])
    area_a, area_b = math.pi * bore**2 / 4, math.pi * (bore**2 - rod**2) / 4
    return (point["pressure_a"] - p_atm) * area_a - (point["pressure_b"] - p_atm) * area_b


def test_the_chambers_balance_the_load_at_the_holding_spool(cylinder, holding):
    params = cylinder.params
    for load, (_, linear) in holding.items():
        point = linear.operating_point
        assert point["load"] == load and point["position"] == POSITION
        assert abs(_pressure_force(params, point) - load) < ref.CYLINDER_LOAD_BALANCE_ATOL
        force_left = linear.rates[linear.state_names.index("velocity")] * float(params["m"])
        assert abs(force_left) < ref.CYLINDER_LOAD_BALANCE_ATOL
        assert f"load = {load:g} N" in linear.statement
    rising = sorted(LOADS)
    spools = [holding[load][0] for load in rising]
    p_a = [holding[load][1].operating_point["pressure_a"] for load in rising]
    p_b = [holding[load][1].operating_point["pressure_b"] for load in rising]
    assert np.all(np.diff(spools) > 0) and np.all(np.diff(p_a) > 0)
    assert np.all(np.diff(p_b) < 0)


@pytest.mark.parametrize("supply", [ref.CYLINDER_SUPPLY_LOW, ref.CYLINDER_SUPPLY_HIGH])
def test_the_chambers_balance_the_load_at_each_supply_level(cylinder, supply):
    """The supply pressure held as an input beside the load (``inputs={"supply": p_s}``):
    at each level the holding spool's chambers balance the load, with chamber A's rest
    pressure below that level, and a lower supply holds the load at other pressures."""
    load = 150.0
    inputs = {"load": load, "supply": supply}
    spool = _loop(cylinder).holding_input(POSITION, inputs=inputs)
    point = linearise(cylinder, spool, position=POSITION, inputs=inputs).operating_point
    assert abs(_pressure_force(cylinder.params, point) - load) < ref.CYLINDER_LOAD_BALANCE_ATOL
    assert cylinder.params["p_atm"] < point["pressure_a"] < supply
    usual = _loop(cylinder).holding_input(POSITION, inputs={"load": load})
    usual_point = linearise(cylinder, usual, position=POSITION,
                            inputs={"load": load}).operating_point
    assert abs(point["pressure_a"] - usual_point["pressure_a"]) > 1e3  # Pa: it acts


def test_no_load_is_todays_linearisation_and_a_held_load_the_same_point(cylinder, holding):
    """inputs={"load": 0} changes nothing, bit for bit; a load given as an input is the
    same point as the load the cylinder holds (Cylinder(load=Constant(F)))."""
    loop = _loop(cylinder)
    spool = loop.holding_input(POSITION)
    assert holding[0.0][0] == spool
    today = linearise(cylinder, spool, position=POSITION)
    for field in ("A", "B", "C", "rates", "state_scales"):
        np.testing.assert_array_equal(getattr(holding[0.0][1], field), getattr(today, field))
    load = 300.0
    held = pa.Cylinder(cylinder.params, load=Constant(load))
    spool = _loop(held).holding_input(POSITION)
    assert spool == holding[load][0]
    as_held = linearise(held, spool, position=POSITION)
    for field in ("A", "B", "rates"):
        np.testing.assert_array_equal(getattr(holding[load][1], field),
                                      getattr(as_held, field))


def test_a_load_the_spool_does_not_balance_is_the_force_left(cylinder, holding):
    """At the spool command that holds no load, a load F leaves −F on the piston
    (m·v̇ = −F) and the same Jacobian A (the load enters f as a constant)."""
    spool, unloaded = holding[0.0]
    load = 300.0
    loaded = linearise(cylinder, spool, position=POSITION, inputs={"load": load})
    np.testing.assert_array_equal(loaded.A, unloaded.A)
    force_left = loaded.rates[loaded.state_names.index("velocity")] * cylinder.params["m"]
    assert force_left == pytest.approx(-load, abs=ref.CYLINDER_LOAD_BALANCE_ATOL)


def test_the_dc_gain_is_the_holding_force_slope_over_the_bristle_stiffness(cylinder,
                                                                           holding):
    """Presliding, at DC the chambers sit at their rest pressures, which the spool alone
    sets, and the bristle σ0 takes the force: Δx/Δu = (dF_hold/du)/σ0, the slope by
    central differences of ``holding_input`` in the load. Away from the valve's centre
    its pressure gain falls: under ±300 N the gain is below the unloaded one."""
    loop = _loop(cylinder)
    sigma0 = float(cylinder.params["sigma0"])
    step = ref.CYLINDER_LOAD_FD_STEP
    gains = {}
    for load, (_, linear) in holding.items():
        moved = (loop.holding_input(POSITION, inputs={"load": load + step})
                 - loop.holding_input(POSITION, inputs={"load": load - step}))
        gains[load] = linear.dc_gain()
        assert gains[load] == pytest.approx(2.0 * step / moved / sigma0,
                                            rel=ref.CYLINDER_LOAD_DC_GAIN_RTOL)
    assert gains[300.0] < gains[0.0] and gains[-300.0] < gains[0.0]


def test_the_nonlinear_cylinder_rests_under_the_load_at_its_holding_spool(cylinder,
                                                                          holding):
    """Started at the point, the nonlinear cylinder stays put under the load at its
    holding spool command; at the spool command that holds no load it is pushed back."""
    load = 300.0
    moved = {}
    for name, spool in (("holding", holding[load][0]), ("unloaded", holding[0.0][0])):
        run = pa.simulate(cylinder, Experiment(Constant(spool), "spool", 0.5, n_points=51,
                                               drives={"load": Constant(load)}),
                          y0={"position": POSITION})
        moved[name] = run["position"] - POSITION
    assert np.abs(moved["holding"]).max() < ref.CYLINDER_LOAD_REST_ATOL
    assert moved["unloaded"].min() < -ref.CYLINDER_LOAD_ACTS_MIN


def test_the_nonlinear_sweep_under_the_load_follows_the_loaded_linearisation(cylinder,
                                                                            holding):
    """``frequency_response(..., position=, inputs=)``: the nonlinear cylinder, held
    mid-stroke under the load and swept about its holding spool command, has the gain and
    phase of the loaded linearisation, far from the unloaded one's."""
    from pneumact.control import frequency_response

    load = 300.0
    spool, loaded = holding[load]
    frequencies = np.array([2.0, 20.0, 150.0])
    sweep = frequency_response(cylinder, spool, ref.CYLINDER_LOAD_SWEEP_AMPLITUDE,
                               frequencies, position=POSITION, inputs={"load": load})
    expected = loaded.frequency_response(frequencies)
    np.testing.assert_allclose(sweep["gain"], np.abs(expected),
                               rtol=ref.CYLINDER_LOAD_SWEEP_RTOL)
    np.testing.assert_allclose(sweep["phase_deg"], np.degrees(np.angle(expected)), rtol=0,
                               atol=ref.CYLINDER_LOAD_SWEEP_PHASE_DEG)
    unloaded = np.abs(holding[0.0][1].frequency_response(frequencies))
    assert np.all(np.abs(unloaded / sweep["gain"] - 1) > 100 * ref.CYLINDER_LOAD_SWEEP_RTOL)


def test_a_linear_design_under_the_load_is_made_on_the_loaded_linearisation(cylinder,
                                                                           holding):
    """``linear_design(..., at=x, inputs={"load": F})`` designs on the plant held at x
    under F (its holding spool command, mid-stroke, not on a stop), the same linearisation
    as ``linearise``'s there."""
    pytest.importorskip("control")
    from pneumact.control import linear_design

    load = 300.0
    design = linear_design(_loop(cylinder), "settling=0.3,overshoot=5%", at=POSITION,
                           regime="presliding", inputs={"load": load})
    _, loaded = holding[load]
    assert design.plant.operating_point == loaded.operating_point
    np.testing.assert_array_equal(design.plant.A, loaded.A)
    np.testing.assert_array_equal(design.plant.B, loaded.B)


def test_inputs_the_plant_does_not_declare_or_out_of_range_are_refused(cylinder):
    spool = 0.0
    with pytest.raises(ExperimentError, match=r"linearise: inputs = \{'load': 2000000.0\} N; "
                                              r"allowed for the load force of this plant: "
                                              r"a finite number in \[-1e\+06, 1e\+06\] N"):
        linearise(cylinder, spool, position=POSITION, inputs={"load": 2e6})
    with pytest.raises(ExperimentError, match=r"inputs = \{'load': nan\} N; allowed"):
        linearise(cylinder, spool, position=POSITION, inputs={"load": float("nan")})
    with pytest.raises(ExperimentError, match=r"declares no input 'spool' beside its drive "
                                              r"\('spool' is its drive, the input value\); "
                                              r"allowed: 'load' \[N\] in \[-1e\+06, 1e\+06\]"):
        linearise(cylinder, spool, position=POSITION, inputs={"spool": 0.1})
    held = pa.Cylinder(cylinder.params, load=Constant(100.0))
    with pytest.raises(ExperimentError, match=r"holding_input: inputs = \{'load': 100.0\}; "
                                              r"Cylinder.* declares no input 'load' beside "
                                              r"its drive; allowed: 'supply' \[Pa\] in "
                                              r"\[100000, 1e\+07\]"):
        _loop(held).holding_input(POSITION, inputs={"load": 100.0})
    actuator = pa.Actuator(load_quietly("vgt-paper"), valve=pa.CommandValve())
    with pytest.raises(ExperimentError, match=r"linearise: inputs = \{'load': 1.0\}; "
                                              r"Actuator.*allowed: none"):
        linearise(actuator, 0.5, inputs={"load": 1.0})
    with pytest.raises(ParameterError, match=r"holding_input: inputs = \[\('load', 1.0\)\]; "
                                             r"give a dict"):
        _loop(cylinder).holding_input(POSITION, inputs=[("load", 1.0)])
    from pneumact.control import frequency_response

    with pytest.raises(ExperimentError, match=r"frequency_response: inputs = \{'load': "
                                              r"2000000.0\} N; allowed"):
        frequency_response(cylinder, spool, 1e-5, [1.0], inputs={"load": 2e6})
    with pytest.raises(ExperimentError, match=r"frequency_response: position = 0.5; allowed: "
                                              r"a position \[m\] in \[0, 0.2\]"):
        frequency_response(cylinder, spool, 1e-5, [1.0], position=0.5)


def test_a_load_stepping_later_is_held_at_its_value_at_the_start(cylinder, holding):
    """A loop's bias holds the plant at the start (t = 0): a load the cylinder holds that
    steps later (``--load-step``) is zero there, as in the run, so the holding spool
    command is the unloaded one (it once read such a step at t = 0.5 s)."""
    for time in (0.3, 0.5):
        stepping = pa.Cylinder(cylinder.params, load=Step(time, 0.0, 300.0))
        assert _loop(stepping).holding_input(POSITION) == holding[0.0][0]
