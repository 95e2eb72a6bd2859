"""Scalar features of a pressure–position hysteresis record (SI in, SI out).

These numbers summarise one simulated or measured run: the stroke, the width of the
hysteresis loop in pressure and in position, the loop area and the pressure at which
motion starts. They are used by ``Result.summary()``, the CLI and the batch engine, so
everything is vectorised numpy (no pandas, no Python loop over samples).

Branches: the record is cut at its pressure turning points (a reversal counts once the
pressure has come back by more than 10 % of its range, so regulator overshoot or noise
is ignored). A branch is *complete* when it spans at least half the pressure range; the
loop features use the last pair of adjacent complete branches (one falling, one rising).
A record without such a pair (a step response, say) gives NaN loop features.
"""

from __future__ import annotations

import numpy as np

from pneumact.errors import DataError

__all__ = [
    "FEATURE_UNITS",
    "breakaway_pressure",
    "hysteresis_summary",
    "loop_area",
    "loop_width_position",
    "loop_width_pressure",
    "max_error",
    "rms_error",
    "stroke",
]

#: SI unit of every feature this module computes.
FEATURE_UNITS: dict[str, str] = {
    "stroke": "m",
    "loop_width_pressure": "Pa",
    "loop_width_position": "m",
    "loop_area": "Pa*m",
    "breakaway_pressure": "Pa",
    "rms_error": "m",
    "max_error": "m",
}

#: Default motion threshold of ``breakaway_pressure``: this fraction of the stroke ...
BREAKAWAY_STROKE_FRACTION = 0.003  # 0.3 % of the stroke
#: ... but at least this much [m], so presliding (tens of µm) is not counted as motion.
BREAKAWAY_MIN_THRESHOLD = 50e-6  # [m] above LuGre presliding (Fs/σ0 ≈ 32 µm for vgt-paper)
#: A pressure reversal smaller than this fraction of the range is not a turning point.
TURN_TOLERANCE = 0.10
#: A branch spanning at least this fraction of the pressure range is complete.
COMPLETE_BRANCH_FRACTION = 0.5
#: Grids of the loop widths: fractions of the stroke / pressure range, and grid size.
POSITION_GRID = (0.2, 0.8)
PRESSURE_GRID = (0.2, 0.8)
GRID_POINTS = 41


# --------------------------------------------------------------------------- checks


def _as_signal(values, name: str) -> np.ndarray:
    array = np.asarray(values, dtype=float)
    if array.ndim != 1:
        raise DataError(f"{name}: must be a 1-D array, got shape {array.shape}")
    if array.size < 3:
        raise DataError(f"{name}: has {array.size} samples; a feature needs at least 3")
    if not np.all(np.isfinite(array)):
        first = int(np.flatnonzero(~np.isfinite(array))[0])
        raise DataError(
            f"{name}: sample {first} is {array[first]}; every sample must be a finite number"
        )
    return array


def _signals(**named) -> list[np.ndarray]:
    """Check several same-length signals; the error names both lengths."""
    arrays = [_as_signal(values, name) for name, values in named.items()]
    names = list(named)
    for name, array in zip(names[1:], arrays[1:], strict=True):
        if array.size != arrays[0].size:
            raise DataError(
                f"{name} has {array.size} samples but {names[0]} has {arrays[0].size}; "
                "the signals of one record must have the same length"
            )
    return arrays


# --------------------------------------------------------------------------- simple ones


def stroke(position) -> float:
    """Travel of the record: max − min of the position [m]."""
    (x,) = _signals(position=position)
    return float(x.max() - x.min())


def breakaway_pressure(time, pressure, position, threshold: float | None = None) -> float:
    """Pressure [Pa] at the first instant the position leaves its initial value by more
    than ``threshold`` [m] (default: 0.3 % of the stroke, at least 50 µm, so presliding is
    not motion), interpolated linearly between samples; NaN if it never moves."""
    _, p, x = _signals(time=time, pressure=pressure, position=position)
    if threshold is None:
        threshold = max(BREAKAWAY_STROKE_FRACTION * float(x.max() - x.min()),
                        BREAKAWAY_MIN_THRESHOLD)
    if not (np.isfinite(threshold) and threshold > 0):
        raise DataError(f"threshold = {threshold} m; must be a finite length > 0")
    excursion = np.abs(x - x[0])
    moved = np.flatnonzero(excursion > threshold)
    if moved.size == 0:
        return float("nan")
    i = int(moved[0])
    before, after = excursion[i - 1], excursion[i]
    fraction = (threshold - before) / (after - before)
    return float(p[i - 1] + fraction * (p[i] - p[i - 1]))


# --------------------------------------------------------------------------- branches


def _turning_points(p: np.ndarray) -> np.ndarray:
    """Indices [0, turns..., n-1] cutting ``p`` into monotone-trend branches."""
    n = p.size
    span = float(p.max() - p.min())
    if span == 0.0:
        return np.array([0, n - 1])
    step = np.diff(p)
    moving = np.flatnonzero(step != 0.0)
    if moving.size == 0:
        return np.array([0, n - 1])
    direction = np.sign(step[moving])
    changes = np.flatnonzero(direction[1:] != direction[:-1])
    candidates = moving[changes] + 1  # last sample of each run: a local extremum
    tolerance = TURN_TOLERANCE * span
    # Zig-zag over the local extrema only (few for a clean record), not over samples.
    turns = [0]
    trend = 0
    extreme = 0
    for i in [*candidates.tolist(), n - 1]:
        value = p[i]
        if trend == 0:
            if abs(value - p[0]) > tolerance:
                trend, extreme = (1 if value > p[0] else -1), i
        elif trend * (value - p[extreme]) >= 0.0:
            extreme = i
        elif abs(value - p[extreme]) > tolerance:
            turns.append(extreme)
            trend, extreme = -trend, i
    turns.append(n - 1)
    return np.unique(np.asarray(turns))


def _last_loop(p: np.ndarray) -> tuple[slice, slice] | None:
    """(falling branch, rising branch) of the last complete pair, or None."""
    turns = _turning_points(p)
    span = float(p.max() - p.min())
    if turns.size < 3 or span == 0.0:
        return None
    starts, ends = turns[:-1], turns[1:]
    change = p[ends] - p[starts]
    complete = np.abs(change) >= COMPLETE_BRANCH_FRACTION * span
    pairs = np.flatnonzero(complete[:-1] & complete[1:] & (change[:-1] * change[1:] < 0))
    if pairs.size == 0:
        return None
    j = int(pairs[-1])
    first = slice(int(starts[j]), int(ends[j]) + 1)
    second = slice(int(starts[j + 1]), int(ends[j + 1]) + 1)
    return (first, second) if change[j] < 0 else (second, first)


def _first_crossing(levels: np.ndarray, along: np.ndarray, read: np.ndarray) -> np.ndarray:
    """Value of ``read`` where ``along`` first reaches each of ``levels`` (linear
    interpolation between samples); NaN where a level is never reached.

    A level above the start is first reached where the running maximum of ``along``
    reaches it (below the start: the running minimum), so one cumulative pass and a
    binary search per level replace a levels × samples comparison.
    """
    levels = np.asarray(levels, dtype=np.float64)
    n = along.size
    index = np.full(levels.size, n, dtype=np.int64)
    up = levels >= along[0]
    if up.any():
        index[up] = np.searchsorted(np.maximum.accumulate(along), levels[up], side="left")
    down = ~up
    if down.any():
        index[down] = np.searchsorted(-np.minimum.accumulate(along), -levels[down],
                                      side="left")
    reached = index < n
    index = np.minimum(index, n - 1)
    previous = np.maximum(index - 1, 0)
    a0, a1 = along[previous], along[index]
    r0, r1 = read[previous], read[index]
    gap = a1 - a0
    with np.errstate(invalid="ignore", divide="ignore"):
        fraction = np.where(gap != 0.0, (levels - a0) / gap, 1.0)
    value = r0 + fraction * (r1 - r0)
    return np.where(reached, value, np.nan)


def _mean_abs(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(np.mean(np.abs(finite))) if finite.size else float("nan")


# --------------------------------------------------------------------------- loop features


def loop_width_pressure(pressure, position) -> float:
    """Mean pressure gap [Pa] between the falling and rising branch at equal positions
    (grid over 20–80 % of the stroke; each branch read where it first reaches the
    position). For Coulomb friction Fc on area A this is 2·Fc/A."""
    p, x = _signals(pressure=pressure, position=position)
    loop = _last_loop(p)
    if loop is None:
        return float("nan")
    falling, rising = loop
    lo, hi = min(x[falling].min(), x[rising].min()), max(x[falling].max(), x[rising].max())
    if hi <= lo:
        return 0.0
    levels = lo + (hi - lo) * np.linspace(*POSITION_GRID, GRID_POINTS)
    gap = (_first_crossing(levels, x[falling], p[falling])
           - _first_crossing(levels, x[rising], p[rising]))
    return _mean_abs(gap)


def loop_width_position(pressure, position) -> float:
    """Mean position gap [m] between the falling and rising branch at equal pressures
    (grid over the middle 60 % of the pressure range). For Coulomb friction Fc and
    spring stiffness k this is 2·Fc/k."""
    p, x = _signals(pressure=pressure, position=position)
    loop = _last_loop(p)
    if loop is None:
        return float("nan")
    falling, rising = loop
    lo = max(p[falling].min(), p[rising].min())
    hi = min(p[falling].max(), p[rising].max())
    if hi <= lo:
        return float("nan")
    levels = lo + (hi - lo) * np.linspace(*PRESSURE_GRID, GRID_POINTS)
    gap = (_first_crossing(levels, p[falling], x[falling])
           - _first_crossing(levels, p[rising], x[rising]))
    return _mean_abs(gap)


def loop_area(pressure, position) -> float:
    """|∮ p dx| [Pa·m] of the last complete loop (shoelace formula, closed by a straight
    segment from its end back to its start): the friction work per cycle divided by A."""
    p, x = _signals(pressure=pressure, position=position)
    loop = _last_loop(p)
    if loop is None:
        return float("nan")
    start = min(loop[0].start, loop[1].start)
    stop = max(loop[0].stop, loop[1].stop)
    pp, xx = p[start:stop], x[start:stop]
    return float(0.5 * abs(np.dot(pp, np.roll(xx, -1)) - np.dot(np.roll(pp, -1), xx)))


# --------------------------------------------------------------------------- errors


def _position_error(time, position, ref_time, ref_position) -> np.ndarray:
    t, x = _signals(time=time, position=position)
    rt, rx = _signals(ref_time=ref_time, ref_position=ref_position)
    if np.any(np.diff(rt) <= 0):
        raise DataError("ref_time: must be strictly increasing to interpolate the reference")
    inside = (t >= rt[0]) & (t <= rt[-1])
    if not np.any(inside):
        raise DataError(
            f"time spans {t[0]:g}..{t[-1]:g} s but the reference spans {rt[0]:g}..{rt[-1]:g} "
            "s; they must overlap"
        )
    return x[inside] - np.interp(t[inside], rt, rx)


def rms_error(time, position, ref_time, ref_position) -> float:
    """Root-mean-square position error [m] against a reference interpolated on ``time``
    (only where the two records overlap in time)."""
    error = _position_error(time, position, ref_time, ref_position)
    return float(np.sqrt(np.mean(error**2)))


def max_error(time, position, ref_time, ref_position) -> float:
    """Largest absolute position error [m] against a reference interpolated on ``time``."""
    error = _position_error(time, position, ref_time, ref_position)
    return float(np.max(np.abs(error)))


def hysteresis_summary(time, pressure, position) -> dict[str, float]:
    """All hysteresis features of one record, SI (units in ``FEATURE_UNITS``)."""
    t, p, x = _signals(time=time, pressure=pressure, position=position)
    return {
        "stroke": stroke(x),
        "loop_width_pressure": loop_width_pressure(p, x),
        "loop_width_position": loop_width_position(p, x),
        "loop_area": loop_area(p, x),
        "breakaway_pressure": breakaway_pressure(t, p, x),
    }
