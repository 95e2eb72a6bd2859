"""Scalar features of a pressure–position hysteresis record (SI in, SI out).

These numbers summarise one simulated or measured run: the stroke, the width of the
hysteresis loop in pressure and in position, the loop area, the break-away pressure, the
sliding speed and the presliding travel at a reversal, and the position error against a
reference; and a move's (start, travel, overshoot, range, top speeds out and in: a
cylinder's step). They are compiled (numba) once per machine, not per model: the batch
engine computes them for every row without the Python interpreter's cost, and
``Result.summary()`` runs the very same code.

Each feature measures the actuator, not a threshold: the break-away pressure is where the
sliding line of a branch meets the position the branch started from (no motion threshold,
so it does not see the bristle stiffness σ0); the loop width is the pressure gap between
the branches at stated positions. ``docs/features.md`` gives every definition with the
conditions under which it means what its name says.

Branches: the record is cut at its pressure turning points (a reversal counts once the
pressure has come back by more than 10 % of its range, so regulator overshoot or noise
is ignored). A branch is *complete* when it spans at least half the pressure range; the
loop features use the last pair of adjacent complete branches (one falling, one rising).
A record without such a pair (a step response, say) gives NaN loop features.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from pneumact.core.compile_lock import compile_one_process_at_a_time
from pneumact.errors import DataError

from .jit import lazy_dispatcher, njit

__all__ = [
    "FEATURES",
    "FEATURE_UNITS",
    "MOTION_FEATURES",
    "SUMMARY_FEATURES",
    "breakaway_pressure",
    "hysteresis_summary",
    "loop_area",
    "loop_width_position",
    "loop_width_pressure",
    "loop_width_profile",
    "max_error",
    "motion_onset_pressure",
    "presliding_travel",
    "rms_error",
    "sliding_speed",
    "stroke",
    "turning_points",
]

#: Every feature, in the order of the compiled ``all_features`` vector, with its SI unit.
FEATURE_UNITS: dict[str, str] = {
    "final_position": "m",
    "max_velocity": "m/s",
    "stroke": "m",
    "loop_width_pressure": "Pa",
    "loop_width_position": "m",
    "loop_area": "Pa*m",
    "breakaway_pressure": "Pa",
    "sliding_speed": "m/s",
    "presliding_travel": "m",
    "rms_error": "m",
    "max_error": "m",
    "start_position": "m",
    "travel": "m",
    "overshoot": "m",
    "position_range": "m",
    "top_speed_out": "m/s",
    "top_speed_in": "m/s",
}
FEATURES = tuple(FEATURE_UNITS)
#: each feature's place in that vector (compiled code reads these constants)
F_FINAL_POSITION = FEATURES.index("final_position")
F_MAX_VELOCITY = FEATURES.index("max_velocity")
F_STROKE = FEATURES.index("stroke")
F_LOOP_WIDTH_PRESSURE = FEATURES.index("loop_width_pressure")
F_LOOP_WIDTH_POSITION = FEATURES.index("loop_width_position")
F_LOOP_AREA = FEATURES.index("loop_area")
F_BREAKAWAY_PRESSURE = FEATURES.index("breakaway_pressure")
F_SLIDING_SPEED = FEATURES.index("sliding_speed")
F_PRESLIDING_TRAVEL = FEATURES.index("presliding_travel")
F_RMS_ERROR = FEATURES.index("rms_error")
F_MAX_ERROR = FEATURES.index("max_error")
F_START_POSITION = FEATURES.index("start_position")
F_TRAVEL = FEATURES.index("travel")
F_OVERSHOOT = FEATURES.index("overshoot")
F_POSITION_RANGE = FEATURES.index("position_range")
F_TOP_SPEED_OUT = FEATURES.index("top_speed_out")
F_TOP_SPEED_IN = FEATURES.index("top_speed_in")
N_FEATURES = len(FEATURES)
#: Features that need a pressure record, and those that need a reference record.
PRESSURE_FEATURES = ("loop_width_pressure", "loop_width_position", "loop_area",
                     "breakaway_pressure", "sliding_speed", "presliding_travel")
REFERENCE_FEATURES = ("rms_error", "max_error")
#: A move's features, from position and velocity alone (``Result.summary()`` of a model
#: whose ``summary_kind`` is "motion": a cylinder's step, a rig's motion).
MOTION_FEATURES = ("start_position", "final_position", "travel", "overshoot",
                   "position_range", "top_speed_out", "top_speed_in")
#: The features a batch computes by default for a model of each ``summary_kind`` (the
#: pressure features where the model has a pressure signal): what its runs' summary says.
SUMMARY_FEATURES: dict[str, tuple[str, ...]] = {
    "hysteresis": ("final_position", "max_velocity", "stroke", *PRESSURE_FEATURES),
    "motion": MOTION_FEATURES,
}

#: The sliding part of a branch: from this fraction of its travel to that one (counted
#: from where the branch starts). Gross sliding needs the travel to exceed the presliding
#: range (≈ 3·Fs/σ0, 0.1 mm for vgt-paper) well before 20 %, and the end stop is only
#: reached after the branch's last 20 %; the break-away and the sliding speed use it.
SLIDING_WINDOW = (0.2, 0.8)
#: The presliding travel is read while the pressure comes back from a reversal by this
#: fraction of the loop width: the friction then swings from its sliding level to zero.
PRESLIDING_WIDTH_FRACTION = 0.5
#: A pressure reversal smaller than this fraction of the range is not a turning point.
TURN_TOLERANCE = 0.10
#: A branch spanning at least this fraction of the pressure range is complete.
COMPLETE_BRANCH_FRACTION = 0.5
#: Grids of the loop widths: fractions of the stroke / pressure range, and grid size.
POSITION_GRID = (0.2, 0.8)
PRESSURE_GRID = (0.2, 0.8)
GRID_POINTS = 41


# --------------------------------------------------------------------------- compiled
@njit(cache=True)
def _span(x):  # pragma: no cover - compiled
    """(min, max) of x."""
    lo = x[0]
    hi = x[0]
    for i in range(x.shape[0]):
        lo = min(lo, x[i])
        hi = max(hi, x[i])
    return lo, hi


@njit(cache=True)
def _stroke(x):  # pragma: no cover - compiled
    lo, hi = _span(x)
    return hi - lo


@njit(cache=True)
def _motion_onset(p, x, threshold):  # pragma: no cover - compiled
    """Pressure at the first sample where |x − x[0]| exceeds ``threshold`` (linear
    interpolation with the sample before); NaN if it never does."""
    for i in range(1, x.shape[0]):
        after = abs(x[i] - x[0])
        if after > threshold:
            before = abs(x[i - 1] - x[0])
            fraction = (threshold - before) / (after - before)
            return p[i - 1] + fraction * (p[i] - p[i - 1])
    return math.nan


@njit(cache=True)
def _turning_points(p):  # pragma: no cover - compiled
    """Indices [0, turns..., n-1] cutting ``p`` into monotone-trend branches."""
    n = p.shape[0]
    turns = np.empty(n, dtype=np.int64)
    turns[0] = 0
    count = 1
    lo, hi = _span(p)
    tolerance = TURN_TOLERANCE * (hi - lo)
    trend = 0
    extreme = 0
    last_dir = 0.0
    last_step = -1
    for k in range(n):
        # the candidates are the local extrema (the sample after the last step of each
        # monotone run, flat steps skipped) and finally n-1
        if k < n - 1:
            step = p[k + 1] - p[k]
            if step == 0.0:
                continue
            direction = 1.0 if step > 0.0 else -1.0
            is_candidate = last_dir != 0.0 and direction != last_dir
            i = last_step + 1
            last_dir = direction
            last_step = k
            if not is_candidate:
                continue
        else:
            i = n - 1
        value = p[i]
        if trend == 0:
            if abs(value - p[0]) > tolerance:
                trend = 1 if value > p[0] else -1
                extreme = i
        elif trend * (value - p[extreme]) >= 0.0:
            extreme = i
        elif abs(value - p[extreme]) > tolerance:
            turns[count] = extreme
            count += 1
            trend = -trend
            extreme = i
    if turns[count - 1] != n - 1:
        turns[count] = n - 1
        count += 1
    return turns[:count]


@njit(cache=True)
def _last_loop(p):  # pragma: no cover - compiled
    """(falling start, falling stop, rising start, rising stop) of the last complete pair
    of branches, stops exclusive; all -1 if there is none."""
    lo, hi = _span(p)
    span = hi - lo
    turns = _turning_points(p)
    if span == 0.0 or turns.shape[0] < 3:
        return -1, -1, -1, -1
    found = -1
    for j in range(turns.shape[0] - 2):
        c0 = p[turns[j + 1]] - p[turns[j]]
        c1 = p[turns[j + 2]] - p[turns[j + 1]]
        limit = COMPLETE_BRANCH_FRACTION * span
        if abs(c0) >= limit and abs(c1) >= limit and c0 * c1 < 0.0:
            found = j
    if found < 0:
        return -1, -1, -1, -1
    a0, a1 = turns[found], turns[found + 1] + 1
    b0, b1 = turns[found + 1], turns[found + 2] + 1
    if p[turns[found + 1]] - p[turns[found]] < 0.0:
        return a0, a1, b0, b1
    return b0, b1, a0, a1


@njit(cache=True)
def _first_at_least(sorted_values, level):  # pragma: no cover - compiled
    """First index i with sorted_values[i] >= level (len if none): a bisection."""
    lo, hi = 0, sorted_values.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if sorted_values[mid] < level:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def _first_crossing(level, along, read, running):  # pragma: no cover - compiled
    """Value of ``read`` where ``along`` first reaches ``level`` (linear interpolation),
    NaN if never. ``running``: running max (level above the start) or −running min."""
    n = along.shape[0]
    if level >= along[0]:
        index = _first_at_least(running[0], level)
    else:
        index = _first_at_least(running[1], -level)
    if index >= n:
        return math.nan
    previous = max(index - 1, 0)
    a0, a1 = along[previous], along[index]
    gap = a1 - a0
    fraction = (level - a0) / gap if gap != 0.0 else 1.0
    return read[previous] + fraction * (read[index] - read[previous])


@njit(cache=True)
def _running(along):  # pragma: no cover - compiled
    """(running maximum, −running minimum) of ``along``, both non-decreasing."""
    n = along.shape[0]
    out = np.empty((2, n))
    hi = along[0]
    lo = along[0]
    for i in range(n):
        hi = max(hi, along[i])
        lo = min(lo, along[i])
        out[0, i] = hi
        out[1, i] = -lo
    return out


@njit(cache=True)
def _mean_gap(levels, along_a, read_a, along_b, read_b):  # pragma: no cover - compiled
    """Mean |read_a − read_b| where each branch first reaches each of GRID_POINTS levels
    evenly spaced over ``levels`` = (first, last) (NaNs skipped)."""
    run_a = _running(along_a)
    run_b = _running(along_b)
    total = 0.0
    count = 0
    for i in range(GRID_POINTS):
        level = levels[0] + (levels[1] - levels[0]) * i / (GRID_POINTS - 1)
        gap = (_first_crossing(level, along_a, read_a, run_a)
               - _first_crossing(level, along_b, read_b, run_b))
        if math.isfinite(gap):
            total += abs(gap)
            count += 1
    return total / count if count else math.nan


# Each loop feature has two forms: ``_name(p, x)``, which finds the last loop itself
# (the common library's entry points, the public functions), and ``_name_in(p, x,
# loop)``, which is given it: ``_pressure_features`` finds the loop once for all six
# (it was found seven times; every feature of one 4001-point record: numba 119 → 42-55 µs,
# measured 2026-11-27 under load), with the same arithmetic, so the values are the same
# bit for bit.
@njit(cache=True)
def _loop_width_pressure(p, x):  # pragma: no cover - compiled
    return _loop_width_pressure_in(p, x, _last_loop(p))


@njit(cache=True)
def _loop_width_pressure_in(p, x, loop):  # pragma: no cover - compiled
    f0, f1, r0, r1 = loop
    if f0 < 0:
        return math.nan
    fa, fb = _span(x[f0:f1])
    ra, rb = _span(x[r0:r1])
    lo, hi = min(fa, ra), max(fb, rb)
    if hi <= lo:
        return 0.0
    levels = (lo + (hi - lo) * POSITION_GRID[0], lo + (hi - lo) * POSITION_GRID[1])
    return _mean_gap(levels, x[f0:f1], p[f0:f1], x[r0:r1], p[r0:r1])


@njit(cache=True)
def _loop_width_position(p, x):  # pragma: no cover - compiled
    return _loop_width_position_in(p, x, _last_loop(p))


@njit(cache=True)
def _loop_width_position_in(p, x, loop):  # pragma: no cover - compiled
    f0, f1, r0, r1 = loop
    if f0 < 0:
        return math.nan
    fa, fb = _span(p[f0:f1])
    ra, rb = _span(p[r0:r1])
    lo, hi = max(fa, ra), min(fb, rb)
    if hi <= lo:
        return math.nan
    levels = (lo + (hi - lo) * PRESSURE_GRID[0], lo + (hi - lo) * PRESSURE_GRID[1])
    return _mean_gap(levels, p[f0:f1], x[f0:f1], p[r0:r1], x[r0:r1])


@njit(cache=True)
def _sliding_levels(xb):  # pragma: no cover - compiled
    """(start, first level, last level) of the sliding window of a branch that moves
    towards larger x (the falling-pressure branch); levels NaN if it does not move."""
    start = xb[0]
    _, top = _span(xb)
    travel = top - start
    if not travel > 0.0:
        return start, math.nan, math.nan
    return start, start + SLIDING_WINDOW[0] * travel, start + SLIDING_WINDOW[1] * travel


@njit(cache=True)
def _breakaway(p, x):  # pragma: no cover - compiled
    return _breakaway_in(p, x, _last_loop(p))


@njit(cache=True)
def _breakaway_in(p, x, loop):  # pragma: no cover - compiled
    """Pressure where the sliding line of the last loop's falling branch (p against x,
    least squares over the sliding window, read where the branch first reaches each of
    GRID_POINTS positions) meets the position the branch started from; NaN without a
    loop or when the line does not fall with x."""
    f0, f1, _, _ = loop
    if f0 < 0:
        return math.nan
    xb, pb = x[f0:f1], p[f0:f1]
    start, first, last = _sliding_levels(xb)
    if not math.isfinite(first):
        return math.nan
    run = _running(xb)
    n = 0
    sx = sp = sxx = sxp = 0.0
    for i in range(GRID_POINTS):
        level = first + (last - first) * i / (GRID_POINTS - 1)
        value = _first_crossing(level, xb, pb, run)
        if math.isfinite(value):
            u = level - start
            n += 1
            sx += u
            sp += value
            sxx += u * u
            sxp += u * value
    denominator = n * sxx - sx * sx
    if n < 2 or denominator <= 0.0:
        return math.nan
    slope = (n * sxp - sx * sp) / denominator
    if not slope < 0.0:
        return math.nan
    return (sp - slope * sx) / n  # the line at u = 0: the branch's starting position


@njit(cache=True)
def _sliding_speed(t, p, x):  # pragma: no cover - compiled
    return _sliding_speed_in(t, x, _last_loop(p))


@njit(cache=True)
def _sliding_speed_in(t, x, loop):  # pragma: no cover - compiled
    """Mean speed over the sliding window of the last loop's falling branch: the window's
    travel over the time the branch takes to cross it."""
    f0, f1, _, _ = loop
    if f0 < 0:
        return math.nan
    xb, tb = x[f0:f1], t[f0:f1]
    _, first, last = _sliding_levels(xb)
    if not math.isfinite(first):
        return math.nan
    run = _running(xb)
    duration = _first_crossing(last, xb, tb, run) - _first_crossing(first, xb, tb, run)
    return (last - first) / duration if duration > 0.0 else math.nan


@njit(cache=True)
def _presliding_travel(p, x):  # pragma: no cover - compiled
    loop = _last_loop(p)
    return _presliding_travel_in(p, x, loop, _loop_width_pressure_in(p, x, loop))


@njit(cache=True)
def _presliding_travel_in(p, x, loop, width):  # pragma: no cover - compiled
    """|Δx| on the last loop's rising branch from its low-pressure reversal until the
    pressure has come back by PRESLIDING_WIDTH_FRACTION of the loop width; NaN without a
    loop or when the branch starts the record (no reversal); ``width``: the loop's width
    in pressure."""
    f0, _, r0, r1 = loop
    if f0 < 0 or r0 == 0:
        return math.nan
    if not width > 0.0:
        return math.nan
    pb, xb = p[r0:r1], x[r0:r1]
    run = _running(pb)
    level = pb[0] + PRESLIDING_WIDTH_FRACTION * width
    return abs(_first_crossing(level, pb, xb, run) - xb[0])


@njit(cache=True)
def _loop_area(p, x):  # pragma: no cover - compiled
    return _loop_area_in(p, x, _last_loop(p))


@njit(cache=True)
def _loop_area_in(p, x, loop):  # pragma: no cover - compiled
    """|∮ p dx| of the last complete loop, closed by a straight segment (shoelace)."""
    f0, f1, r0, r1 = loop
    if f0 < 0:
        return math.nan
    start = min(f0, r0)
    stop = max(f1, r1)
    total = 0.0
    for i in range(start, stop):
        k = i + 1 if i + 1 < stop else start
        total += p[i] * x[k] - p[k] * x[i]
    return 0.5 * abs(total)


@njit(cache=True)
def _position_errors(t, x, ref_t, ref_x):  # pragma: no cover - compiled
    """(rms, max) of x − reference over the overlap of the two time spans; NaN if none.

    Both time axes increase, so the reference is interpolated by one merge walk."""
    total = 0.0
    worst = 0.0
    count = 0
    k = 0
    last = ref_t.shape[0] - 1
    for i in range(t.shape[0]):
        if not ref_t[0] <= t[i] <= ref_t[last]:
            continue
        while k < last - 1 and ref_t[k + 1] <= t[i]:
            k += 1
        fraction = (t[i] - ref_t[k]) / (ref_t[k + 1] - ref_t[k]) if last > 0 else 0.0
        # (1 − f)·a + f·b is exact at both nodes, like np.interp
        err = x[i] - ((1.0 - fraction) * ref_x[k] + fraction * ref_x[min(k + 1, last)])
        total += err * err
        worst = max(worst, abs(err))
        count += 1
    if count == 0:
        return math.nan, math.nan
    return math.sqrt(total / count), worst


@njit(cache=True)
def _pressure_features(t, p, x, out):
    """The features of PRESSURE_FEATURES into ``out`` (a run's summary needs these and the
    stroke only: it compiles them without the rest of ``all_features``); the last loop
    is found once for all of them."""
    loop = _last_loop(p)
    width = _loop_width_pressure_in(p, x, loop)
    out[F_LOOP_WIDTH_PRESSURE] = width
    out[F_LOOP_WIDTH_POSITION] = _loop_width_position_in(p, x, loop)
    out[F_LOOP_AREA] = _loop_area_in(p, x, loop)
    out[F_BREAKAWAY_PRESSURE] = _breakaway_in(p, x, loop)
    out[F_SLIDING_SPEED] = _sliding_speed_in(t, x, loop)
    out[F_PRESLIDING_TRAVEL] = _presliding_travel_in(p, x, loop, width)


@njit(cache=True)
def _motion_features(x, v, out):  # pragma: no cover - compiled
    """The features of MOTION_FEATURES into ``out``: a move from the first position to
    the last, as ``simulation.result.motion_summary`` defines it."""
    start, final = x[0], x[-1]
    travel = final - start
    direction = 1.0 if travel >= 0.0 else -1.0
    farthest = direction * (x[0] - final)
    for i in range(x.shape[0]):
        farthest = max(farthest, direction * (x[i] - final))
    lo, hi = _span(x)
    v_lo, v_hi = _span(v)
    out[F_START_POSITION] = start
    out[F_TRAVEL] = travel
    out[F_OVERSHOOT] = max(0.0, farthest)
    out[F_POSITION_RANGE] = hi - lo
    out[F_TOP_SPEED_OUT] = max(0.0, v_hi)
    out[F_TOP_SPEED_IN] = max(0.0, -v_lo)


@njit(cache=True)
def all_features(t, x, v, p, has_pressure, ref_t, ref_x, has_reference, out):
    """Every feature of FEATURES into ``out`` (NaN where one does not apply)."""
    for k in range(N_FEATURES):
        out[k] = math.nan
    out[F_FINAL_POSITION] = x[-1]
    v_lo, v_hi = _span(v)
    out[F_MAX_VELOCITY] = max(-v_lo, v_hi)
    out[F_STROKE] = _stroke(x)
    _motion_features(x, v, out)
    if has_pressure:
        _pressure_features(t, p, x, out)
    if has_reference:
        out[F_RMS_ERROR], out[F_MAX_ERROR] = _position_errors(t, x, ref_t, ref_x)


# --------------------------------------------------------------------------- checks
def _as_signal(values, name: str) -> np.ndarray:
    array = np.ascontiguousarray(values, dtype=float)
    if array.ndim != 1:
        raise DataError(f"{name}: must be a 1-D array, got shape {array.shape}")
    if array.size < 3:
        raise DataError(f"{name}: has {array.size} samples; a feature needs at least 3")
    if not np.all(np.isfinite(array)):
        first = int(np.flatnonzero(~np.isfinite(array))[0])
        raise DataError(f"{name}: sample {first} is {array[first]}; every sample must be a "
                        "finite number")
    return array


def _signals(**named) -> list[np.ndarray]:
    """Check several same-length signals; the error names both lengths."""
    arrays = [_as_signal(values, name) for name, values in named.items()]
    names = list(named)
    for name, array in zip(names[1:], arrays[1:], strict=True):
        if array.size != arrays[0].size:
            raise DataError(f"{name} has {array.size} samples but {names[0]} has "
                            f"{arrays[0].size}; the signals of one record must have the "
                            "same length")
    return arrays


def _reference(ref_time, ref_position) -> tuple[np.ndarray, np.ndarray]:
    rt, rx = _signals(ref_time=ref_time, ref_position=ref_position)
    if np.any(np.diff(rt) <= 0):
        raise DataError("ref_time: must be strictly increasing to interpolate the reference")
    return rt, rx


# --------------------------------------------------------------------------- public API
def _on_engine(function):
    """``function`` on the engine in force (``core.c_common``: on C, its translation in
    the library every model shares)."""
    from .c_common import on_engine

    return on_engine(function)


def stroke(position) -> float:
    """Travel of the record: max − min of the position [m]."""
    (x,) = _signals(position=position)
    return float(_on_engine(_stroke)(x))


def breakaway_pressure(time, pressure, position) -> float:
    """Break-away pressure [Pa]: where the sliding line of the loop's falling-pressure
    branch meets the position that branch started from (at rest, on the default cycle).

    The line is fitted (pressure against position) over 20–80 % of the branch's travel,
    where the diaphragm slides, and extrapolated back: the onset of gross sliding, with
    no motion threshold, so the bristle stiffness σ0 and the presliding creep do not move
    it. In steady sliding its vacuum is (F0 + k·x_start + F_slide)/A_d, F_slide = g(v) +
    σ2·v at the branch's sliding speed: (F0 + Fc)/A_d when v ≫ vs. NaN without a
    complete loop. ``time`` is accepted for a uniform signature."""
    _, p, x = _signals(time=time, pressure=pressure, position=position)
    return float(_on_engine(_breakaway)(p, x))


def motion_onset_pressure(time, pressure, position, threshold: float) -> float:
    """Pressure [Pa] at the first instant the position leaves its initial value by more
    than ``threshold`` [m], interpolated linearly between samples; NaN if it never does.

    This is a threshold measure: with LuGre friction the presliding creep runs to about
    3·Fs/σ0 before gross sliding, so below that the result follows σ0 and the threshold
    rather than the friction level (use ``breakaway_pressure`` for that)."""
    _, p, x = _signals(time=time, pressure=pressure, position=position)
    if not (np.isfinite(threshold) and threshold > 0):
        raise DataError(f"threshold = {threshold} m; must be a finite length > 0")
    return float(_on_engine(_motion_onset)(p, x, float(threshold)))


def sliding_speed(time, pressure, position) -> float:
    """Mean speed [m/s] of the loop's falling-pressure branch over 20–80 % of its travel
    (the window of the break-away line): the speed the loop's friction is measured at;
    divide by vs to say in which regime of the Stribeck curve the loop lies."""
    t, p, x = _signals(time=time, pressure=pressure, position=position)
    return float(_on_engine(_sliding_speed)(t, p, x))


def presliding_travel(pressure, position) -> float:
    """Position travel [m] after the loop's low-pressure reversal while the pressure comes
    back by half the loop width, i.e. while the friction swings from its sliding level to
    zero: the presliding compliance of the corner (for LuGre about (g/σ0)·ln 2)."""
    p, x = _signals(pressure=pressure, position=position)
    return float(_on_engine(_presliding_travel)(p, x))


def loop_width_pressure(pressure, position) -> float:
    """Mean pressure gap [Pa] between the falling and rising branch at equal positions
    (41 positions over 20–80 % of the loop's travel, each branch read where it first
    reaches the position; ``loop_width_profile`` gives the gap at each). For Coulomb
    friction Fc on area A this is 2·Fc/A; for LuGre sliding steadily at speed v it is
    2·(g(v) + σ2·v)/A, which is 2·Fc/A only while v ≫ vs (see ``sliding_speed``)."""
    p, x = _signals(pressure=pressure, position=position)
    return float(_on_engine(_loop_width_pressure)(p, x))


def loop_width_profile(pressure, position, positions=None) -> np.ndarray:
    """Pressure gap [Pa] between the falling and the rising branch of the last loop at
    each of ``positions`` [m] (default: the grid of ``loop_width_pressure``, 41 points
    over 20–80 % of the loop's travel); NaN where a branch does not reach a position.
    The loop width as a function of position: near the ends it shows the presliding
    corners and the end stops, in the middle the sliding friction 2·F_slide/A_d."""
    p, x = _signals(pressure=pressure, position=position)
    f0, f1, r0, r1 = _last_loop(p)
    if f0 < 0:
        size = GRID_POINTS if positions is None else np.size(positions)
        return np.full(size, np.nan)
    if positions is None:
        lo = min(x[f0:f1].min(), x[r0:r1].min())
        hi = max(x[f0:f1].max(), x[r0:r1].max())
        positions = np.linspace(lo + (hi - lo) * POSITION_GRID[0],
                                lo + (hi - lo) * POSITION_GRID[1], GRID_POINTS)
    levels = np.atleast_1d(np.asarray(positions, dtype=float))
    falling, rising = (x[f0:f1], p[f0:f1]), (x[r0:r1], p[r0:r1])
    runs = _running(falling[0]), _running(rising[0])
    return np.array([_first_crossing(level, *rising, runs[1])
                     - _first_crossing(level, *falling, runs[0]) for level in levels])


def loop_width_position(pressure, position) -> float:
    """Mean position gap [m] between the falling and rising branch at equal pressures
    (grid over the middle 60 % of the pressure range both branches cover). For Coulomb
    friction Fc and spring stiffness k this is 2·Fc/k (2·F_slide(v)/k in general)."""
    p, x = _signals(pressure=pressure, position=position)
    return float(_on_engine(_loop_width_position)(p, x))


def loop_area(pressure, position) -> float:
    """|∮ p dx| [Pa·m] of the last complete loop (shoelace formula, closed by a straight
    segment from its end back to its start): the friction work per cycle divided by A."""
    p, x = _signals(pressure=pressure, position=position)
    return float(_on_engine(_loop_area)(p, x))


def _errors(time, position, ref_time, ref_position) -> tuple[float, float]:
    t, x = _signals(time=time, position=position)
    rt, rx = _reference(ref_time, ref_position)
    if t[-1] < rt[0] or t[0] > rt[-1]:
        raise DataError(f"time spans {t[0]:g}..{t[-1]:g} s but the reference spans "
                        f"{rt[0]:g}..{rt[-1]:g} s; they must overlap")
    rms, worst = _position_errors(t, x, rt, rx)
    return float(rms), float(worst)


def rms_error(time, position, ref_time, ref_position) -> float:
    """Root-mean-square position error [m] against a reference interpolated on ``time``
    (only where the two records overlap in time)."""
    return _errors(time, position, ref_time, ref_position)[0]


def max_error(time, position, ref_time, ref_position) -> float:
    """Largest absolute position error [m] against a reference interpolated on ``time``."""
    return _errors(time, position, ref_time, ref_position)[1]


def turning_points(time, pressure, position) -> np.ndarray:
    """Indices cutting the record into branches of one pressure trend: 0, each reversal
    of the pressure beyond 10 % of its range, and the last sample (the cuts every loop
    feature uses)."""
    _, p, _ = _signals(time=time, pressure=pressure, position=position)
    return _on_engine(_turning_points)(p)


def hysteresis_summary(time, pressure, position) -> dict[str, float]:
    """The hysteresis features of one record, SI (units in ``FEATURE_UNITS``)."""
    t, p, x = _signals(time=time, pressure=pressure, position=position)
    out = np.full(N_FEATURES, np.nan)
    out[F_STROKE] = _on_engine(_stroke)(x)
    _on_engine(_pressure_features)(t, p, x, out)
    names = ("stroke", *PRESSURE_FEATURES)
    return {name: float(out[FEATURES.index(name)]) for name in names}


def _features_lock() -> Path:
    """The lock the features compile under: named and placed as a kernel function's
    (``core.codegen.compile_lock_path``), beside the kernels."""
    from pneumact.core.codegen import cache_dir, compile_lock_path

    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    return compile_lock_path(str(folder / "pneumact_core_features.py"), "all_features")


#: a batch's features compile once per machine: processes that start batches together
#: (a Dask cluster, a parallel test run) wait for the first instead of each compiling
all_features = lazy_dispatcher(
    all_features.py_func, all_features.options,
    prepare=functools.partial(compile_one_process_at_a_time, lock_path=_features_lock))
