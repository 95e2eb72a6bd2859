"""Measured inputs made fit to drive a simulation.

A LuGre model driven by a noisy measured pressure is dithered: every noise sample is a
force rate, the bristles see |v| > 0 all the time, and the stuck state creeps. On the
synthetic presliding test, 50 Pa of sensor noise on the input biases σ0 by −30 % and σ1
by +250 %, and a low-pass filter does not cure it (50 Hz still leaves −20 %). Bench
inputs are made of holds, ramps and fast steps, so ``piecewise_linear_input`` rebuilds
the input as a piecewise-linear signal: knots from the Ramer-Douglas-Peucker
simplification at a few noise standard deviations, then the knot values by linear
least squares over all samples (no noise left within a segment, corners and steps
kept).
"""

from __future__ import annotations

import numpy as np

__all__ = ["knot_jacobian", "noise_level", "piecewise_linear_input", "resolution",
           "sensor_noise"]

#: Beyond this many knots the input is not a bench test of holds, ramps and steps; the
#: knot times are then kept where the simplification put them.
MAX_REFINED_KNOTS = 400


def noise_level(values: np.ndarray) -> float:
    """Standard deviation of white noise on ``values``, from the median absolute second
    difference (insensitive to ramps and to a few steps)."""
    d2 = np.diff(values, 2)
    return float(np.median(np.abs(d2 - np.median(d2))) * 1.4826 / np.sqrt(6.0))


def resolution(values: np.ndarray) -> float:
    """Quantisation step of a signal whose samples lie on a grid (a digital sensor), or
    0: the smallest non-zero step between samples, if at least 90 % of the steps are
    whole multiples of it and the signal shows it is quantised (it holds still for a
    tenth of its samples, or steps by different multiples): a ramp's equal steps are
    not quantisation."""
    all_steps = np.diff(np.asarray(values, dtype=float))
    steps = np.abs(all_steps[all_steps != 0])
    if steps.size < 10:
        return 0.0
    q = float(steps.min())
    multiples = np.round(all_steps / q)
    on_grid = np.abs(all_steps / q - multiples) <= 1e-6 * np.maximum(np.abs(multiples), 1.0)
    holds = np.mean(all_steps == 0) >= 0.1
    varied = np.unique(multiples[on_grid & (all_steps != 0)]).size >= 2
    return q if np.mean(on_grid) >= 0.9 and (holds or varied) else 0.0


def sensor_noise(values: np.ndarray) -> float:
    """Noise standard deviation of a measured signal: ``noise_level``, but at least the
    quantisation noise resolution/√12 of a sensor with a finite ``resolution``, which
    ``noise_level`` misses on a signal that holds still between quantisation steps."""
    return max(noise_level(values), resolution(values) / np.sqrt(12.0))


def _rdp_knots(t: np.ndarray, y: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices kept by the Ramer-Douglas-Peucker simplification (vertical distance)."""
    keep = np.zeros(t.size, dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, t.size - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        seg_t, seg_y = t[i + 1:j], y[i + 1:j]
        line = y[i] + (y[j] - y[i]) * (seg_t - t[i]) / (t[j] - t[i])
        k = int(np.argmax(np.abs(seg_y - line)))
        if abs(seg_y[k] - line[k]) > tolerance:
            m = i + 1 + k
            keep[m] = True
            stack += [(i, m), (m, j)]
    return np.flatnonzero(keep)


def piecewise_linear_input(time: np.ndarray, values: np.ndarray,
                           tolerance: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(knot times, knot values) of a piecewise-linear signal fitted to a noisy input.

    ``tolerance`` (default 6 × the estimated noise level) is the largest deviation left
    unexplained by a segment; a noiseless input keeps its corners exactly."""
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    sigma = noise_level(values)
    scale = max(np.ptp(values), np.abs(values).max())
    if tolerance is None and sigma <= 1e-9 * scale:
        # noiseless (simulated, or already clean): drop only the samples that lie on a
        # straight line between their neighbours (exactly the same signal, fewer knots)
        knots = _rdp_knots(time, values, 1e-9 * scale)
        return time[knots], values[knots]
    tol = 6.0 * sigma if tolerance is None else float(tolerance)
    knots = _rdp_knots(time, values, tol)
    # hat-function basis on the knots: linear least squares for the knot values
    seg = np.clip(np.searchsorted(time[knots], time, side="right") - 1, 0, knots.size - 2)
    t0, t1 = time[knots][seg], time[knots][seg + 1]
    w = (time - t0) / (t1 - t0)
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import lsqr

    rows = np.concatenate([np.arange(time.size)] * 2)
    cols = np.concatenate([seg, seg + 1])
    basis = coo_matrix((np.concatenate([1 - w, w]), (rows, cols)),
                       shape=(time.size, knots.size)).tocsr()
    fitted = lsqr(basis, values, atol=1e-12, btol=1e-12, x0=values[knots])[0]
    return _refine_knot_times(time, values, time[knots], fitted)


def _segments_of(time, knot_t):
    """For each sample: its knot interval, the fraction w along it, and its length."""
    seg = np.clip(np.searchsorted(knot_t, time, side="right") - 1, 0, knot_t.size - 2)
    h = knot_t[seg + 1] - knot_t[seg]
    return seg, (time - knot_t[seg]) / h, h


def knot_jacobian(time: np.ndarray, knot_t: np.ndarray, knot_v: np.ndarray):
    """Sparse ∂(signal at ``time``)/∂(interior knot times, then all knot values) of the
    piecewise-linear signal through (``knot_t``, ``knot_v``): how the rebuilt input
    moves when the noise on the measured one moves its knots (see
    ``identification.uncertainty``), and the Jacobian of the knot refinement."""
    from scipy.sparse import csr_matrix

    n_knots = knot_t.size
    n_in = n_knots - 2
    seg, w, h = _segments_of(time, knot_t)
    slope = (knot_v[seg + 1] - knot_v[seg]) / h
    rows = np.arange(time.size)
    # columns: interior knot times 0..n_in-1 (knot k ↔ column k-1), then values
    cols = [n_in + seg, n_in + seg + 1, seg - 1, seg]
    data = [1 - w, w, -slope * (1 - w), -slope * w]
    keep = [np.ones_like(w, bool), np.ones_like(w, bool), seg >= 1, seg + 1 <= n_in]
    r = np.concatenate([rows[m] for m in keep])
    c = np.concatenate([col[m] for col, m in zip(cols, keep, strict=True)])
    d = np.concatenate([dat[m] for dat, m in zip(data, keep, strict=True)])
    return csr_matrix((d, (r, c)), shape=(time.size, n_in + n_knots))


def _refine_knot_times(time, values, knot_t, knot_v):
    """Move the interior knots in time (between their neighbours' midpoints) and adjust
    all knot values, by nonlinear least squares with the analytic sparse Jacobian: a
    step's corners fall between samples, and a knot on the nearest sample misplaces a
    2 ms step by 10 % of its length."""
    from scipy.optimize import least_squares

    n_knots = knot_t.size
    if n_knots <= 2 or n_knots > MAX_REFINED_KNOTS:
        return knot_t, knot_v
    n_in = n_knots - 2
    mid = 0.5 * (knot_t[1:] + knot_t[:-1])
    lo = np.concatenate([mid[:-1], np.full(n_knots, -np.inf)])
    hi = np.concatenate([mid[1:], np.full(n_knots, np.inf)])

    def unpack(x):
        return np.concatenate([[knot_t[0]], np.sort(x[:n_in]), [knot_t[-1]]]), x[n_in:]

    def residual(x):
        t, v = unpack(x)
        seg, w, _ = _segments_of(time, t)
        return v[seg] + (v[seg + 1] - v[seg]) * w - values

    def jacobian(x):
        return knot_jacobian(time, *unpack(x))

    x0 = np.concatenate([knot_t[1:-1], knot_v])
    sol = least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), x_scale="jac",
                        method="trf", tr_solver="lsmr", ftol=1e-6, max_nfev=40)
    return unpack(sol.x)
