"""Laws with presliding memory against LuGre on the 1995 rig (Canudas de Wit et al.):
no drift under a force below break-away, and the same stick-slip as LuGre when they
share its Fc, Fs and vs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pneumact as pa
from pneumact.analysis.friction_tests import run_friction_test, slip_onsets, solver_for
from pneumact.experiments import Experiment, Sine
from pneumact.experiments.friction import StickSlip
from pneumact.models import ElastoPlastic, FrictionRig, LuGre
from reference import (
    LUGRE_DRIFT_MIN_FRACTION,
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
        return pa.load_params("canudas1995-elastoplastic")  # z_ba = 0.95·Fc/σ0


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
    for law in (ElastoPlastic(),):
        positions = _cycle_end_positions(law, rig_params)
        assert np.ptp(positions[1:]) <= NO_DRIFT_RANGE_FRACTION * span, (law, positions)


def _stick_slip(law, params) -> tuple[float, float]:
    """The period of the stick-slip cycle and the spring force at slip onset."""
    run = run_friction_test("stick-slip", params, friction=law,
                            t_end=STICK_SLIP_DURATION).result
    onsets = slip_onsets(run, 10 * params["vs"])[1:]
    spring = params["k_drive"] * (run["drive_spring"] - run["position"])
    return float(np.mean(np.diff(onsets))), float(np.mean(np.interp(onsets, run.time, spring)))


@pytest.mark.parametrize("law", [ElastoPlastic()], ids=repr)
def test_stick_slip_with_lugre_s_coulomb_static_and_stribeck_is_lugre_s(law, rig_params):
    period, peak = _stick_slip(law, rig_params)
    lugre_period, lugre_peak = _stick_slip(LuGre(), rig_params)
    assert period == pytest.approx(lugre_period, rel=STICK_SLIP_LAW_RTOL)
    assert peak == pytest.approx(lugre_peak, rel=STICK_SLIP_LAW_RTOL)
