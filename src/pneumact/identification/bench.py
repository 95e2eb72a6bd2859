"""What a bench record says about the actuator's forces (paper eqs. 9-13).

On a record of chamber pressure and position, the force balance of eq. 1 gives the
friction force F_f = (p_atm − p)·A_d − (F0 + k·x) − m·a, with velocity and acceleration
from a Savitzky-Golay filter (zero phase). Steady segments (constant velocity, so ż = 0
and eq. 12 holds) are found in the velocity itself, so any record with ramps will do.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.signal import savgol_filter

from ..errors import DataError
from ..io.records import Record

__all__ = ["Kinematics", "drive_force", "kinematics", "steady_segments"]


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


def _uniform(record: Record) -> Record:
    dt = np.diff(record.time)
    if np.ptp(dt) <= 1e-6 * np.mean(dt):
        return record
    return record.resample(float(np.median(dt)))


def kinematics(record: Record, window: float = 0.02) -> Kinematics:
    """Smoothed velocity and acceleration of ``record`` (Savitzky-Golay, cubic, over
    ``window`` seconds; the record is resampled to its median step if not uniform)."""
    record.require(["pressure", "position"], "the force balance")
    rec = _uniform(record)
    dt = float(rec.time[1] - rec.time[0])
    n = max(7, round(window / dt) | 1)
    if n >= len(rec):
        raise DataError(f"{record.source}: {len(rec)} samples are too few for a {window} s "
                        "differentiation window")
    x = rec["position"]
    v = savgol_filter(x, n, 3, deriv=1, delta=dt)
    a = savgol_filter(x, n, 3, deriv=2, delta=dt)
    return Kinematics(rec.time, savgol_filter(x, n, 3), v, a, rec["pressure"], x)


def drive_force(pressure: np.ndarray, params) -> np.ndarray:
    """Force of the pressure difference on the diaphragm, (p_atm − p)·A_d [N]."""
    return (params["p_atm"] - pressure) * params["A_d"]


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) index pairs of the True runs of ``mask``."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    return list(zip(edges[::2], edges[1::2], strict=True))


def steady_segments(record: Record, params, *, min_speed: float = 2e-5,
                    min_duration: float = 0.2, keep: tuple[float, float] = (0.4, 0.9),
                    max_variation: float = 0.25, window: float = 0.1,
                    min_travel: float = 50e-6, max_drift: float = 0.03) -> pd.DataFrame:
    """Segments of steady sliding and their mean velocity and friction force.

    A segment is a run of one velocity sign with |v| > ``min_speed`` lasting at least
    ``min_duration``; of it the fraction ``keep`` (in time) is used, after the
    break-away transient, and kept only if std(v)/|mean v| < ``max_variation``. The
    friction is the force balance with F0, k, m and A_d from ``params``; the velocity
    is the slope of a straight line through the positions (robust to sensor noise).
    A segment must also travel at least ``min_travel`` (beyond the bristles' presliding
    range Fs/σ0, some tens of µm: slower creep before break-away is not sliding), its
    friction must oppose the motion, and the slopes of its two halves must agree within
    ``max_drift`` (relative): a segment still accelerating after a reversal is not steady.
    """
    kin = kinematics(record, window)
    fast = kinematics(record, 0.01).velocity  # follows the mechanics' ringing
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
            if abs(slope) * (kin.time[sel][-1] - kin.time[sel][0]) < min_travel:
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
            rows.append({"record": record.source, "t_start": kin.time[sel][0],
                         "t_end": kin.time[sel][-1], "velocity": slope,
                         "friction": float(np.mean(f)), "samples": int(sel.sum()),
                         "position": float(np.mean(kin.position[sel]))})
    return pd.DataFrame(rows, columns=["record", "t_start", "t_end", "velocity", "friction",
                                       "samples", "position"])
