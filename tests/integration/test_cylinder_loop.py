"""The double-acting cylinder in a closed loop (issue 41, item 5): position control
through the spool command, by a PID and by the servo-pneumatic state feedback on
position, velocity and the chambers' pressure difference."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.control import PID, ClosedLoop, loop_metrics
from pneumact.errors import ParameterError
from pneumact.experiments import SetpointStep

pytestmark = pytest.mark.integration

#: kp [1/m], kd [s/m]: a loop that overshoots by about a fifth without pressure feedback
KP, KD = 100.0, 0.5
#: pressure-difference gains [1/Pa], rising
KDPS = (0.0, 1e-6, 3e-6)
T_STEP, T_END = 1.0, 2.0
START = 0.09


def state_feedback(kdp: float) -> PID:
    """u = kp·(r − x) − kd·v − kdp·Δp, limited to the spool's travel."""
    return PID(kp=KP, kd=KD, kdp=kdp, derivative="velocity", u_min=-1.0, u_max=1.0)


@pytest.fixture(scope="module")
def cylinder():
    return pa.Cylinder(load_quietly("iso15552-32"))


#: a PID with integral action (its derivative on the measured velocity): one kernel with
#: the state feedbacks, the gains being settings
PID_GAINS = {"kp": 60.0, "ki": 300.0, "kd": 0.5}


@pytest.fixture(scope="module")
def runs(cylinder):
    """One 20 mm step per pressure gain, and one under the PID."""
    step = SetpointStep(START, START + ref.CYLINDER_LOOP_STEP, t_step=T_STEP, t_end=T_END,
                        n_points=4001)
    controllers = {kdp: state_feedback(kdp) for kdp in KDPS}
    controllers["pid"] = PID(**PID_GAINS, derivative="velocity", u_min=-1.0, u_max=1.0)
    return {name: pa.simulate(ClosedLoop(cylinder, controller), step)
            for name, controller in controllers.items()}


@pytest.mark.parametrize("name", [*KDPS, "pid"])
def test_a_20mm_step_settles(runs, name):
    """After the set-point's step the position settles into 2 % of the step and stays."""
    run = runs[name]
    metrics = loop_metrics(run, t_step=T_STEP, band=ref.CYLINDER_LOOP_BAND)
    assert np.isfinite(metrics.settling_time), metrics
    assert metrics.settling_time < T_END - T_STEP
    assert not metrics.hunting
    assert np.all(np.abs(run["command"]) <= 1.0)


def test_pressure_feedback_adds_damping(runs):
    """At the same kp and kd, more pressure-difference feedback, less overshoot."""
    overshoot = [loop_metrics(runs[k], t_step=T_STEP).overshoot for k in KDPS]
    assert all(a > b for a, b in itertools.pairwise(overshoot)), overshoot
    assert overshoot[0] - overshoot[-1] > ref.CYLINDER_DAMPING_MIN_POINTS, overshoot


def test_the_command_is_the_state_feedback_law(runs, cylinder):
    """command = clip(kp·e − kd·v − kdp·((p_a − p_atm) − (p_b − p_atm)·A_b/A_a), ±1),
    written out from the run's own signals."""
    kdp = KDPS[-1]
    run = runs[kdp]
    params = cylinder.params
    p_atm = float(params["p_atm"])
    bore, rod = float(params["D_bore"]), float(params["d_rod"])
    area_ratio = (bore**2 - rod**2) / bore**2
    dp = (run["pressure_a"] - p_atm) - (run["pressure_b"] - p_atm) * area_ratio
    law = KP * run["error"] - KD * run["velocity"] - kdp * dp
    expected = np.clip(law, -1.0, 1.0)
    assert np.max(np.abs(run["command"] - expected)) < ref.CYLINDER_LAW_ATOL
    assert np.max(np.abs(kdp * dp)) > 0.05  # the pressure term mattered in this run
    assert np.any(np.abs(law) > 1.0)  # and the limit too


def test_pressure_feedback_needs_two_chambers():
    vgt = load_quietly("vgt-paper")
    with pytest.raises(ParameterError, match=r"kdp = 1e-06.*Cylinder"):
        ClosedLoop(pa.Actuator(vgt, valve=pa.CommandValve()), PID(kp=1.0, kdp=1e-6))
    with pytest.raises(ParameterError, match=r"kdp = -1.*>= 0"):
        PID(kp=1.0, kdp=-1.0)


def test_a_kinematic_rig_has_no_input_to_control():
    rig = pa.FrictionRig(load_quietly("canudas1995"), drive="velocity")
    with pytest.raises(ParameterError, match="kinematic drive has no input"):
        ClosedLoop(rig, PID(kp=1.0))
