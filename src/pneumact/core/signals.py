"""Input signals (pressure, command, force, velocity, ...) and their compiled evaluation.

A signal is a sum of terms. Each term is piecewise linear (ramps, steps, triangles,
measured samples) or a windowed sine. Every corner and jump is declared as a breakpoint:
the integrator stops there and restarts, so it never steps over a corner.

Terms are packed into one float64 array per channel so the compiled kernels can read
them without Python objects:

    channel = [n_terms, term, term, ...]
    piecewise-linear term = [0, n, t_0 .. t_{n-1}, y_0 .. y_{n-1}]   (held flat outside)
    sine term             = [1, 5, amplitude, frequency, phase, t_start, t_stop]

``channel_eval`` picks the segment from a *segment time* (the midpoint of the interval
between two breakpoints being integrated) and evaluates its linear formula at the actual
time. Inside one interval the segment is then fixed, so a jump at a breakpoint is seen
from the correct side by every stage of the integrator.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..errors import ExperimentError
from .jit import njit

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

KIND_PWL = 0
KIND_SINE = 1


@njit(cache=True, inline="always")
def channel_driven(sig, ptr, ch):  # pragma: no cover - compiled
    """Whether channel ``ch`` holds a signal (an empty channel, ``None`` when packed, has
    no terms): a component whose input no experiment drives holds its own value."""
    return sig[ptr[ch]] > 0.0


@njit(cache=True, inline="always")
def channel_eval(sig, ptr, ch, s, s_seg):  # pragma: no cover - compiled
    """Value and slope of channel ``ch`` at ``s``; the segment is the one holding ``s_seg``."""
    i = ptr[ch]
    n_terms = int(sig[i])
    i += 1
    value = 0.0
    slope = 0.0
    for _ in range(n_terms):
        kind = int(sig[i])
        n = int(sig[i + 1])
        i += 2
        if kind == KIND_PWL:
            ts = i
            ys = i + n
            if n == 1 or s_seg < sig[ts]:
                value += sig[ys]
            elif s_seg >= sig[ts + n - 1]:
                value += sig[ys + n - 1]
            else:
                lo = 0
                hi = n - 1
                while hi - lo > 1:
                    mid = (lo + hi) // 2
                    if sig[ts + mid] <= s_seg:
                        lo = mid
                    else:
                        hi = mid
                t0 = sig[ts + lo]
                y0 = sig[ys + lo]
                sl = (sig[ys + lo + 1] - y0) / (sig[ts + lo + 1] - t0)
                value += y0 + sl * (s - t0)
                slope += sl
            i += 2 * n
        else:
            amp = sig[i]
            omega = 2.0 * math.pi * sig[i + 1]
            phase = sig[i + 2]
            t_start = sig[i + 3]
            t_stop = sig[i + 4]
            if s_seg < t_start:
                value += amp * math.sin(phase)
            elif s_seg >= t_stop:
                value += amp * math.sin(omega * (t_stop - t_start) + phase)
            else:
                arg = omega * (s - t_start) + phase
                value += amp * math.sin(arg)
                slope += amp * omega * math.cos(arg)
            i += n
    return value, slope


@njit(cache=True)
def map_eval(sig, ptr, ch, u):  # pragma: no cover - compiled
    """Value and slope of the static map in channel ``ch`` at ``u`` (a valve's area against
    its opening). Not inlined into its callers, unlike ``channel_eval``: a valve reads two
    maps at several places of every kernel function, and inlining that loop each time
    made the valve kernels compile in 15-17 s instead of 9-10 s, for no run time."""
    return channel_eval(sig, ptr, ch, u, u)


@njit(cache=True)
def _eval_many(sig, ptr, ch, s, out_value, out_slope):  # pragma: no cover - compiled
    for j in range(s.shape[0]):
        out_value[j], out_slope[j] = channel_eval(sig, ptr, ch, s[j], s[j])


class Signal:
    """A scalar function of time (or of position/command for maps), sum of terms.

    Signals add (``a + b``) and scale (``2.0 * a``). Calling a signal evaluates it with
    the right-continuous convention at jumps.
    """

    def __init__(self, terms: Sequence[np.ndarray]):
        self._terms = [np.asarray(t, dtype=np.float64) for t in terms]

    # -- packing -------------------------------------------------------------------
    def encode(self) -> np.ndarray:
        """The packed float64 channel array read by the compiled kernels."""
        return np.concatenate([np.array([float(len(self._terms))]), *self._terms])

    def breakpoints(self) -> np.ndarray:
        """Sorted unique times where the signal has a corner or a jump."""
        points: list[np.ndarray] = []
        for term in self._terms:
            n = int(term[1])
            if int(term[0]) == KIND_PWL:
                points.append(term[2 : 2 + n])
            else:
                points.append(term[5:7])
        if not points:
            return np.empty(0)
        bp = np.unique(np.concatenate(points))
        return bp[np.isfinite(bp)]

    # -- evaluation ----------------------------------------------------------------
    def __call__(self, t: float | np.ndarray) -> np.ndarray:
        return self.evaluate(t)[0]

    def evaluate(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value and slope at ``t`` (right-continuous at jumps)."""
        s = np.atleast_1d(np.asarray(t, dtype=np.float64))
        value = np.empty_like(s)
        slope = np.empty_like(s)
        from .c_common import on_engine

        on_engine(_eval_many)(self.encode(), np.zeros(1, dtype=np.int64), 0, s, value, slope)
        if np.ndim(t) == 0:
            return value[0], slope[0]
        return value, slope

    def extremes(self, t0: float, t1: float) -> tuple[float, float]:
        """(lowest, highest) value over [t0, t1]: exact at the corners of a piecewise
        linear signal (where its extremes lie, both sides of a jump), a fine grid in
        between for sines and sums."""
        points = [np.array([t0, t1], dtype=float)]
        bp = self.breakpoints()
        bp = bp[(bp >= t0) & (bp <= t1)]
        points += [bp, np.nextafter(bp, -np.inf)]
        if any(int(term[0]) != KIND_PWL for term in self._terms):
            points.append(np.linspace(t0, t1, 20001))
        grid = np.concatenate(points)
        values = self.evaluate(grid[(grid >= t0) & (grid <= t1)])[0]
        return float(np.min(values)), float(np.max(values))

    # -- algebra -------------------------------------------------------------------
    def __add__(self, other: Signal | float) -> Signal:
        if isinstance(other, (int, float)):
            other = Constant(float(other))
        if not isinstance(other, Signal):
            return NotImplemented
        return Signal(self._terms + other._terms)

    __radd__ = __add__

    def __mul__(self, factor: float) -> Signal:
        if not isinstance(factor, (int, float)):
            return NotImplemented
        scaled = []
        for term in self._terms:
            term = term.copy()
            n = int(term[1])
            if int(term[0]) == KIND_PWL:
                term[2 + n : 2 + 2 * n] *= factor
            else:
                term[2] *= factor
            scaled.append(term)
        return Signal(scaled)

    __rmul__ = __mul__

    def __repr__(self) -> str:
        return f"{type(self).__name__}(terms={len(self._terms)})"


def _pwl_term(t: ArrayLike, y: ArrayLike, what: str) -> np.ndarray:
    t = np.asarray(t, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    if t.size == 0 or t.size != y.size:
        raise ExperimentError(
            f"{what}: time and value need the same non-zero length, got {t.size} and {y.size}"
        )
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        bad = int(np.flatnonzero(~(np.isfinite(t) & np.isfinite(y)))[0])
        raise ExperimentError(f"{what}: sample {bad} is not finite (t={t[bad]}, y={y[bad]})")
    dt = np.diff(t)
    if np.any(dt < 0):
        bad = int(np.flatnonzero(dt < 0)[0])
        raise ExperimentError(
            f"{what}: time must not decrease, but t[{bad + 1}] = {t[bad + 1]} < "
            f"t[{bad}] = {t[bad]}"
        )
    if t.size > 2 and np.any((dt[1:] == 0) & (dt[:-1] == 0)):
        raise ExperimentError(f"{what}: a time appears more than twice (one jump per instant)")
    return np.concatenate([[KIND_PWL, t.size], t, y])


class PiecewiseLinear(Signal):
    """Linear between samples, held flat outside; a repeated time is a jump."""

    def __init__(self, t: ArrayLike, y: ArrayLike):
        super().__init__([_pwl_term(t, y, "PiecewiseLinear")])


class Constant(Signal):
    """A constant value."""

    def __init__(self, value: float):
        super().__init__([np.array([KIND_PWL, 1, 0.0, float(value)])])


class Step(Signal):
    """``before`` until ``t_step``, then ``after``."""

    def __init__(self, t_step: float, before: float, after: float):
        super().__init__(
            [_pwl_term([t_step, t_step], [before, after], "Step")]
        )


class Ramp(Signal):
    """From ``start`` to ``stop`` between ``t_start`` and ``t_start + duration``."""

    def __init__(self, start: float, stop: float, duration: float, t_start: float = 0.0):
        if not duration > 0:
            raise ExperimentError(f"Ramp: duration = {duration} s, must be > 0")
        super().__init__(
            [_pwl_term([t_start, t_start + duration], [start, stop], "Ramp")]
        )


class Triangle(Signal):
    """Triangle wave from ``first`` to ``second`` and back, ``cycles`` times.

    The slow up/down cycle of the quasi-static hysteresis test: one cycle lasts
    ``period`` seconds, half of it each way.
    """

    def __init__(
        self, first: float, second: float, period: float, cycles: int = 1,
        t_start: float = 0.0,
    ):
        if not period > 0:
            raise ExperimentError(f"Triangle: period = {period} s, must be > 0")
        if int(cycles) < 1:
            raise ExperimentError(f"Triangle: cycles = {cycles}, must be >= 1")
        n = 2 * int(cycles) + 1
        t = t_start + 0.5 * period * np.arange(n)
        y = np.where(np.arange(n) % 2 == 0, first, second)
        super().__init__([_pwl_term(t, y, "Triangle")])


class Sine(Signal):
    """``offset + amplitude·sin(2π·frequency·(t − t_start) + phase)`` on [t_start, t_stop)."""

    def __init__(
        self, amplitude: float, frequency: float, offset: float = 0.0, phase: float = 0.0,
        t_start: float = 0.0, t_stop: float = math.inf,
    ):
        if not frequency > 0:
            raise ExperimentError(f"Sine: frequency = {frequency} Hz, must be > 0")
        terms = [np.array([KIND_SINE, 5, amplitude, frequency, phase, t_start, t_stop])]
        if offset != 0.0:
            terms.append(np.array([KIND_PWL, 1, 0.0, float(offset)]))
        super().__init__(terms)


def pack_channels(channels: Sequence[Signal | None]) -> tuple[np.ndarray, np.ndarray]:
    """Pack signals into (data, offsets) for the kernels; ``None`` is an empty channel."""
    parts = []
    ptr = np.zeros(len(channels), dtype=np.int64)
    pos = 0
    for k, ch in enumerate(channels):
        enc = np.zeros(1) if ch is None else ch.encode()
        ptr[k] = pos
        pos += enc.size
        parts.append(enc)
    return np.concatenate(parts), ptr
