"""Hysteresis-loop measures on a measured or simulated record, and their comparison.

The measures actuator engineers quote: the loop width in pressure (at equal position)
and in position (at equal pressure) over the middle of the stroke, the enclosed area, the
break-away pressure (``core.features``, the same compiled code the batch engine
runs), and the reversal points of the pressure with the position there.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..core.features import FEATURE_UNITS, hysteresis_summary, turning_points
from ..io.records import PRESSURE_SIGNAL

__all__ = ["LOOP_MEASURES", "compare_loops", "loop_measures", "reversals"]

LOOP_MEASURES = ("stroke", "loop_width_pressure", "loop_width_position", "loop_area",
                 "breakaway_pressure")


def _writeable(*signals) -> list[np.ndarray]:
    """Writeable float copies of ``signals``: a Record's signals are read-only, and numba
    compiles the features once more for each mix of read-only and writeable arguments
    (measured, predicted, both: three times each)."""
    return [np.array(a, dtype=float, order="C") for a in signals]


def reversals(time, pressure, position) -> pd.DataFrame:
    """The pressure's reversal points (turning points beyond 10 % of its range): time,
    pressure, position, and whether the pressure turned at a minimum or a maximum."""
    t, p, x = _writeable(time, pressure, position)
    cuts = turning_points(t, p, x)
    turns = cuts[1:-1]
    kind = ["minimum" if p[cuts[j]] < p[cuts[j - 1]] else "maximum"
            for j in range(1, cuts.size - 1)]
    return pd.DataFrame({"time": t[turns], PRESSURE_SIGNAL: p[turns], "position": x[turns],
                         "turn": kind})


def loop_measures(time, pressure, position) -> dict[str, float]:
    """The loop measures of one record (SI; units in ``FEATURE_UNITS``)."""
    summary = hysteresis_summary(*_writeable(time, pressure, position))
    return {name: summary[name] for name in LOOP_MEASURES}


def compare_loops(measured: dict[str, float], model: dict[str, float]) -> pd.DataFrame:
    """Measured and model loop measures side by side, with the difference (model −
    measured) and the relative difference."""
    rows = []
    for name in LOOP_MEASURES:
        m, s = measured.get(name, np.nan), model.get(name, np.nan)
        rows.append({"measure": name, "unit": FEATURE_UNITS[name], "measured": m,
                     "model": s, "difference": s - m,
                     "relative": (s - m) / abs(m) if m not in (0.0,) and np.isfinite(m)
                     else np.nan})
    return pd.DataFrame(rows)
