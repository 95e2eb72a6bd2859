"""The paper's quasi-static hysteresis test (Figs. 5-6): vgt-paper under a slow 100 → 20 →
100 kPa cycle. Known answers from the static force balance
(p_atm − p)·A_d = F0 + k·x ± F_friction:

- loop width in pressure at equal position ≈ 2·Fc/A_d (1.78 kPa),
- loop width in position at equal pressure ≈ 2·Fc/k (0.40 mm),
- motion starts between (F0 + Fc)/A_d and (F0 + Fs)/A_d of vacuum (+ k·threshold/A_d),
- the loop closes, and vanishes without Coulomb friction,
- the same width appears against the simulated chamber pressure behind a valve.

Loop widths come from ``pneumact.features`` (mean gap over the middle of the stroke).
"""

from __future__ import annotations

import numpy as np
import pytest

from pneumact.core.features import (
    loop_width_position,
    loop_width_pressure,
    motion_onset_pressure,
)
from pneumact.experiments.actuator import CommandCycle, PressureCycle
from pneumact.models import Actuator, CommandValve, CoulombViscous, PressureRegulator
from pneumact.simulation import Rodas4, simulate
from reference import (
    BREAKAWAY_THRESHOLD_FACTOR,
    LOOP_CLOSURE_TOL,
    LOOP_WIDTH_RTOL,
    NO_COULOMB_WIDTH_FRACTION,
    QUASI_STATIC_CYCLE,
    VALVE_LOOP_WIDTH_RTOL,
)

HIGH, LOW, PERIOD = QUASI_STATIC_CYCLE


@pytest.fixture(scope="module")
def paper_loop(vgt):
    """The paper's set-up: ideal pressure source, LuGre with delta = 1 (stick-slip)."""
    return simulate(Actuator(vgt), PressureCycle(HIGH, LOW, PERIOD), Rodas4())


def test_loop_width_in_pressure_is_twice_coulomb_over_area(paper_loop, vgt):
    width = loop_width_pressure(paper_loop["pressure"], paper_loop["position"])
    assert width == pytest.approx(2.0 * vgt["Fc"] / vgt["A_d"], rel=LOOP_WIDTH_RTOL)


def test_loop_width_in_position_is_twice_coulomb_over_stiffness(paper_loop, vgt):
    width = loop_width_position(paper_loop["pressure"], paper_loop["position"])
    assert width == pytest.approx(2.0 * vgt["Fc"] / vgt["k"], rel=LOOP_WIDTH_RTOL)


def test_motion_starts_at_preload_plus_breakaway_force(paper_loop, vgt):
    threshold = BREAKAWAY_THRESHOLD_FACTOR * vgt["Fs"] / vgt["sigma0"]  # beyond presliding
    p_break = motion_onset_pressure(paper_loop.time, paper_loop["pressure"],
                                    paper_loop["position"], threshold=threshold)
    vacuum = vgt["p_atm"] - p_break
    lowest = (vgt["F0"] + vgt["Fc"]) / vgt["A_d"]
    highest = (vgt["F0"] + vgt["Fs"] + vgt["k"] * threshold) / vgt["A_d"]
    assert lowest <= vacuum <= highest, (lowest, vacuum, highest)
    # and it has not moved (beyond presliding) before the preload is overcome
    x, p = paper_loop["position"], paper_loop["pressure"]
    before = (vgt["p_atm"] - p) * vgt["A_d"] < vgt["F0"]
    before &= paper_loop.time < PERIOD / 2
    assert np.all(np.abs(x[before] - x[0]) <= vgt["Fs"] / vgt["sigma0"])


def test_loop_closes(paper_loop, vgt):
    x = paper_loop["position"]
    assert np.ptp(x) > 0.01
    assert abs(x[-1] - x[0]) <= LOOP_CLOSURE_TOL


def test_loop_vanishes_without_coulomb_friction(vgt):
    params = vgt.replace(Fc=0.0)  # viscous sigma2 only
    r = simulate(Actuator(params, friction=CoulombViscous()),
                 PressureCycle(HIGH, LOW, PERIOD), Rodas4(rtol=1e-6))
    width = loop_width_pressure(r["pressure"], r["position"])
    assert width <= NO_COULOMB_WIDTH_FRACTION * 2.0 * vgt["Fc"] / vgt["A_d"]


@pytest.mark.parametrize("valve", ["regulator", "command"])
def test_valve_driven_loop_against_chamber_pressure(valve, vgt):
    if valve == "regulator":
        model = Actuator(vgt, valve=PressureRegulator())
        experiment = PressureCycle(HIGH, LOW, PERIOD)
    else:
        model = Actuator(vgt, valve=CommandValve())
        experiment = CommandCycle(0.0, 1.0, PERIOD)
    r = simulate(model, experiment, Rodas4(rtol=1e-6))
    assert np.ptp(r["position"]) > 0.01
    width = loop_width_pressure(r["pressure"], r["position"])
    assert width == pytest.approx(2.0 * vgt["Fc"] / vgt["A_d"], rel=VALVE_LOOP_WIDTH_RTOL)
