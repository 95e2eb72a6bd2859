"""Laws with presliding memory against LuGre on the 1995 rig (Canudas de Wit et al.):
no drift under a force below break-away, and the same stick-slip as LuGre when they
share its Fc, Fs and vs."""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import pytest

import pneumact as pa
from pneumact.analysis.friction_tests import run_friction_test, slip_onsets, solver_for
from pneumact.experiments import Experiment, PiecewiseLinear, Sine
from pneumact.experiments.friction import StickSlip
from pneumact.models import GMS, ElastoPlastic, FrictionRig, LuGre
from reference import (
    KNEE_SLOPE_RTOL,
    LUGRE_DRIFT_MIN_FRACTION,
    LUGRE_OPEN_MIN,
    MAXWELL_SLIP_ATOL,
    MEMORY_CLOSE_ATOL,
    NO_DRIFT_RANGE_FRACTION,
    STICK_SLIP_DURATION,
    STICK_SLIP_LAW_RTOL,
)

#: a force 0.5 ± 0.4 N at 1 Hz for 10 cycles, below Fc = 1 N
CYCLES = 10
FORCE_BELOW_BREAK_AWAY = Experiment(Sine(0.4, 1.0, offset=0.5), "force", float(CYCLES),
                                    n_points=100 * CYCLES + 1, name="force below break-away")


@pytest.fixture(scope="module")
def rig_params():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)  # the 1995 paper's σ1
        # the two shipped sets share the 1995 values; z_ba = 0.95·Fc/σ0, and 4 blocks
        params = pa.load_params("canudas1995-elastoplastic")
        blocks = pa.load_params("canudas1995-gms4")
        return params.replace({name: blocks[name] for name in GMS(4).block.parameters
                               if name.startswith("gms_")})


def _cycle_end_positions(law, params) -> np.ndarray:
    run = pa.simulate(FrictionRig(params, law, "force"), FORCE_BELOW_BREAK_AWAY,
                      solver_for(StickSlip(), params, law))
    return run["position"][::100]


def test_a_force_below_break_away_moves_lugre_on_but_not_the_memory_laws(rig_params):
    """Dupont et al. 2002, Fig. 1: LuGre's bristle creeps at any force, so an oscillating
    force below break-away walks the body away cycle after cycle; the elasto-plastic
    bristle is a spring below z_ba and the body comes back to the same place."""
    span = LuGre().presliding_range(rig_params)
    lugre = _cycle_end_positions(LuGre(), rig_params)
    assert np.all(np.diff(lugre[1:]) > LUGRE_DRIFT_MIN_FRACTION * span), lugre
    for law in (ElastoPlastic(), GMS(4)):
        positions = _cycle_end_positions(law, rig_params)
        assert np.ptp(positions[1:]) <= NO_DRIFT_RANGE_FRACTION * span, (law, positions)


def _stick_slip(law, params) -> tuple[float, float]:
    """The period of the stick-slip cycle and the spring force at slip onset."""
    run = run_friction_test("stick-slip", params, friction=law,
                            t_end=STICK_SLIP_DURATION).result
    onsets = slip_onsets(run, 10 * params["vs"])[1:]
    spring = params["k_drive"] * (run["drive_spring"] - run["position"])
    return float(np.mean(np.diff(onsets))), float(np.mean(np.interp(onsets, run.time, spring)))


@pytest.mark.parametrize("law", [ElastoPlastic(), GMS(4)], ids=repr)
def test_stick_slip_with_lugre_s_coulomb_static_and_stribeck_is_lugre_s(law, rig_params):
    period, peak = _stick_slip(law, rig_params)
    lugre_period, lugre_peak = _stick_slip(LuGre(), rig_params)
    margin = STICK_SLIP_LAW_RTOL[law.name]
    assert period == pytest.approx(lugre_period, rel=margin)
    assert peak == pytest.approx(lugre_peak, rel=margin)


# --------------------------------------------------- GMS: presliding with non-local memory
#: a slow prescribed position (1e-5 m/s, 1 % of vs: g(v) is Fs to 1e-4) through the
#: virgin curve to +A, down to −A, up to B, an inner loop B → C → B, and on to +A
MEMORY_PATH_UM = (0.0, 80.0, -80.0, 40.0, 10.0, 40.0, 80.0)
MEMORY_SPEED = 1e-5


def _memory_experiment() -> tuple[Experiment, np.ndarray]:
    x = np.asarray(MEMORY_PATH_UM) * 1e-6
    t = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)) / MEMORY_SPEED)])
    experiment = Experiment(PiecewiseLinear(t.tolist(), x.tolist()), "position",
                            float(t[-1]), n_points=round(t[-1] / 0.05) + 1, name="nested")
    return experiment, t


def _maxwell_slip(x: np.ndarray, stiffness: np.ndarray, deflection: np.ndarray) -> np.ndarray:
    """Σ kᵢ·zᵢ of elastic-perfectly-plastic blocks (yield deflection Δᵢ) along a path
    x: each leg from a reversal moves zᵢ with x and clips it at ±Δᵢ."""
    z = np.zeros_like(deflection)
    force = np.empty_like(x)
    x_prev = x[0]
    for j, xj in enumerate(x):
        z = np.clip(z + (xj - x_prev), -deflection, deflection)
        x_prev = xj
        force[j] = float(stiffness @ z)
    return force


@pytest.fixture(scope="module")
def gms_params():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)
        return pa.load_params("canudas1995-gms4").replace(sigma1=0.0, sigma2=0.0)


@pytest.fixture(scope="module")
def nested_runs(gms_params):
    experiment, corners = _memory_experiment()
    runs = {}
    for law in (GMS(4), LuGre()):
        runs[law.name] = pa.simulate(FrictionRig(gms_params, law, "position"), experiment,
                                     solver_for(StickSlip(), gms_params, law))
    return runs, corners


def test_gms_follows_the_maxwell_slip_blocks_through_nested_reversals(gms_params,
                                                                      nested_runs):
    """Slowly, a GMS block is an elastic-perfectly-plastic spring (Al-Bender et al. 2005,
    sec. II): the friction force is Σ kᵢ·clip(...) of the blocks, exactly."""
    runs, _ = nested_runs
    run = runs["GMS"]
    law = GMS(4)
    stiffness = np.array([gms_params[f"gms_k{i}"] for i in range(1, 5)])
    expected = _maxwell_slip(run["position"], stiffness,
                             law.break_away_deflections(gms_params))
    np.testing.assert_allclose(run["friction"], expected,
                               atol=MAXWELL_SLIP_ATOL * gms_params["Fs"])


def test_gms_virgin_curve_has_a_knee_at_each_block_break_away(gms_params, nested_runs):
    """From rest the slope dF/dx is the stiffness of the blocks still stuck: Σk down to
    the last block's kN, dropping at each break-away deflection νᵢ·Fs/kᵢ."""
    runs, corners = nested_runs
    run = runs["GMS"]
    first = run.time <= corners[1]
    x, force = run["position"][first], run["friction"][first]
    knees = np.sort(GMS(4).break_away_deflections(gms_params))
    stiffness = np.array([gms_params[f"gms_k{i}"] for i in range(1, 5)])
    deflections = GMS(4).break_away_deflections(gms_params)
    edges = np.concatenate([[0.0], knees, [x.max()]])
    for lo, hi in itertools.pairwise(edges):
        inside = (x > lo + 0.1 * (hi - lo)) & (x < hi - 0.1 * (hi - lo))
        slope = np.polyfit(x[inside], force[inside], 1)[0]
        stuck = stiffness[deflections > 0.5 * (lo + hi)].sum()
        assert slope == pytest.approx(stuck, rel=KNEE_SLOPE_RTOL, abs=1e-9), (lo, hi)


def _force_at_inner_reversal(run, corners) -> tuple[float, float]:
    """F at B on the way up, before the inner loop and after it closed."""
    before = np.interp(corners[3], run.time, run["friction"])
    after = np.interp(corners[5], run.time, run["friction"])
    return before, after


def test_gms_inner_loop_closes_at_its_reversal_point_and_lugre_s_does_not(gms_params,
                                                                         nested_runs):
    """Non-local memory: after the inner loop B → C → B the force at B is what it was,
    and the curve goes on as if the loop had not been (wiping-out). LuGre's bristle has
    one state and forgets: its loop does not close."""
    runs, corners = nested_runs
    before, after = _force_at_inner_reversal(runs["GMS"], corners)
    assert after == pytest.approx(before, abs=MEMORY_CLOSE_ATOL * gms_params["Fs"])
    lugre_before, lugre_after = _force_at_inner_reversal(runs["LuGre"], corners)
    assert abs(lugre_after - lugre_before) > LUGRE_OPEN_MIN * gms_params["Fs"]
