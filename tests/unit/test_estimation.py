"""Identification building blocks against known answers: least squares with standard
errors, the HAC covariance, input rebuilding, records, the inverse friction model."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import reference as ref
from pneumact.errors import DataError, ParameterError
from pneumact.experiments import PiecewiseLinear, SpoolStep
from pneumact.identification import Estimates, inverse_friction, linear_least_squares
from pneumact.identification.estimates import (
    _bandwidth,
    _long_run_covariance,
    covariance_from_jacobian,
)
from pneumact.identification.inputs import (
    input_jumps,
    noise_level,
    piecewise_linear_input,
    sampled_input,
)
from pneumact.identification.paper import record_kind
from pneumact.io import Record, read_record, read_records


def test_linear_least_squares_matches_the_textbook_line_fit():
    rng = np.random.default_rng(0)
    x = np.linspace(0, 1, 200)
    y = 2.0 + 3.0 * x + rng.normal(0, 0.1, x.size)
    est, res, cond = linear_least_squares(np.column_stack([np.ones_like(x), x]), y,
                                          ["a", "b"])
    slope, intercept, _, _, se_slope = stats.linregress(x, y)
    assert est["b"] == pytest.approx(slope, rel=1e-12)
    assert est["a"] == pytest.approx(intercept, rel=1e-12)
    assert est.stderr[1] == pytest.approx(se_slope, rel=1e-10)
    assert est.dof == x.size - 2
    assert np.allclose(res, y - intercept - slope * x)
    assert cond > 1


def test_interval_is_student_t():
    est = Estimates(("a",), np.array([1.0]), np.array([0.5]), np.array([[0.25]]), 7)
    low, high = est.interval(0.95)[0]
    q = stats.t.ppf(0.975, 7)
    assert (low, high) == pytest.approx((1 - q * 0.5, 1 + q * 0.5))


def test_unexcited_parameter_is_named():
    with pytest.raises(DataError, match="never excite b"):
        linear_least_squares(np.column_stack([np.ones(5), np.zeros(5)]), np.ones(5),
                             ["a", "b"])


def test_singular_problem_has_infinite_errors_not_fake_ones():
    jac = np.column_stack([np.ones(10), 2 * np.ones(10)])
    cov, _ = covariance_from_jacobian(jac, np.ones(10), 2)
    assert np.all(np.isinf(cov))


def test_long_run_covariance_is_the_bartlett_sum():
    g = np.random.default_rng(1).normal(size=(60, 3))
    lags = 5
    expected = g.T @ g
    for lag in range(1, lags + 1):
        cross = g[lag:].T @ g[:-lag]
        expected += (1 - lag / (lags + 1)) * (cross + cross.T)
    assert np.allclose(_long_run_covariance(g, lags), expected, rtol=1e-12, atol=1e-12)


def _bartlett_sum(g: np.ndarray, bandwidth: int) -> np.ndarray:
    """Σ_{|l| ≤ L} (1 − |l|/(L+1))·Σ_t g_t·g_{t−l}ᵀ, lag by lag."""
    expected = g.T @ g
    for lag in range(1, min(bandwidth, len(g) - 1) + 1):
        cross = g[lag:].T @ g[:-lag]
        expected += (1 - lag / (bandwidth + 1)) * (cross + cross.T)
    return expected


@pytest.mark.parametrize(("n", "bandwidth"), [(600, 40), (601, 150), (50, 80)])
def test_long_run_covariance_in_the_frequency_domain_is_the_bartlett_sum(n, bandwidth):
    """Bandwidths above ``DIRECT_BANDWIDTH`` take the spectral path: even and odd
    padded lengths, and a bandwidth beyond the samples (lags without pairs)."""
    from pneumact.identification.estimates import DIRECT_BANDWIDTH

    assert bandwidth > DIRECT_BANDWIDTH
    rng = np.random.default_rng(4)
    g = np.cumsum(rng.normal(size=(n, 4)) * [1.0, 1e-3, 10.0, 0.5], axis=0)  # correlated
    expected = _bartlett_sum(g, bandwidth)
    np.testing.assert_allclose(_long_run_covariance(g, bandwidth), expected,
                               rtol=0, atol=ref.HAC_SPECTRAL_RTOL * np.abs(expected).max())


def test_bandwidth_follows_the_correlation_length():
    rng = np.random.default_rng(2)
    white = rng.normal(size=20_000)
    ar = np.empty_like(white)
    ar[0] = white[0]
    for i in range(1, ar.size):
        ar[i] = ref.HAC_AR1_RHO * ar[i - 1] + white[i]
    expected_lag = int(np.ceil(-1 / np.log(ref.HAC_AR1_RHO)))
    assert _bandwidth(white) <= 3
    assert abs(_bandwidth(ar) - 3 * expected_lag) <= 3


def test_noise_level_of_white_noise_on_a_ramp():
    rng = np.random.default_rng(3)
    t = np.linspace(0, 1, 10_000)
    y = 5e4 + 2e4 * t + rng.normal(0, ref.PWL_NOISE, t.size)
    assert noise_level(y) == pytest.approx(ref.PWL_NOISE, rel=ref.NOISE_LEVEL_RTOL)


def test_piecewise_linear_input_keeps_steps_and_removes_noise():
    t = np.arange(0, 1.0, 2e-4)
    corners_t = [0, 0.2, 0.4, 0.402, 0.6, 0.602, 1.0 - 2e-4]
    corners_v = [1e5, 1e5, 9e4, 9.05e4, 9.05e4, 8.95e4, 8.95e4]
    clean = np.interp(t, corners_t, corners_v)
    noisy = clean + np.random.default_rng(4).normal(0, ref.PWL_NOISE, t.size)
    knots_t, knots_v = piecewise_linear_input(t, noisy)
    rebuilt = np.interp(t, knots_t, knots_v)
    assert np.max(np.abs(rebuilt - clean)) < ref.PWL_MAX_ERROR * ref.PWL_NOISE
    assert knots_t.size < 20
    same_t, same_v = piecewise_linear_input(t, clean)
    assert same_t.size < 20
    assert np.allclose(np.interp(t, same_t, same_v), clean, rtol=1e-12)


def test_a_noiseless_set_point_keeps_its_corners_between_samples():
    """Issue 38: a regulator's set-point (exact, as commanded) sampled at 123 Hz has its
    ramps' corners between samples; rebuilt, the corners are where the lines meet, so
    the signal equals the commanded one between the samples too (a line across the
    straddling interval cut each corner: the truth's own model then missed a drawn
    actuator's resampled ramps by 6-8 noise deviations). Corners on samples: unchanged."""
    corners_t = [0.0, 0.30, 1.2071, 1.5, 2.4033, 3.0]
    corners_v = [8e4, 8e4, 3e4, 3e4, 8e4, 8e4]
    t = np.arange(0.0, 3.0, 1 / 123.0)
    knots_t, knots_v = piecewise_linear_input(t, np.interp(t, corners_t, corners_v))
    fine = np.linspace(0.0, t[-1], 20001)
    np.testing.assert_allclose(np.interp(fine, knots_t, knots_v),
                               np.interp(fine, corners_t, corners_v), rtol=0, atol=1e-8)
    on = np.arange(3001) * 1e-3  # every corner on a sample: the corners are the knots
    sampled = [0.0, 0.3, 1.207, 1.5, 2.403, 3.0]
    knots_t, knots_v = piecewise_linear_input(on, np.interp(on, sampled, corners_v))
    np.testing.assert_array_equal(knots_t, sampled)
    np.testing.assert_array_equal(knots_v, corners_v)


def test_a_sampled_step_is_rebuilt_as_a_step_at_the_sample_that_shows_it():
    """A spool logged as commanded (1 kHz, the step at a sample): rebuilt, smoothed or
    not, it equals the commanded step between the samples too (a line across the
    interval moved it by half a sample); with noise, the jump keeps that time. A ramp
    over two samples and a quantised signal's one-step flicker are not jumps."""
    t = np.arange(301) * 1e-3
    commanded = SpoolStep(-1.0, 0.5, t_step=0.1, t_end=0.3).drive
    spool = commanded(t)
    between = t[:-1] + 0.37e-3
    assert input_jumps(spool).tolist() == [99]
    for knots in (piecewise_linear_input(t, spool), sampled_input(t, spool)):
        rebuilt = PiecewiseLinear(*knots)
        np.testing.assert_array_equal(rebuilt(between), commanded(between))
    noisy = spool + np.random.default_rng(5).normal(0.0, ref.STEP_FIT_SPOOL_NOISE, t.size)
    knots_t, knots_v = piecewise_linear_input(t, noisy)
    assert knots_t[np.flatnonzero(np.diff(knots_t) == 0)].tolist() == [t[100]]
    rebuilt = PiecewiseLinear(knots_t, knots_v)(between)
    assert np.max(np.abs(rebuilt - commanded(between))) < ref.PWL_MAX_ERROR * \
        ref.STEP_FIT_SPOOL_NOISE
    ramp = np.interp(t, [0.0, 0.1, 0.102, 0.3], [-1.0, -1.0, 0.5, 0.5])
    assert input_jumps(ramp).size == 0
    creeping = np.round(np.linspace(0.0, 1.0, t.size) / 0.01) * 0.01
    assert input_jumps(creeping).size == 0


# --------------------------------------------------------------------------- records
def test_record_from_arrays_names_each_problem():
    t = np.linspace(0, 1, 5)
    with pytest.raises(DataError, match=r"'position' has 1 NaN"):
        Record.from_arrays(t, {"position": [0, 1, np.nan, 2, 3]}, source="r")
    with pytest.raises(DataError, match="not strictly increasing"):
        Record.from_arrays([0, 1, 1, 2, 3], {"position": np.zeros(5)}, source="r")
    with pytest.raises(DataError, match="shape"):
        Record.from_arrays(t, {"position": np.zeros(4)}, source="r")


def test_record_crop_resample_and_round_trip(tmp_path):
    t = np.linspace(0, 2, 201)
    rec = Record.from_arrays(t, {"pressure": 1e5 - 1e4 * t, "position": 1e-3 * t},
                             source="bench")
    cropped = rec.crop(0.5, 1.5)
    assert cropped.time[0] == pytest.approx(0.5) and cropped.time[-1] == pytest.approx(1.5)
    resampled = rec.resample(0.1)
    assert np.allclose(resampled["position"], 1e-3 * resampled.time, rtol=1e-12)
    path = rec.save(tmp_path / "r.csv", units={"pressure": "kPa", "position": "mm"})
    assert path.read_text().splitlines()[0] == "time [s],pressure [kPa],position [mm]"
    back = read_record(path)
    assert np.allclose(back["pressure"], rec["pressure"], rtol=1e-12)
    assert np.allclose(back["position"], rec["position"], rtol=1e-12, atol=1e-18)
    assert len(read_records(tmp_path)) == 1
    with pytest.raises(DataError, match="needs signal"):
        rec.require(["force"], "this use")
    with pytest.raises(DataError, match="keeps 0 samples"):
        rec.crop(5, 6)


def test_record_kind_from_meta_or_name():
    t = [0.0, 1.0]
    assert record_kind(Record.from_arrays(t, {}, source="x", meta={"kind": "ramp"})) == "ramp"
    assert record_kind(Record.from_arrays(t, {}, source="/a/presliding_2.csv")) == \
        "presliding"
    with pytest.raises(DataError, match="sweep\\*, ramp\\* or presliding\\*"):
        record_kind(Record.from_arrays(t, {}, source="other.csv"))


# --------------------------------------------------------------------------- inverse
def _motion_record(fc=20.0, fv=200.0, mass=95.0, offset=-3.0, stribeck=None):
    t = np.arange(0, 10, 1e-3)
    w = 2 * np.pi * 0.5
    x, v, a = 0.1 * np.sin(w * t), 0.1 * w * np.cos(w * t), -0.1 * w**2 * np.sin(w * t)
    force = mass * a + fc * np.sign(v) + fv * v + offset
    if stribeck is not None:
        fs, vs = stribeck
        force += np.sign(v) * (fs - fc) * np.exp(-((np.abs(v) / vs) ** 2))
    return Record.from_arrays(t, {"position": x, "force": force}, source="analytic")


def test_inverse_model_recovers_coulomb_viscous_mass_offset():
    result = inverse_friction(_motion_record())
    for name, value in {"mass": 95.0, "Fc": 20.0, "Fv": 200.0, "offset": -3.0}.items():
        assert result.estimates[name] == pytest.approx(value, rel=ref.INVERSE_RTOL)
    assert result.relative_force_error < ref.INVERSE_RTOL


def test_the_friction_of_a_record_is_its_force_less_inertia_and_offset():
    """force − M·a − offset with the identified M and offset: the friction that made it
    (away from the reversals, where sgn(v) jumps)."""
    friction = inverse_friction(_motion_record()).friction_of(_motion_record())
    v = np.gradient(friction["position"], friction.time)
    moving = np.abs(v) > 0.05 * np.max(np.abs(v))
    moving[:2] = moving[-2:] = False  # one-sided differences at the ends
    truth = 20.0 * np.sign(v) + 200.0 * v
    np.testing.assert_allclose(friction["friction"][moving], truth[moving],
                               atol=ref.INVERSE_RTOL * 20.0)
    assert friction.units["friction"] == "N"


def test_inverse_model_refuses_a_record_that_does_not_move():
    """Position within its noise (or constant), motion one way only, estimates no
    friction can have: a clear refusal, not a mass of 1e12 kg and a negative Fc."""
    rng = np.random.default_rng(1)
    t = np.arange(0, 2, 5e-3)
    force = 2.3 + 0.01 * rng.standard_normal(t.size)
    for position in (0.005 + 1e-6 * rng.standard_normal(t.size), np.full(t.size, 0.005)):
        still = Record.from_arrays(t, {"position": position, "force": force}, source="still")
        with pytest.raises(DataError, match="still: the record does not move"):
            inverse_friction(still)
    one_way = Record.from_arrays(t, {"position": 0.01 * t, "force": force}, source="ramp")
    with pytest.raises(DataError, match="regressors are not excited: condition number"):
        inverse_friction(one_way)
    with pytest.raises(DataError, match=r"impossible estimates: Fc = -20 \(a negative"):
        inverse_friction(_motion_record(fc=-20.0))
    with pytest.raises(DataError, match=r"impossible estimates: mass = 2e\+05 kg"):
        inverse_friction(_motion_record(mass=2e5))


def test_inverse_model_stribeck_and_asymmetric():
    stribeck = inverse_friction(_motion_record(stribeck=(30.0, 0.02)), "stribeck")
    assert stribeck.estimates["Fs"] == pytest.approx(30.0, rel=10 * ref.INVERSE_RTOL)
    assert stribeck.estimates["vs"] == pytest.approx(0.02, rel=10 * ref.INVERSE_RTOL)
    asym = inverse_friction(_motion_record(offset=0.0), asymmetric=True)
    assert asym.estimates["Fc_pos"] == pytest.approx(20.0, rel=ref.INVERSE_RTOL)
    assert asym.estimates["Fc_neg"] == pytest.approx(20.0, rel=ref.INVERSE_RTOL)
    with pytest.raises(ParameterError, match="offset"):
        inverse_friction(_motion_record(), asymmetric=True, offset=True)
    with pytest.raises(ParameterError, match="friction = 'dahl'"):
        inverse_friction(_motion_record(), "dahl")
