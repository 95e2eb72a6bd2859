"""What a bench record says about the actuator's forces (paper eqs. 9-13).

On a record of chamber pressure and position, the force balance of eq. 1 gives the
friction force F_f = (p_atm − p)·A_d − (F0 + k·x) − m·a, with velocity and acceleration
from a Savitzky-Golay filter (zero phase). Steady segments (constant velocity, so ż = 0
and eq. 12 holds) are found in the velocity itself, so any record with ramps will do.

No threshold here is tuned to one actuator: the differentiation window follows the
record's own noise and speed (``smoothing_window``), "moving" means faster than a few
times the velocity noise of that window, and a segment must outlast several windows and
travel beyond the presliding range the caller states. What remains are ratios
(``SMOOTHING_NOISE``, the ``keep`` fraction, ``max_variation``, ``max_drift``), each
explained where it is defined.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..errors import DataError
from ..io.records import PRESSURE_SIGNAL, Record
from .inputs import sensor_noise
from .smoothing import savgol_filter, savgol_weights

__all__ = ["Kinematics", "drive_force", "kinematics", "smoothing_window", "steady_segments",
           "typical_speed", "velocity_noise"]

#: The differentiation window is the shortest whose velocity noise is at most this
#: fraction of the record's typical speed: a 5 % noise averages to well below 1 % over
#: the hundreds of samples of a steady segment, and a longer window only blurs the
#: break-away transients the segments must exclude.
SMOOTHING_NOISE = 0.05
#: "Moving" means a velocity this many times its noise standard deviation (a false
#: detection of motion from noise alone is then a 5-sigma event).
MOVING_SIGMAS = 5.0
#: A steady segment lasts at least this many differentiation windows (so that its mean
#: velocity and force average independent noise, and its break-away transient, one
#: window long, is a small part of it).
SEGMENT_WINDOWS = 4
#: Shortest and longest differentiation windows, in samples (a cubic filter needs 7).
MIN_WINDOW_SAMPLES = 7


@dataclass(frozen=True)
class Kinematics:
    """Position (smoothed, and as measured), velocity and acceleration on a uniform grid
    (SI)."""

    time: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    pressure: np.ndarray
    measured_position: np.ndarray
    window: float


def _uniform(record: Record) -> Record:
    dt = np.diff(record.time)
    if np.ptp(dt) <= 1e-6 * np.mean(dt):
        return record
    return record.resample(float(np.median(dt)))


def velocity_noise(samples: int, dt: float, position_noise: float) -> float:
    """Standard deviation of the cubic Savitzky-Golay velocity over ``samples`` points
    when the position carries white noise of ``position_noise``."""
    coefficients = savgol_weights(samples, 3, deriv=1, delta=dt)
    return float(position_noise * np.linalg.norm(coefficients))


def _window_samples(n_samples: int, dt: float, position_noise: float, speed: float) -> int:
    """Smallest odd window whose velocity noise is ``SMOOTHING_NOISE`` × ``speed``."""
    largest = max(MIN_WINDOW_SAMPLES, (n_samples // 4) | 1)
    n = MIN_WINDOW_SAMPLES
    while n < largest and velocity_noise(n, dt, position_noise) > SMOOTHING_NOISE * speed:
        n = min(largest, int(n * 1.25) | 1)
    return n


def typical_speed(record: Record) -> float:
    """The record's typical speed [m/s]: the median |v| of the samples that move, over a
    differentiation window of a fiftieth of the record (0 if nothing moves)."""
    rec = _uniform(record)
    dt = float(rec.time[1] - rec.time[0])
    x = rec["position"]
    sigma = max(sensor_noise(x), 1e-12 * max(np.ptp(x), 1e-3))
    coarse = max(MIN_WINDOW_SAMPLES, (len(rec) // 50) | 1)
    if coarse >= len(rec):
        raise DataError(f"{record.source}: {len(rec)} samples are too few to differentiate")
    v = np.abs(savgol_filter(x, coarse, 3, deriv=1, delta=dt))
    moving = v[v > MOVING_SIGMAS * velocity_noise(coarse, dt, sigma)]
    return float(np.median(moving)) if moving.size else 0.0


def smoothing_window(record: Record, speed: float | None = None) -> float:
    """Differentiation window [s] for ``record``: the shortest whose velocity noise is
    ``SMOOTHING_NOISE`` of ``speed`` (default: the record's typical speed, the median
    |v| of the samples that move, over a window of a fiftieth of the record), from the
    position noise the record itself shows (``inputs.sensor_noise``)."""
    rec = _uniform(record)
    dt = float(rec.time[1] - rec.time[0])
    x = rec["position"]
    sigma = max(sensor_noise(x), 1e-12 * max(np.ptp(x), 1e-3))
    if speed is None:
        speed = typical_speed(rec)
    if not speed > 0:
        return MIN_WINDOW_SAMPLES * dt
    return _window_samples(len(rec), dt, sigma, speed) * dt


def kinematics(record: Record, window: float | None = None) -> Kinematics:
    """Smoothed velocity and acceleration of ``record`` (Savitzky-Golay, cubic, over
    ``window`` seconds; default ``smoothing_window(record)``; the record is resampled
    to its median step if not uniform)."""
    record.require([PRESSURE_SIGNAL, "position"], "the force balance")
    rec = _uniform(record)
    dt = float(rec.time[1] - rec.time[0])
    window = smoothing_window(rec) if window is None else window
    n = max(MIN_WINDOW_SAMPLES, round(window / dt) | 1)
    if n >= len(rec):
        raise DataError(f"{record.source}: {len(rec)} samples are too few for a {window} s "
                        "differentiation window")
    x = rec["position"]
    v = savgol_filter(x, n, 3, deriv=1, delta=dt)
    a = savgol_filter(x, n, 3, deriv=2, delta=dt)
    return Kinematics(rec.time, savgol_filter(x, n, 3), v, a, rec[PRESSURE_SIGNAL], x,
                      n * dt)


def drive_force(pressure: np.ndarray, params) -> np.ndarray:
    """Force of the pressure difference on the diaphragm, (p_atm − p)·A_d [N]."""
    return (params["p_atm"] - pressure) * params["A_d"]


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) index pairs of the True runs of ``mask``."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return list(zip(edges[::2], edges[1::2], strict=True))


def moving_threshold(kin: Kinematics, record: Record) -> float:
    """Speed [m/s] above which the record clearly moves: ``MOVING_SIGMAS`` × the
    velocity noise of the differentiation window."""
    dt = float(kin.time[1] - kin.time[0])
    n = max(MIN_WINDOW_SAMPLES, round(kin.window / dt) | 1)
    sigma = sensor_noise(record["position"])
    return MOVING_SIGMAS * velocity_noise(n, dt, sigma)


def steady_segments(record: Record, params, *, presliding_range: float = 0.0,
                    keep: tuple[float, float] = (0.4, 0.9), max_variation: float = 0.25,
                    max_drift: float = 0.03) -> pd.DataFrame:
    """Segments of steady sliding and their mean velocity and friction force.

    A segment is a run of one velocity sign faster than ``moving_threshold`` lasting at
    least ``SEGMENT_WINDOWS`` differentiation windows (``smoothing_window``); of it the
    fraction ``keep`` (in time) is used, after the break-away transient, and kept only if
    std(v)/|mean v| < ``max_variation`` (a quarter: stick-slip swings the velocity by
    its whole size). The friction is the force balance with F0, k, m and A_d from
    ``params``; the velocity is the slope of a straight line through the positions
    (robust to sensor noise). A segment must also travel more than
    ``presliding_range`` (a bristle's deflection before gross sliding, about 3·Fs/σ0:
    slower creep before break-away is not sliding), its friction must oppose the
    motion, and the slopes of its two halves must agree within ``max_drift`` (3 %: a
    segment still accelerating after a reversal is not steady).
    """
    kin = kinematics(record)
    fast = kinematics(record, max(kin.window / 10, 0.0)).velocity  # follows the ringing
    min_speed = moving_threshold(kin, record)
    min_duration = SEGMENT_WINDOWS * kin.window
    # the measured position: a smoothed one is biased where the motion accelerates, and
    # the noise averages out over a segment anyway
    force = drive_force(kin.pressure, params) - params["F0"] - \
        params["k"] * kin.measured_position
    moving = np.abs(kin.velocity) > min_speed
    rows = []
    for sign in (1, -1):
        for i0, i1 in _runs(moving & (np.sign(kin.velocity) == sign)):
            t0, t1 = kin.time[i0], kin.time[i1 - 1]
            if t1 - t0 < min_duration:
                continue
            sel = (kin.time >= t0 + keep[0] * (t1 - t0)) & (kin.time <= t0 + keep[1] * (t1 - t0))
            if np.count_nonzero(sel) < 10:
                continue
            v = kin.velocity[sel]
            if np.std(v) > max_variation * abs(np.mean(v)):
                continue
            slope = np.polyfit(kin.time[sel], kin.position[sel], 1)[0]
            if slope * sign < 2 * min_speed:
                continue  # a creep or a reversal transient, not steady sliding
            if abs(slope) * (kin.time[sel][-1] - kin.time[sel][0]) <= presliding_range:
                continue  # presliding creep before break-away
            idx = np.flatnonzero(sel)
            halves = np.array_split(idx, 2)
            v1, v2 = (np.polyfit(kin.time[h], kin.measured_position[h], 1)[0] for h in halves)
            if abs(v2 - v1) > max_drift * abs(slope):
                continue  # still accelerating
            i_first, i_last = np.flatnonzero(sel)[[0, -1]]
            duration = kin.time[i_last] - kin.time[i_first]
            inertia = params["m"] * (fast[i_last] - fast[i_first]) / duration  # mean m·a
            f = force[sel] - inertia
            if np.mean(f) * sign <= 0:
                continue  # friction that does not oppose the motion: a transient
            rows.append({"record": os.path.basename(record.source),
                         "t_start": kin.time[sel][0],
                         "t_end": kin.time[sel][-1], "velocity": slope,
                         "friction": float(np.mean(f)), "samples": int(sel.sum()),
                         "position": float(np.mean(kin.position[sel]))})
    return pd.DataFrame(rows, columns=["record", "t_start", "t_end", "velocity", "friction",
                                       "samples", "position"])
