"""Validation of identified friction laws on real force records.

``validate_friction``: a law identified on one record (``inverse_friction``) predicts the
force of others (the EMPS drive: identified on ``DATA_EMPS.mat``, predicting
``DATA_EMPS_PULSES.mat``). ``friction_across_levels``: laws identified at some operating
levels (the TU Delft cylinder's supply pressures) are interpolated linearly in the level
and predict the friction at the other levels.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ArgumentError, DataError
from ..io.records import Record
from ..io.report import NotebookDisplay
from ..plotting import tight_layout
from .metrics import METRIC_NAMES, error_metrics

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["FrictionValidation", "friction_across_levels", "validate_friction"]


@dataclass(eq=False)
class FrictionValidation(NotebookDisplay):
    """Predicted against measured force per record (``predictions[name]``: time,
    velocity, measured, predicted, SI) and the parameters each prediction used.

    ``to_pandas()``: the predictions, long (``"metrics"``, ``"parameters"``: the
    others); ``plot()``: measured and predicted force; ``write(folder)``: the tables,
    force.png and report.html."""

    model: str
    identified_on: list[str]
    predictions: dict[str, pd.DataFrame]
    parameters: pd.DataFrame
    role: dict[str, str] = field(default_factory=dict)

    def metrics(self) -> pd.DataFrame:
        """Per record: role (identification or validation), the error metrics of the
        force and the relative force error ‖F − F̂‖/‖F‖."""
        rows = []
        for name, frame in self.predictions.items():
            measured, predicted = frame["measured"], frame["predicted"]
            rows.append({"record": name, "role": self.role.get(name, "validation"),
                         **error_metrics(measured, predicted, f"{name}: force"),
                         "relative_force_error": float(
                             np.linalg.norm(measured - predicted) / np.linalg.norm(measured))})
        return pd.DataFrame(rows, columns=["record", "role", *METRIC_NAMES,
                                           "relative_force_error"])

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """record, time, velocity, measured, predicted (SI); ``name``: "metrics" or
        "parameters" for those tables."""
        if name == "metrics":
            return self.metrics()
        if name == "parameters":
            return self.parameters
        if name is not None:
            raise ArgumentError(f"to_pandas: name = {name!r}; allowed: metrics, parameters")
        return pd.concat([frame.assign(record=record)[["record", *frame.columns]]
                          for record, frame in self.predictions.items()], ignore_index=True)

    def plot(self, page: int = 0) -> Figure:
        """Per record: measured and predicted force against time, and against velocity;
        every record (``page`` 0) or the ``page``-th page of ``PANELS_PER_PAGE`` records
        (from 1)."""
        from ..plotting import panel_grid, record_pages

        shown = list(self.predictions.items())
        if page:
            shown = record_pages(shown)[page - 1]
        fig, panels = panel_grid(len(shown), rows_per=2, height=3.1)
        for (ax_time, ax_vel), (name, d) in zip(panels, shown, strict=True):
            ax_time.plot(d["time"], d["measured"], "k-", lw=0.6, label="measured")
            ax_time.plot(d["time"], d["predicted"], "C0-", lw=0.8, label="model")
            ax_time.set_xlabel("time [s]")
            ax_time.set_ylabel("force [N]")
            ax_time.set_title(f"{name} ({self.role.get(name, 'validation')})", fontsize=9)
            velocity, predicted = d["velocity"].to_numpy(), d["predicted"].to_numpy()
            ax_vel.plot(velocity * 1e3, d["measured"], "k.", ms=1)
            for branch in (velocity < 0, velocity > 0):  # the Coulomb step: not drawn
                order = np.argsort(velocity[branch])    # through v = 0
                ax_vel.plot(velocity[branch][order] * 1e3, predicted[branch][order], "C0-",
                            lw=1)
            ax_vel.set_xlabel("velocity [mm/s]")
            ax_vel.set_ylabel("force [N]")
            for ax in (ax_time, ax_vel):
                ax.grid(True, alpha=0.3)
        panels[0][0].legend(fontsize=8)
        tight_layout(fig)
        return fig

    def write(self, out_dir: str | os.PathLike, *, call: str = "", title: str = "") -> list[Path]:
        """predictions.csv, metrics.csv, parameters.csv, force.png and report.html, all
        or nothing."""
        from ..io.report import Report
        from ..io.tables import write_files
        from ..plotting import figure_writer, page_name, record_pages

        report = Report(title or f"Friction ({self.model}) against measured force",
                        call=call)
        report.text(f"Identified on: {', '.join(self.identified_on)}; the other records "
                    "are predicted, never fitted. NRMSE = ‖F − F̂‖/‖F − F̄‖, fit % = "
                    "100·(1 − NRMSE); relative force error = ‖F − F̂‖/‖F‖.")
        report.table(self.metrics(), "Force error per record", index=False)
        report.table(self.parameters, "Parameters of each prediction (SI)")
        pages = len(record_pages(list(self.predictions)))
        for k in range(1, pages + 1):
            report.figure(self.plot(page=k), "Measured and predicted force"
                          + (f" (page {k} of {pages})" if pages > 1 else ""))
        return write_files(out_dir, {
            "predictions.csv": lambda p: self.to_pandas().to_csv(p, index=False),
            "metrics.csv": lambda p: self.metrics().to_csv(p, index=False),
            "parameters.csv": lambda p: self.parameters.to_csv(p),
            **{f"{page_name('force', k)}.png": figure_writer(
                functools.partial(self.plot, page=k)) for k in range(1, pages + 1)},
            "report.html": report.write})


def _name(record: Record, i: int) -> str:
    return os.path.basename(record.source) or f"record {i + 1}"


def validate_friction(result, records: Record | Sequence[Record]) -> FrictionValidation:
    """The identified law ``result`` (``inverse_friction``) on its own data and on
    ``records``."""
    records = [records] if isinstance(records, Record) else list(records)
    identified = result.data.rename(columns={"force": "measured"})
    source = result.options.get("source") or "identification record"
    predictions = {source: identified[["time", "velocity", "measured", "predicted"]]}
    for i, record in enumerate(records):
        predictions[_name(record, i)] = result.prediction(record)
    values = pd.DataFrame({name: result.estimates.as_dict() for name in predictions}).T
    return FrictionValidation(result.model, [source], predictions, values,
                              {source: "identification"})


def friction_across_levels(records: Mapping[float, Record], train: Sequence[float],
                           model: str = "coulomb-viscous", **options) -> FrictionValidation:
    """Identify ``model`` at each ``train`` level (``inverse_friction`` ``options``),
    interpolate each parameter linearly in the level (least squares over the training
    levels; constant with one) and predict the friction at every level."""
    from ..identification import inverse_friction

    levels = sorted(records)
    train = sorted(set(train))
    unknown = [t for t in train if t not in records]
    if unknown or not train or len(train) == len(levels):
        raise DataError(f"friction_across_levels: training levels {train} must be some, not "
                        f"all, of the records' levels {levels}")
    fitted = {level: inverse_friction(records[level], model, **options) for level in train}
    names = list(fitted[train[0]].estimates.names)
    table = pd.DataFrame([fitted[lv].estimates.as_dict() for lv in train], index=train)[names]
    degree = 1 if len(train) > 1 else 0
    coefficients = {n: np.polyfit(train, table[n].to_numpy(), degree) for n in names}
    predictions, used, role = {}, {}, {}
    for level in levels:
        values = {n: float(np.polyval(c, level)) for n, c in coefficients.items()}
        name = f"{level:g} ({_name(records[level], 0)})"
        predictions[name] = fitted[train[0]].prediction(records[level], values)
        used[name] = values
        role[name] = "identification" if level in train else "validation"
    return FrictionValidation(model, [f"{lv:g}" for lv in train], predictions,
                              pd.DataFrame(used).T, role)
