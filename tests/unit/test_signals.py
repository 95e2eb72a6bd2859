"""Input signals: values, slopes, breakpoints, jumps, algebra and rejected input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumact.core.signals import (
    Constant,
    PiecewiseLinear,
    Ramp,
    Sine,
    Step,
    Triangle,
)
from pneumact.errors import ExperimentError
from reference import (
    ROUND_OFF_ATOL,
    SIGNAL_RTOL,
)


def test_step_is_right_continuous_with_one_breakpoint():
    step = Step(1.5, before=2.0, after=7.0)
    assert step(1.5 - 1e-9) == 2.0
    assert step(1.5) == 7.0
    assert step(10.0) == 7.0
    np.testing.assert_array_equal(step.breakpoints(), [1.5])


def test_ramp_values_slope_and_breakpoints():
    ramp = Ramp(10.0, 30.0, duration=4.0, t_start=1.0)
    value, slope = ramp.evaluate(np.array([0.0, 1.0, 2.0, 5.0, 9.0]))
    np.testing.assert_allclose(value, [10.0, 10.0, 15.0, 30.0, 30.0], rtol=SIGNAL_RTOL)
    np.testing.assert_allclose(slope, [0.0, 5.0, 5.0, 0.0, 0.0], rtol=SIGNAL_RTOL)
    np.testing.assert_array_equal(ramp.breakpoints(), [1.0, 5.0])


def test_triangle_values_and_corners():
    tri = Triangle(100e3, 20e3, period=20.0, cycles=2)
    t = np.array([0.0, 5.0, 10.0, 15.0, 20.0, 30.0, 40.0, 50.0])
    np.testing.assert_allclose(tri(t), [100e3, 60e3, 20e3, 60e3, 100e3, 20e3, 100e3, 100e3],
                               rtol=SIGNAL_RTOL)
    np.testing.assert_array_equal(tri.breakpoints(), [0.0, 10.0, 20.0, 30.0, 40.0])
    _, slope = tri.evaluate(np.array([5.0, 15.0]))
    np.testing.assert_allclose(slope, [-8e3, 8e3], rtol=SIGNAL_RTOL)


def test_sine_value_slope_and_window():
    sine = Sine(amplitude=2.0, frequency=0.5, offset=1.0, t_start=1.0, t_stop=3.0)
    t = np.array([0.0, 1.0, 1.5, 2.0, 2.5, 4.0])
    expected = 1.0 + 2.0 * np.sin(math.pi * (np.clip(t, 1.0, 3.0) - 1.0))
    value, slope = sine.evaluate(t)
    np.testing.assert_allclose(value, expected, rtol=SIGNAL_RTOL, atol=ROUND_OFF_ATOL)
    assert slope[1] == pytest.approx(2.0 * math.pi, rel=SIGNAL_RTOL)  # 2·ω·cos(0)
    assert slope[0] == 0.0 and slope[-1] == 0.0
    bp = sine.breakpoints()  # the window edges (a constant offset may add t = 0)
    assert {1.0, 3.0} <= set(bp.tolist())
    assert not np.any((bp > 1.0) & (bp < 3.0))


def test_sum_and_scaling():
    total = 2.0 * Ramp(0.0, 1.0, duration=2.0) + Step(1.0, 0.0, 3.0) + 0.5
    t = np.array([0.0, 0.5, 1.0, 2.0, 3.0])
    np.testing.assert_allclose(total(t), [0.5, 1.0, 4.5, 5.5, 5.5], rtol=SIGNAL_RTOL)
    np.testing.assert_array_equal(total.breakpoints(), [0.0, 1.0, 2.0])
    scaled = Sine(1.0, 1.0) * 3.0
    assert scaled(0.25) == pytest.approx(3.0, rel=SIGNAL_RTOL)
    assert Constant(4.0)(123.0) == 4.0


def test_piecewise_linear_repeated_time_is_a_jump():
    pwl = PiecewiseLinear([0.0, 1.0, 1.0, 2.0], [0.0, 1.0, 5.0, 6.0])
    np.testing.assert_allclose(pwl(np.array([0.5, 1.0, 1.5, 3.0])), [0.5, 5.0, 5.5, 6.0],
                               rtol=SIGNAL_RTOL)


def test_piecewise_linear_rejects_decreasing_time():
    with pytest.raises(ExperimentError, match=r"time must not decrease.*t\[2\]"):
        PiecewiseLinear([0.0, 2.0, 1.0], [0.0, 1.0, 2.0])


@pytest.mark.parametrize(("t", "y"), [([0.0, np.nan, 2.0], [0.0, 1.0, 2.0]),
                                      ([0.0, 1.0, 2.0], [0.0, np.inf, 2.0])])
def test_piecewise_linear_rejects_non_finite_samples(t, y):
    with pytest.raises(ExperimentError, match="sample 1 is not finite"):
        PiecewiseLinear(t, y)


def test_piecewise_linear_rejects_length_mismatch_and_bad_ramp():
    with pytest.raises(ExperimentError, match="same non-zero length"):
        PiecewiseLinear([0.0, 1.0], [0.0])
    with pytest.raises(ExperimentError, match="duration"):
        Ramp(0.0, 1.0, duration=0.0)
    with pytest.raises(ExperimentError, match="frequency"):
        Sine(1.0, frequency=0.0)


def test_what_an_experiment_remembers_is_handed_out_as_copies():
    """A run asks an experiment for its breakpoints and its inputs' extremes (the drive's
    range check) once and then from memory: a caller that changes what it got changes
    nothing the next caller sees, and the answers are a fresh experiment's."""
    from pneumact.experiments import Experiment

    def make() -> Experiment:
        drive = PiecewiseLinear([0.0, 0.2, 0.2, 0.5], [1.0, 1.0, 3.0, 2.0]) + \
            Step(0.4, 0.0, 1.0)
        return Experiment(drive, "pressure", 0.5, drives={"force": Constant(2.0)})

    experiment, fresh = make(), make()
    for ask in (Experiment.breakpoints, Experiment.input_extremes):
        got = ask(experiment)
        if isinstance(got, dict):
            got.clear()
        else:
            got[:] = -1.0
    np.testing.assert_array_equal(experiment.breakpoints(), fresh.breakpoints())
    assert experiment.input_extremes() == fresh.input_extremes()
    extremes = experiment.input_extremes()
    assert extremes["pressure"] == pytest.approx((1.0, 10.0 / 3.0), rel=SIGNAL_RTOL)  # 0.4 s
    assert extremes["force"] == (2.0, 2.0)
