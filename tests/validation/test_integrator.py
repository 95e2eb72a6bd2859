"""The compiled integrators against independent references.

- Rodas4 against scipy's Radau (Python wrappers around the same kernel ``rhs``/``jac``,
  integrated interval by interval between the breakpoints, at rtol 1e-10).
- Observed order of Rodas4 (4) and Dormand-Prince (5) at fixed step on a linear
  spring-mass-damper whose solution is known in closed form.
- Adaptive error control: the error falls with rtol; Dormand-Prince agrees with Rodas4.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pneumact.core.signals import Constant, Sine, Triangle
from pneumact.experiments.actuator import CommandCycle, Experiment
from pneumact.models import Actuator, CommandValve, CoulombViscous, FrictionRig, LuGre
from pneumact.simulation import DormandPrince, Rodas4, simulate
from pneumact.simulation.simulate import prepare
from reference import (
    CONVERGED_RTOL,
    DOPRI_ORDER_RANGE,
    DOPRI_VS_RODAS_TOL,
    LOOSE_ORACLE_ERROR,
    ORDER_STEPS_DOPRI,
    ORDER_STEPS_RODAS,
    RADAU_ATOL_FACTOR,
    RADAU_RTOL,
    RODAS_ORDER_RANGE,
    RODAS_VS_RADAU,
)


# ------------------------------------------------------------------ Radau reference
def radau_reference(model, experiment) -> tuple[np.ndarray, np.ndarray]:
    """(times, states) from scipy Radau on the kernel's own rhs/jac, restarted at every
    breakpoint with the segment time ts = midpoint of the interval (as the kernel does)."""
    prep = prepare(model, experiment, Rodas4(rtol=RADAU_RTOL))
    kernel, prm, sig, ptr = prep.kernel, prep.vector, prep.sig, prep.ptr
    bp, t_out, y0, atol = prep.breakpoints, prep.t_out, prep.y0, prep.atol
    n = y0.size
    states = np.empty((t_out.size, n))
    y = y0.copy()
    states[t_out <= bp[0]] = y
    for a, b in itertools.pairwise(bp):
        ts = 0.5 * (a + b)

        def f(t, y, ts=ts):
            out = np.empty(n)
            kernel.rhs(t, ts, y, prm, sig, ptr, out)
            return out

        def jac(t, y, ts=ts):
            out = np.zeros((n, n))
            kernel.jac(t, ts, y, prm, sig, ptr, out)
            return out

        inside = (t_out > a) & (t_out <= b)
        t_eval = t_out[inside]
        count = t_eval.size
        if count == 0 or t_eval[-1] != b:
            t_eval = np.append(t_eval, b)  # also land on the breakpoint to restart there
        sol = solve_ivp(f, (a, b), y, method="Radau", rtol=RADAU_RTOL,
                        atol=atol * RADAU_ATOL_FACTOR, jac=jac, t_eval=t_eval)
        assert sol.success, sol.message
        states[inside] = sol.y.T[:count]
        y = sol.y[:, -1].copy()
    return t_out, states


RADAU_CASES = {
    "source_delta2": ("source", 2.0),
    "source_delta1": ("source", 1.0),
    "command_delta2": ("command", 2.0),
}


def _radau_case(name, vgt):
    valve, delta = RADAU_CASES[name]
    params = vgt.replace(delta=delta)
    if valve == "source":
        model = Actuator(params, friction=LuGre())
        experiment = Experiment(Triangle(100e3, 20e3, period=2.0), "pressure", t_end=2.0,
                                n_points=401)
    else:
        model = Actuator(params, friction=LuGre(), valve=CommandValve())
        experiment = CommandCycle(0.0, 1.0, period=2.0, n_points=401)
    return model, experiment


@pytest.fixture(scope="module", params=list(RADAU_CASES))
def radau_case(request, vgt):
    model, experiment = _radau_case(request.param, vgt)
    return request.param, model, experiment, radau_reference(model, experiment)


def test_rodas4_matches_radau(radau_case):
    name, model, experiment, (t_ref, y_ref) = radau_case
    errors = []
    for rtol in (1e-6, 1e-9):
        r = simulate(model, experiment, Rodas4(rtol=rtol))
        np.testing.assert_array_equal(r.time, t_ref)
        errors.append(np.abs(r["position"] - y_ref[:, 0]).max())
    assert np.ptp(y_ref[:, 0]) > 0.01, "the actuator must travel"
    tol_loose, tol_tight = RODAS_VS_RADAU[name]
    assert errors[0] <= tol_loose, f"{name}: rtol 1e-6 error {errors[0]:.3g} m"
    assert errors[1] <= tol_tight, f"{name}: rtol 1e-9 error {errors[1]:.3g} m"
    assert errors[1] < errors[0], "tightening rtol must reduce the error"


# ------------------------------------------------- fixed-step order on a linear oscillator
T_ORDER = 10.0  # s: about two periods of the rig oscillator (ω_d = 1.4 rad/s)


def _oscillator(canudas):
    """Mass m on a spring k_drive whose free end sits at 1 m, viscous damping σ2 only."""
    params = canudas.replace(Fc=0.0)
    model = FrictionRig(params, friction=CoulombViscous(), drive="spring")
    m, k, c = params["m"], params["k_drive"], params["sigma2"]
    return model, m, k, c


def _oscillator_exact(t, m, k, c):
    """x(t) of m·x'' + c·x' + k·x = k·1 from rest at 0 (underdamped)."""
    a = c / (2.0 * m)
    wd = math.sqrt(k / m - a * a)
    return 1.0 - np.exp(-a * t) * (np.cos(wd * t) + a / wd * np.sin(wd * t))


def _fixed_step_error(model, solver_type, h, m, k, c, t_grid) -> float:
    experiment = Experiment(Constant(1.0), "spring", t_end=T_ORDER)
    # rtol near 1 and a huge atol never reject a step; h_init = h_max = h fixes it
    solver = solver_type(rtol=0.5, atol=1e3, h_init=h, h_max=h)
    r = simulate(model, experiment, solver, t_eval=t_grid)
    assert r.meta["rejected"] == 0
    assert r.meta["steps"] == round(T_ORDER / h)
    return float(np.abs(r["position"] - _oscillator_exact(t_grid, m, k, c)).max())


@pytest.mark.parametrize(("solver_type", "steps", "order_range"), [
    (Rodas4, ORDER_STEPS_RODAS, RODAS_ORDER_RANGE),
    (DormandPrince, ORDER_STEPS_DOPRI, DOPRI_ORDER_RANGE),
], ids=["Rodas4", "DormandPrince"])
def test_fixed_step_convergence_order(solver_type, steps, order_range, canudas):
    model, m, k, c = _oscillator(canudas)
    # compare at the step ends of the coarsest step (no dense-output interpolation)
    t_grid = np.linspace(0.0, T_ORDER, round(T_ORDER / steps[0]) + 1)
    errors = np.array([_fixed_step_error(model, solver_type, h, m, k, c, t_grid)
                       for h in steps])
    orders = np.log2(errors[:-1] / errors[1:])
    lo, hi = order_range
    assert np.all((orders >= lo) & (orders <= hi)), (
        f"{solver_type.__name__}: errors {errors}, observed orders {orders}"
    )


@pytest.mark.parametrize("solver_type", [Rodas4, DormandPrince])
def test_adaptive_error_falls_with_rtol(solver_type, canudas):
    model, m, k, c = _oscillator(canudas)
    experiment = Experiment(Constant(1.0), "spring", t_end=T_ORDER, n_points=501)
    errors = []
    for rtol in (1e-4, 1e-6, 1e-8, 1e-10):
        r = simulate(model, experiment, solver_type(rtol=rtol))
        errors.append(np.abs(r["position"] - _oscillator_exact(r.time, m, k, c)).max())
    errors = np.array(errors)
    assert np.all(errors[1:] < 0.5 * errors[:-1]), f"errors {errors}"
    assert errors[0] < LOOSE_ORACLE_ERROR


def test_dormand_prince_agrees_with_rodas4_on_a_non_stiff_problem(canudas):
    model, *_ = _oscillator(canudas)
    experiment = Experiment(Sine(0.5, 0.3, offset=0.2), "spring", t_end=20.0,
                            n_points=2001)
    x_dopri = simulate(model, experiment, DormandPrince(rtol=CONVERGED_RTOL))["position"]
    x_rodas = simulate(model, experiment, Rodas4(rtol=CONVERGED_RTOL))["position"]
    assert np.ptp(x_rodas) > 0.1
    assert np.abs(x_dopri - x_rodas).max() <= DOPRI_VS_RODAS_TOL
