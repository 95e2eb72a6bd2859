"""Simulation results: one object with named, unit-tagged signals."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd


@dataclass(eq=False)
class Result:
    """Signals of one simulation on a common time grid, in SI units.

    ``result["position"]`` gives an array; ``result.units["position"]`` its unit.
    ``to_pandas()`` gives a DataFrame indexed by time (units in ``attrs["units"]``).
    """

    time: np.ndarray
    signals: dict[str, np.ndarray]
    units: dict[str, str]
    meta: dict = field(default_factory=dict)

    @classmethod
    def from_kernel(cls, kernel, model, experiment, solver, t_out, y_out, out, info, wall):
        signals: dict[str, np.ndarray] = {}
        units: dict[str, str] = {}
        for i, (name, unit) in enumerate(zip(kernel.STATE_NAMES, kernel.STATE_UNITS,
                                             strict=True)):
            signals[name] = y_out[:, i].copy()
            units[name] = unit
        for i, (name, unit) in enumerate(zip(kernel.OUTPUT_NAMES, kernel.OUTPUT_UNITS,
                                             strict=True)):
            if name == "drive":
                name, unit = f"drive_{experiment.quantity}", experiment.unit
            if name in signals:
                continue
            signals[name] = out[:, i].copy()
            units[name] = unit
        params = model.params
        meta = {
            "model": model.describe() if hasattr(model, "describe") else repr(model),
            "params": getattr(params, "name", "custom"),
            "experiment": experiment.name,
            "solver": f"{type(solver).__name__}(rtol={solver.rtol})",
            "steps": int(info[2]),
            "rejected": int(info[3]),
            "rhs_evaluations": int(info[4]),
            "jacobian_evaluations": int(info[5]),
            "wall_time_s": wall,
        }
        return cls(np.asarray(t_out, dtype=float).copy(), signals, units, meta)

    # -- access ------------------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; signals: {', '.join(self.signals)}") from None

    @property
    def names(self) -> list[str]:
        return list(self.signals)

    def to_pandas(self) -> pd.DataFrame:
        frame = pd.DataFrame(self.signals, index=pd.Index(self.time, name="time"))
        frame.attrs["units"] = {"time": "s", **self.units}
        return frame

    def save(self, path: str | Path) -> Path:
        """Write all signals to CSV (header ``name [unit]``) or Parquet, atomically."""
        from ..io import write_table

        return write_table(self.to_pandas(), path, {"time": "s", **self.units})

    # -- analysis and plots --------------------------------------------------------------
    def summary(self) -> dict[str, float]:
        """Stroke, loop widths and break-away pressure (see ``pneumact.features``)."""
        from ..features import hysteresis_summary

        return hysteresis_summary(self.time, self["pressure"], self["position"])

    def plot_hysteresis(self, ax=None, **kwargs):
        """Pressure [kPa] against position [mm], like the paper's Figs. 5-6."""
        from ..plotting import plot_hysteresis

        return plot_hysteresis(self, ax=ax, **kwargs)

    def plot(self, signals=None, axes=None):
        """Time series of the chosen signals, one panel each, in display units."""
        from ..plotting import plot_time_series

        return plot_time_series(self, signals=signals, axes=axes)

    def __repr__(self) -> str:
        return (f"Result({len(self.time)} samples over {self.time[0]:g}..{self.time[-1]:g} s, "
                f"signals={self.names})")
