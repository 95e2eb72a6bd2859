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

__all__ = ["noise_level", "piecewise_linear_input"]

#: Beyond this many knots the input is not a bench test of holds, ramps and steps; the
#: knot times are then kept where the simplification put them.
MAX_REFINED_KNOTS = 400


def noise_level(values: np.ndarray) -> float:
    """Standard deviation of white noise on ``values``, from the median absolute second
    difference (insensitive to ramps and to a few steps)."""
    d2 = np.diff(values, 2)
    return float(np.median(np.abs(d2 - np.median(d2))) * 1.4826 / np.sqrt(6.0))


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


def _refine_knot_times(time, values, knot_t, knot_v):
    """Move the interior knots in time (between their neighbours' midpoints) and adjust
    all knot values, by nonlinear least squares with the analytic sparse Jacobian: a
    step's corners fall between samples, and a knot on the nearest sample misplaces a
    2 ms step by 10 % of its length."""
    from scipy.optimize import least_squares
    from scipy.sparse import csr_matrix

    n_knots = knot_t.size
    if n_knots <= 2 or n_knots > MAX_REFINED_KNOTS:
        return knot_t, knot_v
    n_in = n_knots - 2
    mid = 0.5 * (knot_t[1:] + knot_t[:-1])
    lo = np.concatenate([mid[:-1], np.full(n_knots, -np.inf)])
    hi = np.concatenate([mid[1:], np.full(n_knots, np.inf)])
    rows = np.arange(time.size)

    def unpack(x):
        t = np.concatenate([[knot_t[0]], np.sort(x[:n_in]), [knot_t[-1]]])
        seg = np.clip(np.searchsorted(t, time, side="right") - 1, 0, n_knots - 2)
        h = t[seg + 1] - t[seg]
        w = (time - t[seg]) / h
        return t, x[n_in:], seg, w, h

    def residual(x):
        _t, v, seg, w, _ = unpack(x)
        return v[seg] + (v[seg + 1] - v[seg]) * w - values

    def jacobian(x):
        _t, v, seg, w, h = unpack(x)
        slope = (v[seg + 1] - v[seg]) / h
        # columns: interior knot times 0..n_in-1 (knot k ↔ column k-1), then values
        cols = [n_in + seg, n_in + seg + 1, seg - 1, seg]
        data = [1 - w, w, -slope * (1 - w), -slope * w]
        keep = [np.ones_like(w, bool), np.ones_like(w, bool), seg >= 1, seg + 1 <= n_in]
        r = np.concatenate([rows[m] for m in keep])
        c = np.concatenate([col[m] for col, m in zip(cols, keep, strict=True)])
        d = np.concatenate([dat[m] for dat, m in zip(data, keep, strict=True)])
        return csr_matrix((d, (r, c)), shape=(time.size, n_in + n_knots))

    x0 = np.concatenate([knot_t[1:-1], knot_v])
    sol = least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), x_scale="jac",
                        method="trf", tr_solver="lsmr", ftol=1e-6, max_nfev=40)
    t, v, *_ = unpack(sol.x)
    return t, v
