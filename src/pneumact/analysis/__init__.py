"""Analysis of runs and records: hysteresis features, friction-test analysis."""

from pneumact.analysis.features import (
    FEATURE_UNITS,
    FEATURES,
    breakaway_pressure,
    hysteresis_summary,
    loop_area,
    loop_width_position,
    loop_width_pressure,
    max_error,
    rms_error,
    stroke,
)

__all__ = [
    "FEATURES",
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
