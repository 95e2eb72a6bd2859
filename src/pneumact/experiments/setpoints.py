"""Position set-point experiments for closed loops: steps, ramps, piecewise-linear and
measured profiles. Each is an ``Experiment`` of the quantity ``position`` [m]."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..core.signals import PiecewiseLinear, Step
from ..errors import ExperimentError
from .actuator import Experiment

__all__ = ["SetpointProfile", "SetpointRamp", "SetpointStep", "SetpointTable"]


def _check(name: str, t_end: float, n_points: int, **positions: float) -> None:
    for key, value in positions.items():
        if not math.isfinite(value):
            raise ExperimentError(f"{name}: {key} = {value!r} m; must be a finite position")
    if not (math.isfinite(t_end) and t_end > 0):
        raise ExperimentError(f"{name}: t_end = {t_end!r} s; must be > 0")
    if int(n_points) < 2:
        raise ExperimentError(f"{name}: n_points = {n_points}; must be >= 2")


def SetpointStep(start: float, stop: float, t_step: float = 0.1, t_end: float = 1.0,
                 n_points: int = 4001) -> Experiment:
    """The set-point jumps from ``start`` to ``stop`` [m] at ``t_step`` [s] (by default
    after 0.1 s at ``start``, where a loop built to hold ``start`` rests)."""
    _check("SetpointStep", t_end, n_points, start=start, stop=stop)
    if not 0.0 <= t_step < t_end:
        raise ExperimentError(f"SetpointStep: t_step = {t_step} s; must be in [0, {t_end})")
    signal = Step(t_step, start, stop) if t_step > 0 else PiecewiseLinear([0.0], [stop])
    return Experiment(signal, "position", t_end, n_points=n_points, name="SetpointStep")


def SetpointRamp(start: float, stop: float, duration: float, t_start: float = 0.0,
                 t_end: float | None = None, n_points: int = 4001) -> Experiment:
    """From ``start`` to ``stop`` [m] at constant speed over ``duration`` [s] from
    ``t_start``, then held (``t_end`` default: twice the ramp's end)."""
    end = 2.0 * (t_start + duration) if t_end is None else t_end
    _check("SetpointRamp", end, n_points, start=start, stop=stop)
    if not duration > 0:
        raise ExperimentError(f"SetpointRamp: duration = {duration} s; must be > 0")
    signal = PiecewiseLinear([t_start, t_start + duration], [start, stop])
    return Experiment(signal, "position", end, n_points=n_points, name="SetpointRamp")


def SetpointTable(times: ArrayLike, positions: ArrayLike,
                  t_end: float | None = None, n_points: int = 4001) -> Experiment:
    """Piecewise-linear set-point through (time [s], position [m]) corners; a repeated
    time is a jump."""
    times = np.asarray(times, dtype=float)
    signal = PiecewiseLinear(times, positions)
    end = float(times[-1]) if t_end is None else float(t_end)
    _check("SetpointTable", end, n_points)
    return Experiment(signal, "position", end, n_points=n_points, name="SetpointTable")


def SetpointProfile(time, position, name: str = "measured profile",
                    n_points: int | None = None) -> Experiment:
    """A measured position profile (e.g. a recorded reference), linear between samples;
    output on the profile's own samples up to 20001 points."""
    time = np.asarray(time, dtype=float)
    if time.ndim != 1 or time.size < 2:
        raise ExperimentError(f"{name}: need at least two samples, got {time.size}")
    signal = PiecewiseLinear(time, position)
    n = int(n_points) if n_points else int(min(time.size, 20001))
    return Experiment(signal, "position", float(time[-1]), float(time[0]), n, name)
