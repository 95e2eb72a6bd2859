"""Simulation results: one object with named, unit-tagged signals and what made them."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.c_engine import Kernel
from ..io.report import ResultVocabulary, table_writer

if TYPE_CHECKING:
    import os

    import pandas as pd
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class SolverStats:
    """The integrator's report of one run, read from its info array by name."""

    status: int
    reason: str
    t: float
    steps: int
    rejected: int
    rhs_evaluations: int
    jacobian_evaluations: int
    last_step: float

    @property
    def ok(self) -> bool:
        return self.status == 0

    @classmethod
    def from_info(cls, kernel: Kernel, info: np.ndarray) -> SolverStats:
        status = int(info[kernel.INFO_STATUS])
        return cls(status=status,
                   reason="ok" if status == 0 else kernel.STATUS_TEXT.get(status, "unknown"),
                   t=float(info[kernel.INFO_T]), steps=int(info[kernel.INFO_STEPS]),
                   rejected=int(info[kernel.INFO_REJECTED]),
                   rhs_evaluations=int(info[kernel.INFO_RHS]),
                   jacobian_evaluations=int(info[kernel.INFO_JAC]),
                   last_step=float(info[kernel.INFO_H]))


@dataclass(eq=False)
class Result(ResultVocabulary):
    """Signals of one simulation on a common time grid, in SI units.

    ``result["position"]`` gives an array; ``result.units["position"]`` its unit.
    ``to_pandas()`` gives a DataFrame indexed by time (units in ``attrs["units"]``);
    ``plot()`` the time series; ``write(folder)`` signals.csv, parameters.csv,
    signals.png and report.html; ``save(path)`` the signals alone, as one CSV or
    Parquet file (the file-level saver, like ``Record.save``).
    ``parameters`` holds every parameter value the run used (SI), ``components`` the
    model's components (friction law, valve, ...), ``meta`` the solver's report.
    """

    time: np.ndarray
    signals: dict[str, np.ndarray]
    units: dict[str, str]
    meta: dict = field(default_factory=dict)
    parameters: dict[str, float] = field(default_factory=dict)
    components: dict[str, str] = field(default_factory=dict)

    @classmethod
    def from_run(cls, prep, experiment, solver, y_out, out, stats: SolverStats,
                 wall: float) -> Result:
        assembly = prep.assembly
        signals: dict[str, np.ndarray] = {}
        units: dict[str, str] = {}
        for i, (name, unit) in enumerate(zip(assembly.state_names, assembly.state_units,
                                             strict=True)):
            signals[name] = np.ascontiguousarray(y_out[:, i])
            units[name] = unit
        for i, (name, unit) in enumerate(zip(assembly.output_names, assembly.output_units,
                                             strict=True)):
            if name == "drive":
                name, unit = f"drive_{experiment.quantity}", experiment.unit
            if name in signals:
                continue
            signals[name] = np.ascontiguousarray(out[:, i])
            units[name] = unit
        params = assembly.model.params
        meta = {
            "model": assembly.describe(),
            "params": getattr(params, "name", "custom"),
            "experiment": experiment.name,
            "solver": f"{type(solver).__name__}(rtol={solver.rtol})",
            "engine": getattr(prep.kernel, "engine", "numba"),
            "steps": stats.steps,
            "rejected": stats.rejected,
            "rhs_evaluations": stats.rhs_evaluations,
            "jacobian_evaluations": stats.jacobian_evaluations,
            "wall_time_s": wall,
            "summary": assembly.model.summary_kind,
        }
        components = {part.name: part.label for part in assembly.parts if part.label}
        return cls(np.asarray(prep.t_out, dtype=float).copy(), signals, units, meta,
                   assembly.values(prep.vector), components)

    # -- access ------------------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        if name == "time":
            return self.time
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; signals: {', '.join(self.signals)}") from None

    def __contains__(self, name: object) -> bool:
        return name == "time" or name in self.signals

    @property
    def names(self) -> list[str]:
        return list(self.signals)

    report_title = "Simulation"
    figure_name = "signals"

    def tables(self) -> dict[str, pd.DataFrame]:
        import pandas as pd

        return {"signals": self.to_pandas(),
                "parameters": pd.DataFrame({"value": self.parameters}).rename_axis("name")}

    def report_text(self) -> str:
        meta = self.meta
        return (f"Model {meta.get('model', '?')} with parameters {meta.get('params', '?')} "
                f"under {meta.get('experiment', '?')}; {meta.get('solver', '')}, "
                f"{meta.get('steps', '?')} steps. Components: "
                f"{', '.join(f'{k} {v}' for k, v in self.components.items())}.")

    def to_pandas(self, name: str | None = None):
        """A DataFrame indexed by time; units, parameters and components in ``attrs``
        (``name="parameters"``: the parameter values the run used)."""
        import pandas as pd

        if name is not None:
            return super().to_pandas(name)
        frame = pd.DataFrame(self.signals, index=pd.Index(self.time, name="time"))
        frame.attrs["units"] = {"time": "s", **self.units}
        frame.attrs["parameters"] = dict(self.parameters)
        frame.attrs["components"] = dict(self.components)
        return frame

    def save(self, path: str | Path) -> Path:
        """Write all signals to CSV (header ``name [unit]``) or Parquet, atomically."""
        from ..io.tables import write_columns

        return write_columns({"time": self.time, **self.signals}, path,
                             {"time": "s", **self.units})

    # -- analysis and plots --------------------------------------------------------------
    def summary(self) -> dict[str, float]:
        """The features the model names (its ``summary_kind``), SI: an actuator's stroke,
        loop widths and break-away pressure (see ``pneumact.analysis``); a cylinder's or
        a rig's motion (``motion_summary``)."""
        kind = self.meta.get("summary", "hysteresis")  # a result made before the kinds
        return SUMMARIES[kind](self)

    def write(self, out_dir: str | os.PathLike[str], *, call: str = "") -> list[Path]:
        """signals.csv (header ``name [unit]``), parameters.csv, signals.png and
        report.html in ``out_dir``, all or nothing."""
        from ..io.report import figure_png
        from ..io.tables import write_files

        png = figure_png(self.plot())
        return write_files(out_dir, {
            "signals.csv": self.save,
            "parameters.csv": table_writer(self.to_pandas("parameters")),
            f"{self.figure_name}.png": lambda p: Path(p).write_bytes(png),
            "report.html": self.report(call, png).write})

    def plot_hysteresis(self, ax=None, **kwargs) -> Figure:
        """Pressure [kPa] against position [mm], like the paper's Figs. 5-6 (on ``ax``
        when given); returns the Figure."""
        from ..plotting import plot_hysteresis

        return plot_hysteresis(self, ax=ax, **kwargs)

    def plot(self, signals=None, axes=None) -> Figure:
        """Time series of the chosen signals, one panel each, in display units."""
        from ..plotting import plot_time_series

        return plot_time_series(self, signals=signals, axes=axes)

    def notebook_table(self):
        """Each signal's first, smallest, largest and last value (a notebook's display)."""
        from ..io.display import signal_summary

        return signal_summary(self.signals, self.units)

    def __repr__(self) -> str:
        return (f"Result({len(self.time)} samples over {self.time[0]:g}..{self.time[-1]:g} s, "
                f"signals={self.names})")


def hysteresis_features(result: Result) -> dict[str, float]:
    """Stroke, loop widths and break-away pressure of a pressure-position record."""
    from ..core.features import hysteresis_summary
    from ..models.actuator import CHAMBER_PRESSURE

    return hysteresis_summary(result.time, result[CHAMBER_PRESSURE], result["position"])


def motion_summary(result: Result) -> dict[str, float]:
    """A move from the first position to the last, SI: ``start_position``,
    ``final_position``, ``travel`` (final − start), ``overshoot`` (the farthest the
    position went past the final one in the direction of travel, ≥ 0; past the start's
    side when there is no travel), ``position_range`` (max − min), ``top_speed_out`` and
    ``top_speed_in`` (the largest velocity towards larger and smaller x, ≥ 0)."""
    x, v = result["position"], result["velocity"]
    start, final = float(x[0]), float(x[-1])
    travel = final - start
    direction = 1.0 if travel >= 0.0 else -1.0
    return {"start_position": start, "final_position": final, "travel": travel,
            "overshoot": max(0.0, float(np.max(direction * (x - final)))),
            "position_range": float(np.ptp(x)),
            "top_speed_out": max(0.0, float(np.max(v))),
            "top_speed_in": max(0.0, float(-np.min(v)))}


#: a model's ``summary_kind`` -> what ``Result.summary()`` computes
SUMMARIES = {"hysteresis": hysteresis_features, "motion": motion_summary}
