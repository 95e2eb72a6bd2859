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

A change within one sample interval, far larger than its neighbours' (a spool or
command step, logged as commanded), is a jump, not a ramp: the samples cannot say where
in the interval it happened, and a straight line across it moves the step by half an
interval on average (on a cylinder's spool step sampled at 1 kHz that biased Fc by
−20 %, the interval excluding the truth). ``input_jumps`` finds them and the rebuilt
input jumps at the first sample that shows the new value: a sampled record is
right-continuous (a controller's command holds from its sample on, as pneumact's
signals do at their own jumps); each side is rebuilt on its own and the value before
the jump is held up to it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["input_jumps", "knot_jacobian", "noise_level", "piecewise_linear_input",
           "resolution", "sampled_input", "sensor_noise"]

#: Beyond this many knots the input is not a bench test of holds, ramps and steps; the
#: knot times are then kept where the simplification put them.
MAX_REFINED_KNOTS = 400
#: A change between two samples is a jump when it is this many times each neighbouring
#: sample's change (a ramp's changes are equal, a first-order rise's shrink by e^(h/τ))
JUMP_NEIGHBOUR_RATIO = 10.0
#: ... and this many times the white noise on the signal (``noise_level``)
JUMP_NOISE_RATIO = 20.0
#: ... and this share of the signal's peak-to-peak (a quantised signal's one-step
#: flicker on a moving signal is not a jump)
JUMP_RANGE_SHARE = 0.05


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


def input_jumps(values: np.ndarray) -> np.ndarray:
    """Indices k of the samples after which a sampled input jumps (a step between samples
    k and k + 1): the change is more than ``JUMP_NEIGHBOUR_RATIO`` times each
    neighbouring sample's change, ``JUMP_NOISE_RATIO`` times the noise and
    ``JUMP_RANGE_SHARE`` of the peak-to-peak. The first and last changes are never
    jumps (no neighbour on one side)."""
    values = np.asarray(values, dtype=float)
    if values.size < 4:
        return np.zeros(0, dtype=int)
    change = np.abs(np.diff(values))
    scale = max(float(np.ptp(values)), float(np.abs(values).max()), 1e-300)
    floor = max(JUMP_NOISE_RATIO * noise_level(values), JUMP_RANGE_SHARE * np.ptp(values),
                1e-9 * scale)
    inner = change[1:-1]
    neighbours = np.maximum(change[:-2], change[2:])
    return np.flatnonzero((inner > JUMP_NEIGHBOUR_RATIO * neighbours) & (inner > floor)) + 1


def sampled_input(time: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(times, values) of a sampled input as it is, linear between samples, but each jump
    (``input_jumps``) held from the sample before it up to the sample that shows it: the
    record's samples unsmoothed, its steps kept as steps."""
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    jumps = input_jumps(values)
    if jumps.size == 0:
        return time, values
    return (np.insert(time, jumps + 1, time[jumps + 1]),
            np.insert(values, jumps + 1, values[jumps]))


def piecewise_linear_input(time: np.ndarray, values: np.ndarray,
                           tolerance: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(knot times, knot values) of a piecewise-linear signal fitted to a noisy input.

    ``tolerance`` (default 6 × the estimated noise level) is the largest deviation left
    unexplained by a segment; a noiseless input keeps its corners exactly. A jump
    (``input_jumps``) between samples k and k + 1 is a repeated knot time at sample
    k + 1, the value before it held from sample k: a step stays a step."""
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    sigma = noise_level(values)
    scale = max(np.ptp(values), np.abs(values).max())
    noiseless = tolerance is None and sigma <= 1e-9 * scale
    tol = 1e-9 * scale if noiseless else (6.0 * sigma if tolerance is None
                                          else float(tolerance))
    jumps = input_jumps(values)
    if jumps.size == 0:
        return _rebuilt_piece(time, values, tol, noiseless)
    starts = np.concatenate([[0], jumps + 1])
    ends = np.concatenate([jumps + 1, [time.size]])
    knots_t: list[np.ndarray] = []
    knots_v: list[np.ndarray] = []
    for start, end in zip(starts, ends, strict=True):
        if knots_t:  # hold the value before the jump up to the jump's sample
            knots_t.append(time[start:start + 1])
            knots_v.append(knots_v[-1][-1:])
        piece_t, piece_v = _rebuilt_piece(time[start:end], values[start:end], tol,
                                          noiseless)
        knots_t.append(piece_t)
        knots_v.append(piece_v)
    return np.concatenate(knots_t), np.concatenate(knots_v)


def _rebuilt_piece(time: np.ndarray, values: np.ndarray, tolerance: float,
                   noiseless: bool) -> tuple[np.ndarray, np.ndarray]:
    """(knot times, knot values) of samples without a jump: the noiseless ones that lie
    on a straight line between their neighbours dropped (the same signal, fewer knots),
    or else the simplification at ``tolerance``, the knot values fitted by linear least
    squares and the knot times refined."""
    if noiseless:
        knots = _rdp_knots(time, values, tolerance)
        return _corners_between_samples(time, values, knots)
    knots = _rdp_knots(time, values, tolerance)
    if knots.size < 2 or time.size < 3:
        return time[knots], values[knots]
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


def _corners_between_samples(time: np.ndarray, values: np.ndarray, knots: np.ndarray
                             ) -> tuple[np.ndarray, np.ndarray]:
    """(knot times, knot values) of a noiseless signal's knots (sample indices), with the
    corner between two knots one sample apart put back where the straight lines on either
    side meet. A set-point's ramp that ends between two samples is logged as knots on the
    samples either side, and a line between them cuts the corner: at 123 Hz that left
    the truth's own model 6-8 noise deviations off a drawn actuator's ramps."""
    knot_t, knot_v = time[knots], values[knots]
    out_t, out_v = [knot_t[:1]], [knot_v[:1]]
    for k in range(1, knots.size):
        a, b = knots[k - 1], knots[k]
        corner = None
        # each side's line pinned by a segment of two intervals at least (a segment of
        # one could itself be a cut corner)
        if b == a + 1 and k >= 2 and k + 1 < knots.size and a - knots[k - 2] >= 2 \
                and knots[k + 1] - b >= 2:
            corner = _meeting_point(time, values, knots[k - 2], a, b, knots[k + 1])
        if corner is not None:
            out_t.append(np.array([corner[0]]))
            out_v.append(np.array([corner[1]]))
        out_t.append(knot_t[k:k + 1])
        out_v.append(knot_v[k:k + 1])
    return np.concatenate(out_t), np.concatenate(out_v)


def _meeting_point(time, values, p: int, a: int, b: int, q: int
                   ) -> tuple[float, float] | None:
    """Where the line through samples p and a meets the line through b and q, when that
    is strictly between samples a and b (None otherwise: parallel lines, or a meeting
    point outside the interval, which is not a corner the samples straddle)."""
    slope_left = (values[a] - values[p]) / (time[a] - time[p])
    slope_right = (values[q] - values[b]) / (time[q] - time[b])
    if slope_left == slope_right:
        return None
    t = (values[b] - values[a] + slope_left * time[a] - slope_right * time[b]) \
        / (slope_left - slope_right)
    if not time[a] < t < time[b]:
        return None
    return float(t), float(values[a] + slope_left * (t - time[a]))


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
