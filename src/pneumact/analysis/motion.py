"""How a run slides: steadily, or in stick-slip (stops and jumps) within its stroke."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["STICK_FRACTION", "SlidingMotion", "sliding_motion"]

#: a sample "stops" below this fraction of the fastest speed in the sliding window
STICK_FRACTION = 0.05
#: this many stops (in the window, both directions together) make a run stick-slip
MIN_STOPS = 3
#: the sliding window: 20-80 % of the travel, as ``sliding_speed``
WINDOW = (0.2, 0.8)


@dataclass(frozen=True)
class SlidingMotion:
    """The speeds [m/s] while the run crosses 20-80 % of its travel, the number of stops
    there, and whether that is stick-slip (at least ``MIN_STOPS`` stops)."""

    min_speed: float
    max_speed: float
    stops: int

    @property
    def stick_slip(self) -> bool:
        return self.stops >= MIN_STOPS


def sliding_motion(position, velocity) -> SlidingMotion:
    """``SlidingMotion`` of a run from its position [m] and velocity [m/s] samples."""
    x = np.asarray(position, dtype=float)
    v = np.abs(np.asarray(velocity, dtype=float))
    travel = float(np.ptp(x)) if x.size else 0.0
    if x.size < 3 or not travel > 0.0:
        return SlidingMotion(np.nan, np.nan, 0)
    low, high = (float(x.min()) + f * travel for f in WINDOW)
    inside = (x > low) & (x < high)
    if not inside.any():
        return SlidingMotion(np.nan, np.nan, 0)
    fastest = float(v[inside].max())
    stopped = inside & (v < STICK_FRACTION * fastest)
    stops = int(np.count_nonzero(stopped[1:] & ~stopped[:-1]) + stopped[0])
    return SlidingMotion(float(v[inside].min()), fastest, stops)
