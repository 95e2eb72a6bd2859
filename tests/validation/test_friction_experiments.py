"""The classic friction experiments of Canudas de Wit et al. (1995) on the FrictionRig:
known answers (analytic steady states, the Dahl closed form, presliding stiffness) and
the qualitative behaviour the paper reports (frictional lag, varying break-away force,
periodic stick-slip), plus an independent-solver check of the stick-slip run."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pneumact.analysis.friction_tests import (
    lag_loop_width,
    run_friction_test,
    slip_onsets,
    solver_for,
)
from pneumact.errors import ExperimentError
from pneumact.experiments import Experiment, PiecewiseLinear
from pneumact.experiments.friction import FRICTION_TESTS, BreakAway, StickSlip
from pneumact.models.friction import BoucWen, Dahl, LuGre
from pneumact.models.friction.evaluation import friction_law_values
from pneumact.models.rig import FrictionRig
from pneumact.parameters import load_params
from pneumact.simulation.simulate import prepare, simulate
from reference import (
    BOUC_WEN_DAHL_ATOL,
    BREAK_AWAY_FAST_FRACTION,
    BREAK_AWAY_FS_RTOL,
    BRISTLE_BOUND_RTOL,
    DAHL_FORCE_ATOL,
    FRICTION_RTOL,
    ONSET_FORCE_RTOL,
    PERIOD_RTOL,
    RADAU_POSITION_ATOL,
    RADAU_RTOL,
    RADAU_SPAN,
    STEADY_STATE_RTOL,
    STICK_SLIP_DURATION,
    STICK_SLIP_RADAU_ATOL,
    STIFFNESS_RTOL,
    STUCK_VELOCITY_FRACTION,
)


@pytest.fixture(scope="module")
def params():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # canudas1995 breaks the sigma1 passivity bound
        return load_params("canudas1995")


@pytest.fixture(scope="module")
def all_runs(params):
    return {kind: run_friction_test(kind, params) for kind in FRICTION_TESTS}


@pytest.mark.parametrize("delta", [1.0, 2.0])
def test_lugre_steady_state_matches_stribeck_curve(params, delta):
    p = params.replace(delta=delta)
    table = run_friction_test("steady-state", p).table
    v = table["velocity [m/s]"].to_numpy()
    g = p["Fc"] + (p["Fs"] - p["Fc"]) * np.exp(-((np.abs(v) / p["vs"]) ** delta))
    expected = np.sign(v) * g + p["sigma2"] * v
    assert np.all(v[:25] < 0) and np.all(v[25:] > 0)
    np.testing.assert_allclose(table["friction [N]"], expected, rtol=STEADY_STATE_RTOL)
    np.testing.assert_allclose(table["steady-state friction [N]"], expected, rtol=FRICTION_RTOL)


def test_presliding_initial_stiffness_is_sigma0(params):
    test = BreakAway(rates=(0.03,), final_force=0.01 * params["Fs"], n_points=2001)
    (setup,) = test.setups(params, LuGre())
    r = simulate(FrictionRig(params, LuGre(), "force"), setup.experiment,
                 solver_for(test, params))
    fit = r.time >= 0.05
    slope = np.polyfit(r["drive_force"][fit], r["position"][fit], 1)[0]
    assert 1.0 / slope == pytest.approx(params["sigma0"], rel=STIFFNESS_RTOL)


def test_presliding_loop_is_hysteretic_and_below_break_away(params, all_runs):
    table = all_runs["presliding"].table
    force = table["force [N]"].to_numpy()
    x = table["position [m]"].to_numpy()
    # displacement stays in the presliding range (a few Fs/sigma0), never gross sliding
    assert np.max(np.abs(x)) < 5 * params["Fs"] / params["sigma0"]
    # at the same force (0) the falling and rising branches sit at different positions
    t = all_runs["presliding"].result.time
    falling = (t > 1.0) & (t < 3.0)
    rising = t > 3.0
    x_fall = np.interp(0.0, force[falling][::-1], x[falling][::-1])
    x_rise = np.interp(0.0, force[rising], x[rising])
    assert x_fall - x_rise > 0.1 * params["Fs"] / params["sigma0"]


#: law -> the bristle bound its exact dynamics keep (with |z(0)| inside it)
INVARIANT_BOUNDS = {"lugre": "Fs", "lugre_decaying": "Fs", "dahl": "Fc"}


@pytest.mark.parametrize("law", [LuGre(), LuGre(decaying_damping=True), Dahl()],
                         ids=lambda law: law.kernel)
def test_bristle_bound_is_invariant_under_the_dynamics(params, law):
    """|σ0·z| <= Fs (LuGre) or Fc (Dahl) holds because on the bound dz/dt points inward
    for every velocity: checked on the law's rates themselves. (The integrator also
    projects every step onto that bound, so bounded outputs of a run prove nothing
    about the dynamics; this can fail.)"""
    bound = params[INVARIANT_BOUNDS[law.kernel]] / params["sigma0"]
    speeds = np.geomspace(1e-7, 1.0, 57)
    v = np.concatenate([speeds, -speeds, speeds, -speeds])
    z = np.concatenate([np.full(2 * speeds.size, bound), np.full(2 * speeds.size, -bound)])
    values = {name: params[name] for name in law.part().block.parameters}
    rates = friction_law_values(law, v, z, values)["rates"][:, 0]
    outward = np.sign(z) * rates
    assert np.all(outward <= BRISTLE_BOUND_RTOL * np.abs(v)), (v[outward > 0],
                                                               outward[outward > 0])
    # inside the bound the bristle moves with the velocity's sign (it is not stuck)
    inside = friction_law_values(law, v, 0.0 * z, values)["rates"][:, 0]
    assert np.all(np.sign(inside) == np.sign(v))


def test_dahl_steady_state_is_coulomb_plus_viscous(params):
    table = run_friction_test("steady-state", params, friction=Dahl()).table
    v = table["velocity [m/s]"].to_numpy()
    np.testing.assert_allclose(table["friction [N]"],
                               np.sign(v) * params["Fc"] + params["sigma2"] * v,
                               rtol=STEADY_STATE_RTOL)


def _reversal_experiment(amplitude: float) -> Experiment:
    """Position 0 → +A → −A → +A, slow (Dahl is rate independent without sigma2)."""
    drive = PiecewiseLinear([0.0, 1.0, 3.0, 5.0], [0.0, amplitude, -amplitude, amplitude])
    return Experiment(drive, "position", 5.0, n_points=2001, name="reversals")


def _dahl_closed_form(x: np.ndarray, fc: float, sigma0: float) -> np.ndarray:
    """dF/dx = sigma0·(1 − F·s/Fc) on each monotone leg, from F = 0 at x = 0."""
    force = np.empty_like(x)
    f_rev, x_rev = 0.0, x[0]
    direction = 1.0
    for i, xi in enumerate(x):
        step = np.sign(xi - x[i - 1]) if i else 1.0
        if step != 0 and step != direction:  # a reversal at the previous sample
            f_rev, x_rev, direction = force[i - 1], x[i - 1], step
        force[i] = direction * fc - (direction * fc - f_rev) * np.exp(
            -sigma0 * abs(xi - x_rev) / fc)
    return force


def test_dahl_follows_closed_form_through_reversals(params):
    p = params.replace(sigma2=0.0)
    amplitude = 5 * p["Fc"] / p["sigma0"]
    r = simulate(FrictionRig(p, Dahl(), "position"), _reversal_experiment(amplitude),
                 solver_for(StickSlip(), p))
    expected = _dahl_closed_form(r["position"], p["Fc"], p["sigma0"])
    np.testing.assert_allclose(r["friction"], expected, atol=DAHL_FORCE_ATOL * p["Fc"])
    assert np.max(np.abs(r["friction"])) > 0.99 * p["Fc"]  # saturated on each leg


def test_bouc_wen_reduces_to_dahl(params):
    p = params.replace(sigma2=0.0, bw_beta=1.0, bw_gamma=0.0, bw_n=1.0)
    exp = _reversal_experiment(5 * p["Fc"] / p["sigma0"])
    dahl = simulate(FrictionRig(p, Dahl(), "position"), exp, solver_for(StickSlip(), p))
    bouc_wen = simulate(FrictionRig(p, BoucWen(), "position"), exp, solver_for(StickSlip(), p))
    np.testing.assert_allclose(bouc_wen["friction"], dahl["friction"],
                               atol=BOUC_WEN_DAHL_ATOL * p["Fc"])


def test_bouc_wen_steady_sliding_is_coulomb_plus_viscous(params):
    table = run_friction_test("steady-state", params, friction=BoucWen()).table
    v = table["velocity [m/s]"].to_numpy()
    np.testing.assert_allclose(table["friction [N]"],
                               np.sign(v) * params["Fc"] + params["sigma2"] * v,
                               rtol=STEADY_STATE_RTOL)


def test_frictional_lag_loop_opens_with_frequency(params, all_runs):
    table = all_runs["frictional-lag"].table
    widths = {}
    for f, part in table.groupby("frequency [Hz]"):
        v = part["velocity [m/s]"].to_numpy()
        assert np.all(v > 0)  # never reverses
        widths[f] = lag_loop_width(v, part["friction [N]"].to_numpy())
    freqs = sorted(widths)
    assert all(widths[a] < widths[b] for a, b in itertools.pairwise(freqs))
    assert widths[freqs[-1]] > 0.05 * (params["Fs"] - params["Fc"])
    # the slowest loop hugs the steady-state (Stribeck) curve more closely than the fastest
    slow = table[table["frequency [Hz]"] == freqs[0]]
    fast = table[table["frequency [Hz]"] == freqs[-1]]
    dev = [np.max(np.abs(t["friction [N]"] - t["steady-state friction [N]"]))
           for t in (slow, fast)]
    assert dev[0] < 0.25 * dev[1]


def test_break_away_force_falls_with_force_rate(params, all_runs):
    table = all_runs["break-away"].table
    rates = table["force rate [N/s]"].to_numpy()
    peak = table["break-away force [N]"].to_numpy()
    applied = table["applied force at break-away [N]"].to_numpy()
    assert np.all(np.diff(rates) > 0)
    assert np.all(np.diff(peak) < 0)  # Canudas et al. 1995: varying break-away force
    fs, fc = params["Fs"], params["Fc"]
    assert peak[0] == pytest.approx(fs, rel=BREAK_AWAY_FS_RTOL)
    assert applied[0] == pytest.approx(fs, rel=BREAK_AWAY_FS_RTOL)
    assert fc < peak[-1] < fc + BREAK_AWAY_FAST_FRACTION * (fs - fc)
    assert np.all(applied >= peak - 1e-9)  # the applied force also accelerates the mass


def test_stick_slip_is_periodic_with_slip_at_static_friction(params):
    outcome = run_friction_test("stick-slip", params, t_end=STICK_SLIP_DURATION)
    r = outcome.result
    assert outcome.table is None and outcome.drive_quantity == "spring"
    onsets = slip_onsets(r, 10 * params["vs"])
    assert onsets.size >= 4
    periods = np.diff(onsets)[1:]
    assert np.ptp(periods) < PERIOD_RTOL * np.mean(periods)
    spring_force = params["k_drive"] * (r["drive_spring"] - r["position"])
    np.testing.assert_allclose(np.interp(onsets, r.time, spring_force), params["Fs"],
                               rtol=ONSET_FORCE_RTOL)
    # between slips the body sticks: velocity back to (almost) zero in every cycle
    for a, b in itertools.pairwise(onsets):
        inside = (r.time > a) & (r.time < b)
        assert np.min(np.abs(r["velocity"][inside])) < STUCK_VELOCITY_FRACTION * params["v_drive"]
        assert np.max(r["velocity"][inside]) > params["v_drive"]


def test_stick_slip_rodas4_agrees_with_scipy_radau(params):
    test = StickSlip(t_end=RADAU_SPAN)
    (setup,) = test.setups(params, LuGre())
    rig = FrictionRig(params, LuGre(), "spring")
    solver = solver_for(test, params)
    r = simulate(rig, setup.experiment, solver)
    prep = prepare(rig, setup.experiment, solver)
    kernel, prm, sig, ptr, bp, y0 = (prep.kernel, prep.vector, prep.sig, prep.ptr,
                                     prep.breakpoints, prep.y0)
    assert list(bp) == [0.0, RADAU_SPAN]
    ts = 0.5 * (bp[0] + bp[1])

    def rhs(t, y):
        dydt = np.empty(3)
        kernel.rhs(t, ts, y, prm, sig, ptr, dydt)
        return dydt

    def jac(t, y):
        out = np.zeros((3, 3))
        kernel.jac(t, ts, y, prm, sig, ptr, out)
        return out

    ref = solve_ivp(rhs, (0.0, RADAU_SPAN), y0, method="Radau", t_eval=r.time, jac=jac,
                    rtol=RADAU_RTOL, atol=STICK_SLIP_RADAU_ATOL)
    assert ref.success
    assert np.max(r["velocity"]) > params["v_drive"]  # the span includes a slip
    assert np.max(np.abs(r["position"] - ref.y[0])) < RADAU_POSITION_ATOL


def test_unknown_kind_and_misplaced_duration_are_rejected(params):
    with pytest.raises(ExperimentError, match="stick-slip"):
        run_friction_test("stiction", params)
    with pytest.raises(ExperimentError, match=r"unknown setting.*t_end"):
        run_friction_test("break-away", params, t_end=1.0)
    with pytest.raises(ExperimentError, match=r"rates = \[1.0, -2.0\]"):
        BreakAway(rates=(1.0, -2.0))
