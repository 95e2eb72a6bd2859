"""Hysteresis features on synthetic records with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from pneumact.core import features
from pneumact.errors import DataError
from reference import (
    BREAKAWAY_INTERPOLATION_RTOL,
    REL_TOL,
    ROUND_OFF_ATOL,
    ZERO_WIDTH_PA,
)

# --- reference values and tolerances (one block) -------------------------------------
P_ATM = 1e5  # Pa
AREA = 2.92246e-3  # m^2
PRELOAD = 32.68  # N
STIFFNESS = 12850.0  # N/m
COULOMB = 2.6  # N
X_MAX = 0.02  # m
P_HIGH, P_LOW = 100e3, 20e3  # Pa
SAMPLES_PER_BRANCH = 2001


def coulomb_play(cycles: int = 1, friction: float = COULOMB):
    """Ideal Coulomb play: x = clip(((p_atm − p)·A − F0 ∓ Fc)/k) on falling/rising branches."""
    down = np.linspace(P_HIGH, P_LOW, SAMPLES_PER_BRANCH)
    up = down[::-1][1:]
    p_cycle = np.concatenate([down, up])
    sign_cycle = np.concatenate([np.ones_like(down), -np.ones_like(up)])
    pressure = np.concatenate([p_cycle] + [p_cycle[1:]] * (cycles - 1))
    signs = np.concatenate([sign_cycle] + [sign_cycle[1:]] * (cycles - 1))
    position = np.clip(((P_ATM - pressure) * AREA - PRELOAD - signs * friction) / STIFFNESS,
                       0.0, X_MAX)
    time = np.linspace(0.0, 20.0 * cycles, pressure.size)
    return time, pressure, position


@pytest.mark.parametrize("cycles", [1, 3])
def test_coulomb_play_widths_are_2Fc_over_A_and_2Fc_over_k(cycles):
    _, p, x = coulomb_play(cycles)
    assert features.loop_width_pressure(p, x) == pytest.approx(2 * COULOMB / AREA,
                                                                rel=REL_TOL)
    assert features.loop_width_position(p, x) == pytest.approx(2 * COULOMB / STIFFNESS,
                                                                rel=REL_TOL)


def test_pure_line_has_zero_width_and_zero_area():
    _, p, x = coulomb_play(friction=0.0)
    assert features.loop_width_pressure(p, x) == pytest.approx(0.0, abs=ZERO_WIDTH_PA)
    assert features.loop_width_position(p, x) == pytest.approx(0.0, abs=ROUND_OFF_ATOL)
    assert features.loop_area(p, x) == pytest.approx(0.0, abs=ZERO_WIDTH_PA)


def test_coulomb_play_area_is_width_times_travel():
    _, p, x = coulomb_play()
    # Between the two branches the pressure gap is 2Fc/A at every position both reach;
    # the rising branch reaches 2Fc/k further, so the area lies between the two products.
    width = 2 * COULOMB / AREA
    top_falling = ((P_ATM - P_LOW) * AREA - PRELOAD - COULOMB) / STIFFNESS
    top_rising = top_falling + 2 * COULOMB / STIFFNESS
    assert width * top_falling <= features.loop_area(p, x) <= width * top_rising


def test_rectangle_loop_area():
    p1, p2, x1, x2 = 30e3, 90e3, 0.001, 0.004
    n = 101
    pressure = np.concatenate([np.linspace(p2, p1, n), np.full(n, p1)[1:],
                               np.linspace(p1, p2, n)[1:], np.full(n, p2)[1:]])
    position = np.concatenate([np.full(n, x1), np.linspace(x1, x2, n)[1:],
                               np.full(n, x2)[1:], np.linspace(x2, x1, n)[1:]])
    assert features.loop_area(pressure, position) == pytest.approx((p2 - p1) * (x2 - x1),
                                                                   rel=REL_TOL)


def test_stroke_is_max_minus_min():
    assert features.stroke([0.0, 0.003, -0.001, 0.002]) == pytest.approx(0.004)


def test_breakaway_is_where_the_sliding_line_leaves_the_rest_position():
    # Coulomb play: the falling branch x = ((p_atm − p)·A − F0 − Fc)/k meets x = 0 at a
    # vacuum of (F0 + Fc)/A, whatever the sampling
    time, p, x = coulomb_play()
    expected = P_ATM - (PRELOAD + COULOMB) / AREA
    assert features.breakaway_pressure(time, p, x) == pytest.approx(expected, rel=REL_TOL)


def test_breakaway_does_not_see_presliding_creep():
    # the same loop with a creep of up to 0.3 mm (three times LuGre's) before sliding:
    # a motion threshold would follow it, the sliding line does not
    time, p, x = coulomb_play()
    vacuum = (P_ATM - p) * AREA - PRELOAD
    creep = np.where(np.arange(p.size) < SAMPLES_PER_BRANCH,
                     3e-4 * np.clip(vacuum / COULOMB, 0.0, 1.0), 0.0)
    crept = np.maximum(x, creep)
    expected = P_ATM - (PRELOAD + COULOMB) / AREA
    assert features.breakaway_pressure(time, p, crept) == pytest.approx(expected,
                                                                        rel=REL_TOL)
    onset = features.motion_onset_pressure(time, p, crept, threshold=1e-4)
    assert P_ATM - onset < (PRELOAD + COULOMB) / AREA - 100.0  # fooled by the creep


def test_motion_onset_finds_the_threshold_crossing():
    time = np.linspace(0.0, 10.0, 1001)
    pressure = P_HIGH - 8e3 * time  # falling 8 kPa/s
    presliding = 30e-6 * np.clip(time / 2.0, 0.0, 1.0)  # 30 µm creep
    position = presliding + np.clip(time - 5.0, 0.0, None) * 1e-3  # 1 mm/s from t = 5 s
    threshold = 50e-6
    expected = P_HIGH - 8e3 * (5.0 + (threshold - 30e-6) / 1e-3)
    assert features.motion_onset_pressure(time, pressure, position, threshold) == \
        pytest.approx(expected, rel=BREAKAWAY_INTERPOLATION_RTOL)
    with pytest.raises(DataError, match="threshold"):
        features.motion_onset_pressure(time, pressure, position, threshold=-1.0)


def test_breakaway_is_nan_without_a_loop():
    time = np.linspace(0, 1, 11)
    assert np.isnan(features.breakaway_pressure(time, 1e5 - time, np.full(11, 1e-6)))
    assert np.isnan(features.motion_onset_pressure(time, 1e5 - time, np.full(11, 1e-6),
                                                   threshold=1e-5))


def test_sliding_speed_of_a_linear_branch():
    # x = (A/k)·(p_atm − p) + const on the falling branch, p falling at a constant rate
    time, p, x = coulomb_play()
    rate = (P_HIGH - P_LOW) / time[SAMPLES_PER_BRANCH - 1]
    assert features.sliding_speed(time, p, x) == pytest.approx(AREA / STIFFNESS * rate,
                                                               rel=REL_TOL)


def test_presliding_travel_of_a_known_corner():
    # a play that sticks at the reversal (x held until the pressure has come back by
    # 2·Fc/A) has a rigid corner; give it a linear presliding compliance c [m/Pa]
    _, p, x = coulomb_play()
    turn = SAMPLES_PER_BRANCH - 1
    stuck = x.copy()
    stuck[turn:] = np.minimum(x[turn:], x[turn])
    assert features.presliding_travel(p, stuck) == pytest.approx(0.0, abs=ROUND_OFF_ATOL)
    compliance = 1e-8  # m/Pa: 8.9 µm over half the 1.78 kPa width
    corner = stuck.copy()
    corner[turn:] = np.minimum(x[turn:], x[turn] - compliance * (p[turn:] - P_LOW))
    width = features.loop_width_pressure(p, corner)
    assert features.presliding_travel(p, corner) == pytest.approx(compliance * width / 2,
                                                                  rel=REL_TOL)


def test_loop_width_profile_is_the_gap_at_each_position():
    _, p, x = coulomb_play()
    profile = features.loop_width_profile(p, x)
    assert profile.shape == (features.GRID_POINTS,)
    assert profile == pytest.approx(np.full(profile.size, 2 * COULOMB / AREA), rel=REL_TOL)
    assert np.mean(profile) == pytest.approx(features.loop_width_pressure(p, x), rel=REL_TOL)
    outside = features.loop_width_profile(p, x, [-1.0, 0.005])
    assert np.isnan(outside[0]) and outside[1] == pytest.approx(2 * COULOMB / AREA,
                                                                rel=REL_TOL)


def test_errors_against_reference():
    time = np.linspace(0, 1, 101)
    position = 0.001 * time
    ref_time = np.linspace(0, 1, 11)
    ref_position = 0.001 * ref_time + 0.0002
    assert features.rms_error(time, position, ref_time, ref_position) == pytest.approx(2e-4)
    assert features.max_error(time, position, ref_time, ref_position) == pytest.approx(2e-4)


def test_summary_has_every_feature_with_a_unit():
    time, p, x = coulomb_play()
    summary = features.hysteresis_summary(time, p, x)
    assert set(summary) == {"stroke", "loop_width_pressure", "loop_width_position",
                            "loop_area", "breakaway_pressure", "sliding_speed",
                            "presliding_travel"}
    assert set(summary) <= set(features.FEATURE_UNITS)
    assert all(np.isfinite(v) for v in summary.values())


def test_step_response_has_no_loop():
    time = np.linspace(0, 1, 101)
    p = np.where(time < 0.1, P_HIGH, P_LOW)
    x = np.where(time < 0.1, 0.0, 0.01)
    assert np.isnan(features.loop_width_pressure(p, x))
    assert np.isnan(features.loop_area(p, x))
    assert np.isnan(features.breakaway_pressure(time, p, x))
    assert np.isnan(features.sliding_speed(time, p, x))
    assert np.isnan(features.presliding_travel(p, x))


def test_length_mismatch_is_a_clear_data_error():
    with pytest.raises(DataError, match=r"position has 4 samples but pressure has 5"):
        features.loop_width_pressure(np.arange(5.0), np.arange(4.0))


def test_too_few_samples_is_a_clear_data_error():
    with pytest.raises(DataError, match=r"pressure: has 2 samples; .* at least 3"):
        features.loop_area([1.0, 2.0], [0.0, 1.0])


def test_nan_is_a_clear_data_error():
    with pytest.raises(DataError, match=r"position: sample 1 is nan"):
        features.stroke([0.0, np.nan, 1.0])


def test_the_loop_features_found_together_are_those_found_alone():
    """``_pressure_features`` finds the last loop once for its six features: each value is
    the one its own function gives, finding the loop itself, bit for bit."""
    names = ("loop_width_pressure", "loop_width_position", "loop_area", "breakaway_pressure",
             "sliding_speed", "presliding_travel")
    for cycles in (1, 3):
        time, pressure, position = coulomb_play(cycles)
        # presliding: the rising branch creeps back before it slides
        position = position + 1e-5 * np.tanh(np.gradient(pressure) / 40.0)
        together = np.full(features.N_FEATURES, np.nan)
        features._pressure_features(time, pressure, position, together)
        alone = {"loop_width_pressure": features._loop_width_pressure(pressure, position),
                 "loop_width_position": features._loop_width_position(pressure, position),
                 "loop_area": features._loop_area(pressure, position),
                 "breakaway_pressure": features._breakaway(pressure, position),
                 "sliding_speed": features._sliding_speed(time, pressure, position),
                 "presliding_travel": features._presliding_travel(pressure, position)}
        assert all(np.isfinite(alone[n]) for n in names), alone
        for name in names:
            assert together[features.FEATURES.index(name)] == alone[name], name
