"""Analysis of runs and records: hysteresis features, friction-test analysis.

The features are computed by ``core.features`` (compiled, below the simulation, so the
batch engine runs them inside its loop); this package is where users find them."""

from pneumact.analysis.motion import SlidingMotion, sliding_motion
from pneumact.core.features import (
    FEATURE_UNITS,
    FEATURES,
    breakaway_pressure,
    hysteresis_summary,
    loop_area,
    loop_width_position,
    loop_width_pressure,
    loop_width_profile,
    max_error,
    motion_onset_pressure,
    presliding_travel,
    rms_error,
    sliding_speed,
    stroke,
)

__all__ = [
    "FEATURES",
    "FEATURE_UNITS",
    "SlidingMotion",
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
    "sliding_motion",
    "sliding_speed",
    "stroke",
]
