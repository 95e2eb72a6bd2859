"""Figures and report sections of a validation (display units: kPa, mm, N)."""

from __future__ import annotations

import numpy as np

from ..io.display import display_frame, display_unit
from ..io.records import PRESSURE_SIGNAL
from ..models.actuator import CHAMBER_PRESSURE
from ..plotting import DISPLAY_UNITS, page_names, panel_grid, tight_layout
from .metrics import metrics_for_reading

__all__ = ["add_to_report", "plot_loops", "plot_residuals", "plot_time"]


def _display(rv, signal: str, values=()) -> tuple[str, float]:
    """(unit shown, factor) of ``signal``: µm for residuals of some micrometres."""
    si = rv.record.units.get(signal, "")
    return display_unit(si, values) if si else DISPLAY_UNITS.get(si, ("", 1.0))


def plot_loops(validation, records=None):
    """Measured (black dashed) and predicted pressure–position loops, one panel per
    record with pressure and position (of ``records``, default all: a page of them)."""
    records = [rv for rv in (validation.records if records is None else records)
               if rv.has_loop]
    fig, panels = panel_grid(len(records))
    for (ax,), rv in zip(panels, records, strict=True):
        ax.plot(rv.record[PRESSURE_SIGNAL] * 1e-3, rv.record["position"] * 1e3, "k--", lw=1,
                label="measured")
        ax.plot(rv.predicted(CHAMBER_PRESSURE) * 1e-3, rv.predicted("position") * 1e3, "C0-",
                lw=1.2, label="model")
        ax.set_xlabel("pressure [kPa abs]")
        ax.set_ylabel("position [mm]")
        ax.set_title(rv.name, fontsize=9)
        ax.grid(True, alpha=0.3)
    panels[0][0].legend(fontsize=8)
    tight_layout(fig)
    return fig


def plot_time(validation, records=None):
    """Per record (of ``records``, default all) and signal: measured and predicted
    against time, residual below."""
    from ..plotting import plot_measured_and_model

    entries = [(rv.name, rv.record.time, rv.record,
                {s: rv.predicted(s) for s in validation.signals}, rv.record.units)
               for rv in (validation.records if records is None else records)]
    return plot_measured_and_model(entries, validation.signals)


def plot_residuals(validation, records=None):
    """Per record (of ``records``, default all): the first signal's residual against
    pressure (or time, without a pressure record), and the residual autocorrelation with
    the ±1.96/√N band."""
    from .metrics import autocorrelation

    signal = validation.signals[0]
    records = validation.records if records is None else records
    fig, panels = panel_grid(len(records), rows_per=2, height=3.0)
    for (ax_res, ax_acf), rv in zip(panels, records, strict=True):
        residual = rv.residual(signal)
        unit, factor = _display(rv, signal, residual)
        if PRESSURE_SIGNAL in rv.record:
            ax_res.plot(rv.record[PRESSURE_SIGNAL] * 1e-3, residual * factor, ".", ms=1.5)
            ax_res.set_xlabel("pressure [kPa abs]")
        else:
            ax_res.plot(rv.record.time, residual * factor, ".", ms=1.5)
            ax_res.set_xlabel("time [s]")
        ax_res.set_ylabel(f"{signal} residual [{unit}]")
        ax_res.set_title(rv.name, fontsize=9)
        acf, band = autocorrelation(residual)
        lags = np.arange(acf.size)
        ax_acf.vlines(lags, 0, acf, lw=1)
        ax_acf.axhspan(-band, band, color="C2", alpha=0.2, label="white noise, 95 %")
        ax_acf.set_xlabel("lag [samples]")
        ax_acf.set_ylabel("autocorrelation")
        for ax in (ax_res, ax_acf):
            ax.grid(True, alpha=0.3)
    panels[0][1].legend(fontsize=8)
    tight_layout(fig)
    return fig


def _reversal_units(table) -> dict[str, str]:
    """The SI unit of each column of a reversal table (``Validation.reversals``)."""
    units = {}
    for column in table.columns:
        name = str(column)
        units[column] = ("Pa" if PRESSURE_SIGNAL in name else "m" if "position" in name
                         else "s" if "time" in name else "")
    return {c: u for c, u in units.items() if u}


def add_to_report(validation, report, title: str | None, figures: dict[str, bytes]) -> None:
    """Metrics, loop measures, reversals and the rendered ``figures``, as report
    sections."""
    label = title or f"Validation ({validation.label})"
    report.heading(label)
    report.text(f"{len(validation.records)} record(s); compared: "
                f"{', '.join(validation.signals)}. NRMSE = ‖y − ŷ‖/‖y − ȳ‖, "
                "fit % = 100·(1 − NRMSE), R² = 1 − NRMSE²; shown in mm or µm, kPa and N (the "
                "CSV files are SI).")
    verdicts = validation.verdicts()
    c = validation.criteria
    report.text("Verdict per record: fit % alone is not enough (a model whose loop is half "
                "as wide still follows the stroke). Adequate needs fit % ≥ "
                f"{c.min_fit_percent:g} for every signal, loop widths within "
                f"{100 * c.loop_width:g} %, loop area within {100 * c.loop_area:g} %, the "
                f"break-away within {100 * c.breakaway:g} % of the loop width and the "
                f"reversal positions within {100 * c.reversal:g} % of the loop width in "
                f"position; residuals count as white when at most "
                f"{100 * c.max_lags_outside:g} % of their autocorrelation lags leave the "
                "white-noise band. Each record drives the model through the input shown.")
    report.table(verdicts, "Verdict per record, with the value of every check", index=False)
    for _, row in verdicts[verdicts["verdict"] == "inadequate"].iterrows():
        report.note(f"{row['record']}: the model is inadequate for this record: "
                    f"{row['reasons']}.")
    for signal, shown in metrics_for_reading(validation.metrics()).items():
        report.table(shown, f"Error metrics of the {signal}, per record and pooled",
                     index=False)
    loops = validation.loops()
    if len(loops):
        report.table(display_frame(loops), "Hysteresis-loop measures, model against "
                     "measurement (difference = model − measured)", index=False)
        _images(report, figures, "loops", "Pressure–position loops: measured (dashed) and "
                                          "model (like the paper's Fig. 6)")
        reversal_table = validation.reversals()
        if len(reversal_table):
            report.table(display_frame(reversal_table, _reversal_units(reversal_table)),
                         "Reversal points of the pressure", index=False)
    _images(report, figures, "time", "Measured and predicted signals, residuals")
    _images(report, figures, "residuals", "Residuals against pressure and their "
                                          "autocorrelation")


def _images(report, figures: dict[str, bytes], name: str, caption: str) -> None:
    """Every page of the figure ``name`` (``name``, ``name-2``, ...), captioned."""
    pages = page_names(figures, name)
    for k, key in enumerate(pages, start=1):
        report.image(figures[key], caption if len(pages) == 1
                     else f"{caption} (page {k} of {len(pages)})")
