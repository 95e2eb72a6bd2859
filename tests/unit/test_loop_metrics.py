"""Loop metrics on synthetic responses with known answers, and the loop figure."""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

import reference as ref
from pneumact import Result
from pneumact.control.metrics import LoopMetrics, loop_metrics
from pneumact.errors import DataError

TAU, ZETA, OMEGA_N = ref.LOOP_TAU, ref.LOOP_ZETA, ref.LOOP_OMEGA_N


def _frame(t, x, r, v=None, u=None, units=None) -> pd.DataFrame:
    columns = {"time": t, "position": x, "position_setpoint": r}
    if v is not None:
        columns["velocity"] = v
    if u is not None:
        columns["command"] = u
    frame = pd.DataFrame(columns)
    if units:
        frame.attrs["units"] = units
    return frame


def _grid(t_end: float, dt: float = ref.LOOP_DT) -> np.ndarray:
    return np.linspace(0.0, t_end, round(t_end / dt) + 1)


def _first_order(t_end=10.0, t_step=1.0, down=False, gain=1.0):
    """x = start + gain·(1 − e^(−(t − t1)/τ))·(target − start) after the step at t1."""
    t = _grid(t_end)
    t1 = t[np.argmin(np.abs(t - t_step))]  # the step on a sample
    s = np.maximum(t - t1, 0.0)
    y = gain * (1.0 - np.exp(-s / TAU))
    dy = np.where(t >= t1, gain * np.exp(-s / TAU) / TAU, 0.0)  # right derivative at t1
    if down:
        return t, t1, 1.0 - y, np.where(t >= t1, 0.0, 1.0), -dy
    return t, t1, y, np.where(t >= t1, 1.0, 0.0), dy  # right-continuous, as pneumact's


def _second_order(s):
    """Unit step response of ωn²/(s² + 2ζωn·s + ωn²), ζ < 1."""
    wd = OMEGA_N * math.sqrt(1.0 - ZETA**2)
    phi = math.acos(ZETA)
    return 1.0 - np.exp(-ZETA * OMEGA_N * s) / math.sqrt(1 - ZETA**2) * np.sin(wd * s + phi)


# --------------------------------------------------------------------------- step response


@pytest.mark.parametrize("down", [False, True], ids=["up", "down"])
def test_first_order_step(down):
    t, t1, x, r, v = _first_order(down=down)
    u = 2.0 * (r - x)  # a P controller's command, kp = 2
    m = loop_metrics(_frame(t, x, r, v, u))
    rtol = ref.LOOP_CROSSING_RTOL
    assert m.t_step == t1
    assert (m.start, m.target) == ((1.0, 0.0) if down else (0.0, 1.0))
    assert m.rise_time == pytest.approx(TAU * math.log(9.0), rel=rtol)
    assert m.settling_time == pytest.approx(TAU * math.log(50.0), rel=rtol)
    assert m.overshoot == 0.0
    # the default window is the last 10 % (1 s): a monotone approach does not widen it
    assert m.window == pytest.approx(1.0, rel=ref.REL_TOL)
    mean_gap = TAU * (math.exp(-8.0 / TAU) - math.exp(-9.0 / TAU))  # ∫ e^(−s/τ) over [8, 9]
    assert m.steady_state_error == pytest.approx(-mean_gap if down else mean_gap,
                                                 rel=ref.LOOP_INTEGRAL_RTOL)
    # |e| = e^(−s/τ) from the step on, 0 before; the trapezoid of the sample interval
    # before the step draws the jump 0 → 1 as a straight line: + dt/2 to both integrals
    T, dt = t[-1] - t1, t[1] - t[0]
    iae = TAU * (1.0 - math.exp(-T / TAU)) + dt / 2
    ise = TAU / 2 * (1.0 - math.exp(-2 * T / TAU)) + dt / 2
    assert m.iae == pytest.approx(iae, rel=ref.LOOP_INTEGRAL_RTOL)
    assert m.ise == pytest.approx(ise, rel=ref.LOOP_INTEGRAL_RTOL)
    assert m.control_effort == pytest.approx(4.0 * ise, rel=ref.LOOP_INTEGRAL_RTOL)
    # |u| jumps by 2 at the step, then decays to 2e^(−T/τ): variation 2 + 2(1 − e^(−T/τ))
    assert m.command_variation == pytest.approx(4.0 - 2.0 * math.exp(-T / TAU),
                                                rel=ref.REL_TOL)
    assert not m.hunting and math.isnan(m.limit_cycle_period)
    # stick: |v| ≤ 1e-3·max|v| = 1e-3/τ once e^(−s/τ) ≤ 1e-3, i.e. from s = τ·ln 1000 on
    assert m.stick_speed == pytest.approx(1e-3 / TAU, rel=ref.REL_TOL)
    assert m.stick_count == 1
    assert m.stick_time == pytest.approx(T - TAU * math.log(1000.0), rel=ref.LOOP_CROSSING_RTOL)
    assert m.mean_stick_duration == m.stick_time


@pytest.mark.parametrize("down", [False, True], ids=["up", "down"])
def test_underdamped_second_order_step(down):
    t = _grid(6.0)
    t1 = t[np.argmin(np.abs(t - 1.0))]  # the step on a sample
    s = np.maximum(t - t1, 0.0)
    y = np.where(t > t1, _second_order(s), 0.0)
    x, r = (1.0 - y, np.where(t >= t1, 0.0, 1.0)) if down else (y, np.where(t >= t1, 1.0, 0.0))
    m = loop_metrics(_frame(t, x, r), window=1.0)
    assert m.t_step == t1
    expected = 100.0 * math.exp(-math.pi * ZETA / math.sqrt(1.0 - ZETA**2))
    assert m.overshoot == pytest.approx(expected, rel=ref.LOOP_PEAK_RTOL)
    # rise: the analytic 10 % and 90 % crossings, by root finding on y itself
    t_peak = math.pi / (OMEGA_N * math.sqrt(1.0 - ZETA**2))
    t10 = brentq(lambda s: _second_order(s) - 0.1, 0.0, t_peak)
    t90 = brentq(lambda s: _second_order(s) - 0.9, 0.0, t_peak)
    assert m.rise_time == pytest.approx(t90 - t10, rel=ref.LOOP_CROSSING_RTOL)
    # settling: on the band's edge then, inside it afterwards (checked on a finer grid)
    s_settle = m.settling_time
    assert abs(_second_order(s_settle) - 1.0) == pytest.approx(0.02, rel=ref.LOOP_CROSSING_RTOL)
    after = np.linspace(s_settle, 5.0, 200_001)
    assert np.max(np.abs(_second_order(after) - 1.0)) <= 0.02 * (1 + ref.LOOP_CROSSING_RTOL)
    # ... and outside it within the half period before: the last exit, not an earlier one
    half_period = math.pi / (OMEGA_N * math.sqrt(1.0 - ZETA**2))
    before = np.linspace(s_settle - half_period, s_settle, 20_001)
    assert np.max(np.abs(_second_order(before) - 1.0)) > 0.02


def test_a_record_that_never_reaches_the_target():
    t, t1, x, r, v = _first_order(gain=0.5)  # stalls half-way
    m = loop_metrics(_frame(t, x, r, v))
    assert math.isnan(m.rise_time) and math.isnan(m.settling_time)
    assert m.overshoot == 0.0
    assert m.steady_state_error == pytest.approx(0.5, rel=ref.LOOP_CROSSING_RTOL)
    assert not m.hunting
    # never arrives: stick phases count from the step; it creeps to a halt once
    # 0.5·e^(−s/τ)/τ ≤ 1e-3·0.5/τ
    assert m.stick_count == 1
    assert m.stick_time == pytest.approx(t[-1] - t1 - TAU * math.log(1000.0),
                                         rel=ref.LOOP_CROSSING_RTOL)


def test_piecewise_linear_step_is_exact():
    """A ramp from 0 to 1 over 1 s, then still: every metric is exact on straight lines."""
    t = _grid(5.0, 1e-3)
    x = np.clip(t - 1.0, 0.0, 1.0)
    r = np.where(t > 1.0, 1.0, 0.0)  # left-valued at 1 s: found one sample late ...
    assert loop_metrics(_frame(t, x, r)).t_step == pytest.approx(1.001, rel=ref.REL_TOL)
    m = loop_metrics(_frame(t, x, r), t_step=1.0, band=0.05)  # ... so given
    assert m.rise_time == pytest.approx(0.8, rel=ref.REL_TOL)
    assert m.settling_time == pytest.approx(0.95, rel=ref.REL_TOL)
    assert (m.overshoot, m.limit_cycle_amplitude) == (0.0, 0.0)
    assert m.steady_state_error == pytest.approx(0.0, abs=ref.ROUND_OFF_ATOL)
    assert math.isnan(m.limit_cycle_period) and not m.hunting


def test_explicit_start_target_and_a_constant_setpoint():
    """A set-point that never changes: the step starts at t0 from the initial position."""
    t, _, x, _, v = _first_order(t_step=0.0)
    m = loop_metrics(_frame(t, x, np.ones_like(t), v))
    assert (m.t_step, m.start, m.target) == (0.0, 0.0, 1.0)
    assert m.rise_time == pytest.approx(TAU * math.log(9.0), rel=ref.LOOP_CROSSING_RTOL)
    # measured against another target, 0.8: the response overshoots it by 25 %
    m = loop_metrics(_frame(t, x, np.ones_like(t), v), target=0.8)
    assert m.overshoot == pytest.approx(25.0, rel=ref.LOOP_PEAK_RTOL)
    assert m.steady_state_error == pytest.approx(-0.2, rel=ref.LOOP_CROSSING_RTOL)
    assert math.isnan(m.settling_time)


def test_a_zero_step_has_no_step_metrics():
    t = _grid(2.0, 1e-3)
    m = loop_metrics(_frame(t, np.full_like(t, 0.3), np.full_like(t, 0.3)))
    assert math.isnan(m.rise_time) and math.isnan(m.settling_time) and math.isnan(m.overshoot)
    assert (m.iae, m.limit_cycle_amplitude, m.hunting) == (0.0, 0.0, False)


# --------------------------------------------------------------------------- limit cycles


def test_sine_about_the_target_is_a_limit_cycle():
    amplitude, period = ref.LOOP_CYCLE_AMPLITUDE, ref.LOOP_CYCLE_PERIOD
    t = _grid(40.0, ref.LOOP_CYCLE_DT)
    w = 2 * math.pi / period
    x = 1.0 + amplitude * np.sin(w * t)
    v = amplitude * w * np.cos(w * t)
    frame = _frame(t, x, np.ones_like(t), v)
    m = loop_metrics(frame, start=0.0)
    assert m.limit_cycle_amplitude == pytest.approx(amplitude, rel=ref.LOOP_PEAK_RTOL)
    assert m.limit_cycle_period == pytest.approx(period, abs=ref.LOOP_PERIOD_SAMPLES *
                                                 ref.LOOP_CYCLE_DT)
    assert m.hunting  # 0.05 > 2 % of the unit step
    # default window: 10 % of 40 s = 2 periods, widened to 2.5 periods = 5 s, whose mean
    # is the half period left over: (A/5 s)·∫ sin over [35, 40] s = −2A/(5π)
    assert m.window == pytest.approx(2.5 * period, abs=ref.LOOP_PERIOD_SAMPLES *
                                     ref.LOOP_CYCLE_DT * 2.5)
    assert m.steady_state_error == pytest.approx(2 * amplitude / (5 * math.pi),
                                                 rel=ref.LOOP_INTEGRAL_RTOL)
    # over whole periods the mean is the target
    m4 = loop_metrics(frame, start=0.0, window=2 * period)
    assert m4.steady_state_error == pytest.approx(0.0, abs=ref.LOOP_INTEGRAL_RTOL * amplitude)
    assert m4.limit_cycle_period == pytest.approx(period, abs=ref.LOOP_PERIOD_SAMPLES *
                                                  ref.LOOP_CYCLE_DT)
    # reversals pass |v| ≤ stick_speed only for ~2e-3/ω = 0.6 ms: not stick phases
    assert (m.stick_count, m.stick_time) == (0, 0.0) and math.isnan(m.mean_stick_duration)
    # the same cycle inside a wider band is not hunting
    assert not loop_metrics(frame, start=0.0, band=0.1).hunting


def _stick_slip():
    """Slip 0 → 1 m over [0, 1] s, then alternately down and up by 0.1 m over
    [3k, 3k + 1] s (k = 1..9), still in between: half-sine velocity pulses."""
    t = _grid(30.0, ref.LOOP_CYCLE_DT)
    x = np.empty_like(t)
    v = np.zeros_like(t)
    big = t <= 1.0
    x[big] = (1.0 - np.cos(np.pi * t[big])) / 2
    v[big] = np.pi / 2 * np.sin(np.pi * t[big])
    level = 1.0
    for k in range(1, 11):
        still = (t > 3 * k - 2) & (t <= 3 * k)
        x[still] = level
        if k == 10:
            break
        slip = (t > 3 * k) & (t <= 3 * k + 1)
        sign = -1.0 if k % 2 else 1.0
        s = t[slip] - 3 * k
        x[slip] = level + sign * 0.05 * (1.0 - np.cos(np.pi * s))
        v[slip] = sign * 0.05 * np.pi * np.sin(np.pi * s)
        level = round(level + sign * 0.1, 12)
    return t, x, v


def test_stick_slip_hunting():
    t, x, v = _stick_slip()
    m = loop_metrics(_frame(t, x, np.ones_like(t), v))
    assert (m.t_step, m.start, m.target) == (0.0, 0.0, 1.0)
    # the position hunts between 0.9 and 1 m with a 6 s period (plateaus at 1 m: 19-21,
    # 25-27 s in the second half of the record)
    assert m.limit_cycle_amplitude == pytest.approx(0.05, rel=ref.REL_TOL)
    assert m.limit_cycle_period == pytest.approx(6.0, abs=ref.LOOP_PERIOD_SAMPLES *
                                                 ref.LOOP_CYCLE_DT)
    assert m.hunting
    assert m.window == pytest.approx(15.0, rel=ref.REL_TOL)  # 2.5 periods, capped at 15 s
    # stick phases: 10 of 2 s after the arrival in the band (t = 0.91 s), each widened by
    # the time the neighbouring slips spend below stick_speed = 1e-3·π/2:
    # δ = arcsin(vs/V)/π at each end of a slip of peak speed V
    vs = m.stick_speed
    assert vs == pytest.approx(1e-3 * np.pi / 2, rel=ref.LOOP_PEAK_RTOL)
    d_big = math.asin(vs / (np.pi / 2)) / np.pi
    d_small = math.asin(vs / (0.05 * np.pi)) / np.pi
    assert m.stick_count == 10
    assert m.stick_time == pytest.approx(20.0 + d_big + 18 * d_small, abs=ref.LOOP_STICK_ATOL)
    assert m.mean_stick_duration == pytest.approx(m.stick_time / 10, rel=ref.REL_TOL)
    # a stick_speed of zero counts only the exactly still samples: each run spans its
    # samples, one sample interval short of 2 s (no crossing to interpolate at |v| = 0)
    m0 = loop_metrics(_frame(t, x, np.ones_like(t), v), stick_speed=0.0)
    assert m0.stick_count == 10
    assert m0.stick_time == pytest.approx(20.0 - 10 * ref.LOOP_CYCLE_DT,
                                          abs=ref.LOOP_STICK_ATOL)


def test_velocity_from_the_position_when_absent():
    t, x, v = _stick_slip()
    with_v = loop_metrics(_frame(t, x, np.ones_like(t), v))
    without = loop_metrics(_frame(t, x, np.ones_like(t)))
    assert without.stick_count == with_v.stick_count
    # np.gradient is O(dt²) accurate inside the slips: the same speed scale; a stick end
    # where the velocity reaches zero with a kink (the big slip's end) moves by < 1 sample
    assert without.stick_speed == pytest.approx(with_v.stick_speed, rel=ref.LOOP_GRADIENT_RTOL)
    assert without.stick_time == pytest.approx(with_v.stick_time, abs=ref.LOOP_CYCLE_DT)


# --------------------------------------------------------------------------- inputs, outputs


def test_result_and_frame_give_the_same_metrics():
    t, _, x, r, v = _first_order()
    u = 3.0 + 2.0 * (r - x)
    result = Result(t, {"position": x, "velocity": v, "position_setpoint": r, "command": u},
                    {"position": "m", "velocity": "m/s", "position_setpoint": "m", "command": "N"})
    from_result = loop_metrics(result)
    from_frame = loop_metrics(result.to_pandas())  # time as the index, units in attrs
    a, b = from_result.as_dict(), from_frame.as_dict()
    assert a.keys() == b.keys()
    for key in a:
        assert a[key] == b[key] or (np.isnan(a[key]) and np.isnan(b[key])), key
    # effort relative to the initial command 3 N: 4·ISE
    assert from_result.control_effort == pytest.approx(4 * from_result.ise,
                                                       rel=ref.LOOP_INTEGRAL_RTOL)
    assert from_result.units()["control_effort"] == "N^2*s"


def test_table_and_dict():
    t, x, v = _stick_slip()
    m = loop_metrics(_frame(t, x, np.ones_like(t), v, np.ones_like(t), {"command": "1"}))
    table = m.to_pandas()
    assert list(table.columns) == ["metric", "value", "unit", "description"]
    assert list(table["metric"]) == list(m.as_dict())
    names = {f.name for f in fields(LoopMetrics)} - {"position_unit", "command_unit"}
    assert set(table["metric"]) == names
    values = dict(zip(table["metric"], table["value"], strict=True))
    assert values["hunting"] is True and values["stick_count"] == 10
    units = dict(zip(table["metric"], table["unit"], strict=True))
    assert (units["rise_time"], units["overshoot"], units["iae"]) == ("s", "%", "m*s")
    assert (units["control_effort"], units["command_variation"]) == ("s", "1")  # unit "1"
    assert m.control_effort == 0.0 and m.command_variation == 0.0
    with pytest.raises(AttributeError):
        m.rise_time = 1.0  # frozen
    assert "hunting" in m.summary()


def test_no_command_gives_nan_effort():
    t, _, x, r, _ = _first_order()
    m = loop_metrics(_frame(t, x, r))
    assert math.isnan(m.control_effort) and math.isnan(m.command_variation)


@pytest.mark.parametrize(("drop", "missing"), [("position_setpoint", "'position_setpoint'"),
                                               ("position", "'position'")])
def test_missing_signal_is_named(drop, missing):
    t, _, x, r, _ = _first_order()
    frame = _frame(t, x, r).drop(columns=drop)
    with pytest.raises(DataError,
                       match=f"no {missing} signal; needed: position, position_setpoint"):
        loop_metrics(frame)
    result = Result(t, {"position": x, "position_setpoint": r}, {})
    del result.signals[drop]
    with pytest.raises(DataError, match=missing):
        loop_metrics(result)


@pytest.mark.parametrize(("options", "message"), [
    ({"band": 0.0}, r"band = 0.0; allowed: a fraction of the step, 0 < band ≤ 1"),
    ({"band": 1.5}, r"band = 1.5"),
    ({"window": 0.0}, r"window = 0.0 s; allowed: a duration in \(0, 10\] s"),
    ({"window": 11.0}, r"window = 11.0 s"),
    ({"t_step": 10.0}, r"t_step = 10.0 s; allowed: a time in \[0, 10\) s"),
    ({"stick_speed": -1.0}, r"stick_speed = -1.0 m/s; allowed: a speed ≥ 0"),
    ({"target": math.nan}, r"target = nan m"),
])
def test_bad_options_are_named(options, message):
    t, _, x, r, _ = _first_order()
    with pytest.raises(DataError, match=message):
        loop_metrics(_frame(t, x, r), **options)


def test_bad_data_is_named():
    t = np.array([0.0, 1.0, 1.0, 2.0])
    with pytest.raises(DataError, match=r"time must increase strictly; time\[2\] = 1.0"):
        loop_metrics(_frame(t, np.zeros(4), np.ones(4)))
    with pytest.raises(DataError, match=r"position\[1\] = nan"):
        loop_metrics(_frame(np.arange(3.0), [0.0, np.nan, 1.0], np.ones(3)))
    with pytest.raises(DataError, match="no column 'time'"):
        loop_metrics(pd.DataFrame({"position": [0.0, 1.0], "position_setpoint": [1.0, 1.0]}))
    with pytest.raises(DataError, match="time has 1 sample"):
        loop_metrics(_frame([0.0], [0.0], [1.0]))
    with pytest.raises(DataError, match="result = dict; allowed: a pneumact Result"):
        loop_metrics({"position": [0.0]})


# --------------------------------------------------------------------------- figure


def test_plot_loop_smoke():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    from pneumact.control.plots import plot_loop

    t, _, x, r, v = _first_order()
    result = Result(t, {"position": x, "velocity": v, "position_setpoint": r, "command": r - x,
                        "friction": 0.1 * np.sign(v), "friction_compensation": 0.0 * t},
                    {"position": "m", "velocity": "m/s", "position_setpoint": "m", "command": "Pa",
                     "friction": "N", "friction_compensation": "N"})
    fig = plot_loop(result, loop_metrics(result))
    try:
        assert isinstance(fig, Figure)
        axes = fig.get_axes()
        assert len(axes) == 4
        assert axes[1].get_ylabel() == "command [kPa]"
        assert axes[3].get_ylabel() == "velocity [mm/s]"
        assert "rise" in fig.get_suptitle()
    finally:
        plt.close(fig)
    fig = plot_loop(result.to_pandas())  # no metrics, a DataFrame
    try:
        assert len(fig.get_axes()) == 4
    finally:
        plt.close(fig)
