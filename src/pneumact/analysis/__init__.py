"""Analysis of runs and records: hysteresis features, friction-test analysis, and the
pneumatic half in numbers (choked limit, chamber time constant, natural frequencies).

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

from .pneumatics import (
    chamber_time_constant,
    chamber_volume,
    choked_limit,
    natural_frequencies,
)

__all__ = [
    "FEATURES",
    "FEATURE_UNITS",
    "SlidingMotion",
    "breakaway_pressure",
    "chamber_time_constant",
    "chamber_volume",
    "choked_limit",
    "hysteresis_summary",
    "loop_area",
    "loop_width_position",
    "loop_width_pressure",
    "loop_width_profile",
    "max_error",
    "motion_onset_pressure",
    "natural_frequencies",
    "presliding_travel",
    "rms_error",
    "sliding_motion",
    "sliding_speed",
    "stroke",
]
