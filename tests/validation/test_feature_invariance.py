"""Features measure the actuator, not a threshold (issue #19): the break-away pressure does
not see the bristle stiffness σ0, the loop width does not see the bristle damping σ1, and
both equal the steady sliding friction at the measured sliding speed, so the loop width is
2·Fc/A_d only while that speed is well above vs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import reference as ref
from pneumact.experiments.actuator import CommandCycle, PressureCycle
from pneumact.models import Actuator, CommandValve, LuGre, PressureSource
from pneumact.simulation import simulate
from pneumact.simulation.batch import simulate_batch

DEFAULT_CYCLES = {  # the default cycles of `pneumact simulate` and `pneumact sensitivity`
    "source": (PressureSource, PressureCycle(100e3, 20e3, 20.0)),
    "command": (CommandValve, CommandCycle(0.0, 1.0, 20.0)),
}


def _batch(vgt, valve: str, name: str, factors) -> pd.DataFrame:
    cls, experiment = DEFAULT_CYCLES[valve]
    table = pd.DataFrame({name: vgt[name] * np.asarray(factors)})
    result = simulate_batch(Actuator(vgt, valve=cls()), experiment, table)
    assert (result.table["status"] == "ok").all(), result.failed
    return result.table


@pytest.mark.parametrize("valve", list(DEFAULT_CYCLES))
def test_breakaway_does_not_see_sigma0(vgt, valve):
    table = _batch(vgt, valve, "sigma0", ref.SIGMA0_FACTORS)
    assert np.ptp(table["breakaway_pressure"]) <= ref.BREAKAWAY_SIGMA0_SPREAD


def test_loop_width_does_not_see_sigma1(vgt):
    table = _batch(vgt, "command", "sigma1", ref.SIGMA1_FACTORS)
    width = table["loop_width_pressure"]
    assert np.ptp(width) <= ref.SIGMA1_WIDTH_RTOL * width.mean()
    travel = table["presliding_travel"]
    assert np.ptp(travel) >= ref.SIGMA1_PRESLIDING_MIN_CHANGE * travel.mean()


@pytest.mark.parametrize("period", [20.0, 320.0])
def test_breakaway_and_width_are_the_sliding_friction_at_the_sliding_speed(vgt, period):
    run = simulate(Actuator(vgt, valve=CommandValve()), CommandCycle(0.0, 1.0, period))
    summary = run.summary()
    speed = summary["sliding_speed"]
    sliding = float(LuGre().steady_force(np.array([speed]), vgt)[0])  # g(v) + σ2·v
    vacuum = vgt["p_atm"] - summary["breakaway_pressure"]
    assert vacuum == pytest.approx((vgt["F0"] + sliding) / vgt["A_d"],
                                   rel=ref.SLIDING_LEVEL_BREAKAWAY_RTOL)
    assert summary["loop_width_pressure"] == pytest.approx(2 * sliding / vgt["A_d"],
                                                           rel=ref.SLIDING_LEVEL_WIDTH_RTOL)
    # and 2·Fc/A_d only where the loop slides well above vs
    quasi_static = 2 * vgt["Fc"] / vgt["A_d"]
    above_vs = speed > 5 * vgt["vs"]
    assert (abs(summary["loop_width_pressure"] / quasi_static - 1) < 0.01) == above_vs
