"""One closed-loop run with its metrics, plot and report; and the classic set-ups.

``run_loop(loop, experiment)`` simulates, measures (``loop_metrics``) and returns a
``LoopStudy`` that writes ``signals.csv``, ``metrics.csv``, ``loop.png`` and a
self-contained ``report.html``. ``canudas_hunting()`` builds the hunting experiment of
Canudas de Wit et al. (1995) exactly as published.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from ..core.signals import Constant
from ..errors import ArgumentError
from ..experiments.actuator import Experiment
from ..io.report import NotebookDisplay
from ..models.controllers import PID
from ..progress import ProgressCallback
from .loop import ClosedLoop

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..parameters.files import ParameterSetLike
    from ..simulation.result import Result
    from .metrics import LoopMetrics

__all__ = ["TRACKING_METRICS", "LoopStudy", "canudas_hunting", "run_loop"]

#: the metrics of a tracked profile (a step's others need one step to mean anything)
TRACKING_METRICS = ("iae", "ise", "control_effort", "command_variation", "stick_time",
                    "stick_count", "mean_stick_duration", "stick_speed", "min_stick")


@dataclass(eq=False)
class LoopStudy(NotebookDisplay):
    """A closed-loop run: the loop, its experiment, the result and its metrics.

    ``to_pandas()``: the signals (``"metrics"``: the loop metrics, ``"controller"``: its
    settings); ``plot()``: set-point and position, command, friction and velocity;
    ``write(folder)``: signals.csv, metrics.csv, loop.png and report.html."""

    loop: ClosedLoop
    experiment: Experiment
    result: Result
    metrics: LoopMetrics
    title: str = "Closed-loop position control"
    #: a profile to follow, not a step: the step metrics (rise, settling, overshoot)
    #: mean nothing and are left out; the tracking error is given instead
    tracking: bool = False

    def _metrics_table(self) -> pd.DataFrame:
        """The metrics as a table (metric, value, unit, description): a step's all of
        them, a tracked profile's the error, effort and stick ones plus the RMS and
        largest tracking error."""
        frame = self.metrics.to_pandas()
        if not self.tracking:
            return frame
        import numpy as np

        error = (np.asarray(self.result["position_setpoint"])
                 - np.asarray(self.result["position"]))
        unit = self.metrics.position_unit
        extra = pd.DataFrame(
            [("rms_tracking_error", float(np.sqrt(np.mean(error ** 2))), unit,
              "RMS of set-point − position over the run"),
             ("max_tracking_error", float(np.max(np.abs(error))), unit,
              "largest |set-point − position|")], columns=frame.columns)
        keep = frame[frame["metric"].isin(TRACKING_METRICS)]
        return pd.concat([extra, keep], ignore_index=True)

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """The run's signals over time; ``name``: "metrics" (a step's metrics, or a
        tracked profile's error, effort and stick ones) or "controller"."""
        if name == "metrics":
            return self._metrics_table()
        if name == "controller":
            return self.controller_table()
        if name is not None:
            raise ArgumentError(f"to_pandas: name = {name!r}; allowed: metrics, controller")
        return self.result.to_pandas()

    def plot(self) -> Figure:
        """Set-point and position, command, friction and velocity, with the metrics."""
        from .plots import plot_loop

        return plot_loop(self.result, self.metrics)

    def controller_table(self) -> pd.DataFrame:
        """The controller's settings as the kernel reads them, and the loop's."""
        part = self.loop.parts()[-1]
        rows = [(name, float(part.settings[name])) for name in part.block.names
                if part.settings[name] != 0.0]
        return pd.DataFrame(rows, columns=["setting", "value"])

    def write(self, out_dir: str | os.PathLike, *, call: str = "") -> list[Path]:
        """signals.csv, metrics.csv, loop.png and report.html: all or nothing."""
        from ..io.display import display_frame
        from ..io.report import Report, figure_png
        from ..io.tables import write_files
        from ..plotting import PNG_DPI

        png = figure_png(self.plot(), dpi=PNG_DPI)
        metrics = self._metrics_table()
        report = Report(self.title, call=call, parameters=self.loop.params)
        report.text(f"Model: {self.loop.describe()}. Experiment: {self.experiment.name}, "
                    f"{self.experiment.t_start:g} to {self.experiment.t_end:g} s. "
                    f"Controller: {self.loop.controller!r}.")
        report.table(display_frame(metrics), "Loop metrics (mm or µm, kPa; metrics.csv "
                     "is SI)", index=False)
        report.image(png, "Set-point and position, command, friction and velocity")
        report.table(self.controller_table(), "Controller settings (SI, zeros omitted)",
                     index=False)

        def write_png(path: Path) -> None:
            path.write_bytes(png)

        return write_files(out_dir, {
            "signals.csv": lambda p: self.result.save(p),
            "metrics.csv": lambda p: metrics.to_csv(p, index=False),
            "loop.png": write_png,
            "report.html": report.write})


def run_loop(loop: ClosedLoop, experiment: Experiment, *, solver=None,
             progress: ProgressCallback | None = None, title: str | None = None,
             tracking: bool = False, y0: Mapping[str, float] | None = None,
             **metric_options) -> LoopStudy:
    """Simulate ``loop`` under the set-point ``experiment`` and measure it
    (``metric_options`` go to ``loop_metrics``); ``tracking``: the set-point is a profile
    to follow, not a step (no step metrics). ``y0``: states set at the start by name, as
    ``simulate``'s (a cylinder rests on a stop: ``{"position": x0}`` holds it at x0)."""
    from ..checks import check_bool, check_type

    check_type("loop", loop, ClosedLoop, where="run_loop", what="a control.ClosedLoop")
    check_bool("tracking", tracking, where="run_loop")
    from ..simulation import simulate
    from .metrics import loop_metrics

    result = simulate(loop, experiment, solver, progress=progress, y0=y0)
    metrics = loop_metrics(result, **metric_options)
    return LoopStudy(loop, experiment, result, metrics,
                     title or f"Closed-loop position control: {experiment.name}", tracking)


def canudas_hunting(params: ParameterSetLike = "canudas1995", *, kp: float = 3.0,
                    ki: float = 4.0, kv: float = 6.0, position_setpoint: float = 1.0,
                    t_end: float = 100.0, n_points: int = 10001,
                    sample_time: float | None = None) -> tuple[ClosedLoop, Experiment]:
    """The hunting experiment of Canudas de Wit et al. (1995, §4): a unit mass with
    LuGre friction (``canudas1995``) under u = −Kv·v − Kp·(x − xd) − Ki·∫(x − xd) dt,
    Kp = 3, Ki = 4, Kv = 6, xd = 1 m, from rest, 100 s. With Fs > Fc it hunts."""
    from ..models.friction import LuGre
    from ..models.rig import FrictionRig
    from ..parameters.files import as_parameter_set

    params = as_parameter_set(params, "canudas_hunting")
    rig = FrictionRig(params, LuGre(), drive="force")
    pid = PID(kp=kp, ki=ki, kd=kv, derivative="velocity", anti_windup="none",
              sample_time=sample_time)
    experiment = Experiment(Constant(position_setpoint), "position", t_end, n_points=n_points,
                            name="Canudas 1995 hunting")
    return ClosedLoop(rig, pid), experiment
