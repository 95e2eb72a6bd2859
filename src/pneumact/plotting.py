"""Plots of results and records, in display units (kPa, mm, mm/s, µm, N).

Files and results stay SI; only the axes convert. Every plot returns the matplotlib
``Figure`` (one convention across pneumact; a function that takes ``ax`` or ``axes``
draws on them and returns their Figure) and never calls ``plt.show()``. Importing
this module does not choose a matplotlib backend (the CLI selects "Agg" itself).
"""

from __future__ import annotations

import contextlib
import functools
import io
import os
import sys
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextvars import ContextVar
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from pneumact.core.units import signal_unit
from pneumact.errors import DataError
from pneumact.files import atomic_write

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "DISPLAY_UNITS",
    "FRICTION_TEST_KINDS",
    "MAX_PANEL_COLUMNS",
    "PANELS_PER_PAGE",
    "SMALL_LENGTH",
    "close_figure",
    "figure_writer",
    "label_log_axis",
    "off_screen",
    "page_name",
    "page_names",
    "panel_grid",
    "plot_friction_test",
    "plot_hysteresis",
    "plot_measured_and_model",
    "plot_time_series",
    "record_pages",
    "save_figure",
    "shown_unit",
]

#: whether figures are made off screen (``off_screen``), in this thread
_OFF_SCREEN: ContextVar[bool] = ContextVar("pneumact_off_screen", default=False)

#: SI unit -> (display unit, factor applied to SI values).
DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "Pa": ("kPa", 1e-3),
    "m": ("mm", 1e3),
    "m/s": ("mm/s", 1e3),
    "N": ("N", 1.0),
    "s": ("s", 1.0),
    "1": ("1", 1.0),
}
#: lengths [m] all below this are shown in µm (a residual of 3 µm, not 0.003 mm)
SMALL_LENGTH = 1e-4
_SMALL: dict[str, tuple[str, float]] = {"m": ("µm", 1e6), "m/s": ("µm/s", 1e6)}


def shown_unit(si: str, values: Any = ()) -> tuple[str, float]:
    """(display unit, factor from SI) of a simple SI unit (``DISPLAY_UNITS``); lengths
    whose magnitudes are all below ``SMALL_LENGTH`` in µm. Unknown units as they are."""
    finite = np.abs(np.asarray(values, dtype=float).ravel())
    finite = finite[np.isfinite(finite) & (finite > 0)]
    if si in _SMALL and finite.size and finite.max() < SMALL_LENGTH:
        return _SMALL[si]
    return DISPLAY_UNITS.get(si, (si, 1.0))


#: Signals shown in finer units than their SI unit suggests.
_SIGNAL_DISPLAY: dict[str, tuple[str, float]] = {
    "bristle": ("µm", 1e6),
}
_DEFAULT_SIGNALS = ("pressure", "position", "velocity", "friction")
FRICTION_TEST_KINDS = ("steady-state", "presliding", "frictional-lag", "break-away",
                       "stick-slip")
PNG_DPI = 120
#: at most this many panels side by side: more records wrap into rows (a taller figure),
#: so that every panel stays readable (≈ 500 px wide at PNG_DPI) and a figure of any
#: number of records stays under ≈ 2 300 px wide
MAX_PANEL_COLUMNS = 4
#: at most this many records' panels on one figure (4 rows of MAX_PANEL_COLUMNS): more
#: records make more figures, a page each (``record_pages``: loops.png, loops-2.png, ...),
#: not an ever taller one
PANELS_PER_PAGE = 16


# --------------------------------------------------------------------------- access


def signal_values(source: Any, name: str) -> np.ndarray:
    """Signal ``name`` (or "time") of a Result, Record, DataFrame or mapping, as floats."""
    if hasattr(source, "result") and hasattr(source, "kind"):  # a FrictionTestResult
        source = source.result
    try:
        pd = sys.modules.get("pandas")  # not imported: ``source`` is no DataFrame
        if pd is not None and isinstance(source, pd.DataFrame):
            if name in source.columns:
                return source[name].to_numpy(dtype=float)
            if name == "time" and source.index.name == "time":
                return source.index.to_numpy(dtype=float)
            raise KeyError(name)
        values = source[name]
    except KeyError:
        raise DataError(
            f"cannot plot: the data has no signal {name!r}; available: {_names(source)}"
        ) from None
    return np.asarray(values, dtype=float)


def _names(source: Any) -> str:
    names = getattr(source, "signals", None) or getattr(source, "columns", None) or source
    try:
        return ", ".join(map(str, list(names)))
    except TypeError:
        return "(unknown)"


def has_signal(source: Any, name: str) -> bool:
    """Whether ``source`` (as for ``signal_values``) carries signal ``name``."""
    if hasattr(source, "result") and hasattr(source, "kind"):
        source = source.result
    if hasattr(source, "columns"):
        return name in source.columns or (name == "time" and source.index.name == "time")
    signals = getattr(source, "signals", None)
    if isinstance(signals, dict):
        return name == "time" or name in signals
    try:
        return name in source
    except (TypeError, KeyError):
        return False


def _unit_of(source: Any, name: str) -> str:
    if hasattr(source, "result") and hasattr(source, "kind"):
        source = source.result
    units = getattr(source, "units", None)
    if units is None and hasattr(source, "attrs"):
        units = source.attrs.get("units")
    if units and name in units:
        return str(units[name])
    return signal_unit(name)


def display_values(source: Any, name: str) -> tuple[np.ndarray, str]:
    """(values in display units, axis label "name [unit]")."""
    values = signal_values(source, name)
    unit = _unit_of(source, name)
    shown, factor = _SIGNAL_DISPLAY.get(name) or DISPLAY_UNITS.get(unit, (unit, 1.0))
    label = name.replace("_", " ")
    return values * factor, f"{label} [{shown}]" if shown else label


@contextlib.contextmanager
def off_screen() -> Iterator[None]:
    """Figures made in the block (``new_axes``, ``panel_grid``) are drawn on an Agg canvas
    of their own, without pyplot: for figures only written to files (the command line),
    pyplot's import and figure manager (~0.05 s of a warm command) are not needed and the
    PNG is the same. Release them with ``close_figure``."""
    token = _OFF_SCREEN.set(True)
    try:
        yield
    finally:
        _OFF_SCREEN.reset(token)


def _subplots(nrows: int, ncols: int, **kwargs: Any) -> tuple[Figure, np.ndarray]:
    """``plt.subplots(nrows, ncols, **kwargs)``, or the same figure on an Agg canvas of its
    own inside ``off_screen``."""
    if not _OFF_SCREEN.get():
        import matplotlib.pyplot as plt

        return plt.subplots(nrows, ncols, **kwargs)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=kwargs.pop("figsize", None))
    FigureCanvasAgg(fig)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def close_figure(fig: Figure) -> None:
    """Let pyplot forget ``fig`` (nothing to do for a figure ``off_screen`` made, nor
    where pyplot was never imported)."""
    if "matplotlib.pyplot" in sys.modules:
        import matplotlib.pyplot as plt

        plt.close(fig)


def new_axes(nrows: int = 1, sharex: bool = True, height: float = 4.0):
    """A figure of ``nrows`` stacked axes: (figure, list of axes)."""
    fig, axes = _subplots(nrows, 1, sharex=sharex, squeeze=False,
                          figsize=(7.0, max(height, 2.2 * nrows)))
    return fig, list(axes[:, 0])


def panel_grid(n: int, rows_per: int = 1, width: float = 4.6, height: float = 3.4,
               columns: int = MAX_PANEL_COLUMNS):
    """A figure for ``n`` panels (a panel: ``rows_per`` axes stacked, e.g. a signal and
    its residual), at most ``columns`` side by side, wrapping into rows; ``width`` and
    ``height`` [in] of one axes. Returns (figure, panels): ``panels[i]`` the list of the
    i-th panel's axes, top first; the grid's unused axes are hidden."""
    n = max(1, int(n))
    cols = max(1, min(n, columns))
    rows = -(-n // cols)
    fig, axes = _subplots(rows * rows_per, cols, squeeze=False,
                          figsize=(width * cols, height * rows_per * rows))
    panels = [[axes[(i // cols) * rows_per + j, i % cols] for j in range(rows_per)]
              for i in range(n)]
    for i in range(n, rows * cols):
        for j in range(rows_per):
            axes[(i // cols) * rows_per + j, i % cols].set_visible(False)
    return fig, panels


def record_pages(items: Sequence[Any], per_page: int | None = None) -> list[list[Any]]:
    """``items`` (records, or what stands for them) in pages of at most ``per_page``
    (default ``PANELS_PER_PAGE``), one figure each; one empty page for no items."""
    size = max(1, int(per_page or PANELS_PER_PAGE))
    items = list(items)
    return [items[k:k + size] for k in range(0, len(items), size)] or [[]]


def page_name(name: str, page: int) -> str:
    """The name of the ``page``-th figure (from 1) of ``name``: ``loops``, ``loops-2``, ..."""
    return name if page <= 1 else f"{name}-{page}"


def page_names(figures: Mapping[str, Any], name: str) -> list[str]:
    """The keys of ``figures`` that are pages of ``name``, in page order."""
    found, page = [], 1
    while page_name(name, page) in figures:
        found.append(page_name(name, page))
        page += 1
    return found


def label_log_axis(ax: Axes, axis: str = "x") -> None:
    """Label a log axis with real numbers at 1, 2 and 5 of each decade (``%g``): a span
    of less than a decade otherwise shows one label ("1") or none."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    target = ax.xaxis if axis == "x" else ax.yaxis
    low, high = sorted(ax.get_xlim() if axis == "x" else ax.get_ylim())
    decades = np.log10(high / low) if low > 0 else np.inf
    subs = (1.0,) if decades > 4 else (1.0, 2.0, 5.0) if decades > 1.2 else \
        (1.0, 2.0, 3.0, 5.0, 7.0)
    target.set_major_locator(LogLocator(base=10.0, subs=subs))
    target.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    target.set_minor_formatter(NullFormatter())


# --------------------------------------------------------------------------- plots


def plot_hysteresis(result_or_frame: Any, ax: Axes | None = None, label: str | None = None,
                    reference: Any = None, **line_kw) -> Figure:
    """Applied pressure [kPa abs] (x) against position [mm] (y), like the paper's
    Figs. 5-6, on ``ax`` (a new figure when None); ``reference`` (a Result, Record or
    DataFrame, e.g. a measurement) is overlaid as a dashed black line. Returns the
    Figure (``fig.axes[0]`` is the Axes drawn on)."""
    if ax is None:
        _, (ax,) = new_axes()
    pressure = signal_values(result_or_frame, "pressure") * 1e-3
    position = signal_values(result_or_frame, "position") * 1e3
    ax.plot(pressure, position, label=label or ("simulated" if reference is not None
                                                 else None), **line_kw)
    if reference is not None:
        ax.plot(signal_values(reference, "pressure") * 1e-3,
                signal_values(reference, "position") * 1e3, "k--", linewidth=1.0, label="measured")
    ax.set_xlabel("pressure [kPa abs]")
    ax.set_ylabel("position [mm]")
    ax.grid(True, alpha=0.3)
    if label is not None or reference is not None:
        ax.legend()
    return cast("Figure", ax.figure)  # the figure the axes were drawn on


def plot_time_series(result: Any, signals: Sequence[str] | None = None,
                     axes: Sequence[Axes] | None = None) -> Figure:
    """One panel per signal (default: pressure, position, velocity, friction, those
    present), in display units, over a shared time axis [s]. Returns the Figure."""
    if signals is None:
        signals = [s for s in _DEFAULT_SIGNALS if has_signal(result, s)]
        signals += [s for s in _names(result).split(", ") if s.startswith("drive_")]
    if isinstance(signals, str):
        signals = [signals]
    if not signals:
        raise DataError("plot_time_series: no signal to plot; pass signals=[...]")
    if axes is None:
        fig, axes = new_axes(len(signals))
    else:
        axes = list(np.ravel(np.asarray(axes, dtype=object)))  # a grid of axes too
        if len(axes) < len(signals):
            raise DataError(f"plot_time_series: {len(signals)} signals but {len(axes)} axes")
        fig = axes[0].figure
    time = signal_values(result, "time")
    for ax, name in zip(axes, signals, strict=False):
        values, ylabel = display_values(result, name)
        ax.plot(time, values)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    axes[len(signals) - 1].set_xlabel("time [s]")
    return fig


def _drive_force_name(result: Any) -> str | None:
    for name in ("drive_force", "drive_drive_force"):
        if has_signal(result, name):
            return name
    return None


def _xy(ax: Axes, source: Any, x: str, ys: Sequence[str], **kw) -> None:
    xv, xlabel = display_values(source, x)
    for y in ys:
        yv, ylabel = display_values(source, y)
        ax.plot(xv, yv, label=y.replace("_", " "), **kw)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel if len(ys) == 1 else "force [N]")
    if len(ys) > 1:
        ax.legend()
    ax.grid(True, alpha=0.3)


def _column(table: Any, *names: str) -> str | None:
    """First column of ``table`` named ``name`` or ``name [unit]``, among ``names``."""
    columns = [str(c) for c in table.columns]
    for name in names:
        for column in columns:
            if column == name or column.startswith(f"{name} ["):
                return column
    return None


def _curve_from_table(ax: Axes, table: Any, kind: str) -> bool:
    """Friction against velocity from a friction test's table; False if not possible."""
    vel = _column(table, "velocity")
    simulated = _column(table, "friction")
    model = _column(table, "steady-state friction")
    if vel is None or (simulated is None and model is None):
        return False
    group = _column(table, "frequency")
    parts = table.groupby(group) if kind == "frictional-lag" and group else [(None, table)]
    for key, part in parts:
        v = part[vel].to_numpy(float) * 1e3
        label = f"{key:g} Hz" if key is not None else "simulated"
        if simulated is not None:
            ax.plot(v, part[simulated].to_numpy(float), "o" if key is None else "-",
                    label=label, markersize=4)
    if model is not None:
        order = np.argsort(table[vel].to_numpy(float))
        v = table[vel].to_numpy(float)[order] * 1e3
        f = table[model].to_numpy(float)[order]
        gap = np.flatnonzero(np.diff(np.sign(v)) != 0) + 1  # no line across v = 0
        ax.plot(np.insert(v, gap, np.nan), np.insert(f, gap, np.nan), "k--", linewidth=1.0,
                label="steady-state map")
    speeds = np.abs(table[vel].to_numpy(float)) * 1e3
    if kind == "steady-state" and np.any(speeds > 0):
        # Stribeck region and sliding region both visible: log-like in each direction.
        ax.set_xscale("symlog", linthresh=float(np.min(speeds[speeds > 0])))
    ax.set_xlabel("velocity [mm/s]")
    ax.set_ylabel("friction [N]")
    ax.legend()
    ax.grid(True, alpha=0.3)
    return True


def plot_friction_test(result: Any, kind: str) -> Figure:
    """Axes that suit each classic friction experiment of a friction rig result (or a
    FrictionTestResult, whose ``.table`` is used for the steady-state curve):

    steady-state and frictional-lag: friction vs velocity; presliding: friction and drive
    force vs position [µm]; break-away: drive force and position vs time; stick-slip:
    position, velocity and friction vs time. Returns the Figure.
    """
    if kind not in FRICTION_TEST_KINDS:
        raise DataError(f"friction test kind = {kind!r}; allowed: {', '.join(FRICTION_TEST_KINDS)}")
    table = getattr(result, "table", None)
    drive_force = _drive_force_name(result)
    if kind in ("steady-state", "frictional-lag"):
        fig, (ax,) = new_axes()
        if table is None or not _curve_from_table(ax, table, kind):
            _xy(ax, result, "velocity", ["friction"])
    elif kind == "presliding":
        fig, (ax,) = new_axes()
        ys = ["friction"] + ([drive_force] if drive_force else [])
        xv = signal_values(result, "position") * 1e6
        for y in ys:
            ax.plot(xv, signal_values(result, y), label=y.replace("_", " "))
        ax.set_xlabel("position [µm]")
        ax.set_ylabel("force [N]")
        ax.legend()
        ax.grid(True, alpha=0.3)
    elif kind == "break-away":
        names = [drive_force or "friction", "position"]
        fig = plot_time_series(result, names)
    else:  # stick-slip
        fig = plot_time_series(result, ["position", "velocity", "friction"])
    fig.suptitle(kind)
    return fig


# --------------------------------------------------------------------------- saving


def write_png(fig, target, dpi: int) -> None:
    """Draw ``fig`` as PNG into ``target`` (a path or a binary file), cropped to what it
    draws (``bbox_inches="tight"``). Matplotlib warns when placing a ``loc="best"``
    legend over many points took it over a second, a matter of the machine's load, not
    of the figure: that warning is not passed on."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message='Creating legend with loc="best"',
                                category=UserWarning)
        png = _tight_png(fig, dpi)
        if png is None:
            fig.savefig(target, format="png", dpi=dpi, bbox_inches="tight")
            return
    if hasattr(target, "write"):
        target.write(png)
    else:
        from pathlib import Path

        Path(target).write_bytes(png)


def _crop(pixels: np.ndarray, box, dpi: int, facecolor) -> np.ndarray:
    """The pixels of ``box`` [in] of a drawn figure (rows from the top); where the box
    (its padding) reaches past the figure, the figure's face colour, as savefig's
    enlarged canvas shows it."""
    import math

    rows, columns = pixels.shape[:2]
    top, bottom = rows - math.ceil(box.y1 * dpi), rows - int(box.y0 * dpi)
    left, right = int(box.x0 * dpi), math.ceil(box.x1 * dpi)
    face = np.round(np.asarray(facecolor, dtype=float) * 255).astype(np.uint8)
    out = np.empty((bottom - top, right - left, 4), dtype=np.uint8)
    out[:] = face
    inside = pixels[max(top, 0):min(bottom, rows), max(left, 0):min(right, columns)]
    row0, column0 = max(top, 0) - top, max(left, 0) - left
    out[row0:row0 + inside.shape[0], column0:column0 + inside.shape[1]] = inside
    return out


def _tight_png(fig, dpi: int) -> bytes | None:
    """The PNG ``savefig(bbox_inches="tight")`` writes, drawn once instead of twice
    (savefig lays the figure out in a first, hidden draw to measure it, then draws it
    again: a third of a many-panel figure's time): the figure drawn at ``dpi`` on its
    Agg canvas, its tight box measured on that drawing and the pixels cropped to it (±1
    pixel of savefig's; its padding may reach past the figure). None (savefig does it)
    where what is drawn reaches outside the figure, which a crop cannot show, or the
    figure or the savefig settings are not the plain Agg case."""
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    rc = matplotlib.rcParams
    pad = rc["savefig.pad_inches"]
    if (type(fig.canvas) is not FigureCanvasAgg or rc["savefig.transparent"]
            or rc["savefig.facecolor"] != "auto" or rc["savefig.edgecolor"] != "auto"
            or not isinstance(pad, (int, float))):
        return None
    canvas, original_dpi = fig.canvas, fig.dpi
    try:
        fig.set_dpi(dpi)
        with _ticks_computed_once(fig):
            canvas.draw()
            drawn = fig.get_tightbbox(canvas.get_renderer())
        width, height = fig.get_size_inches()
        if drawn.x0 < 0 or drawn.y0 < 0 or drawn.x1 > width or drawn.y1 > height:
            return None
        pixels = np.asarray(canvas.buffer_rgba())
        crop = _crop(pixels, drawn.padded(pad), dpi, fig.get_facecolor())
        buffer = io.BytesIO()
        Image.fromarray(crop).save(buffer, format="png", dpi=(dpi, dpi))
        return buffer.getvalue()
    finally:
        fig.set_dpi(original_dpi)


def tight_layout(fig: Figure, **options: Any) -> None:
    """``fig.tight_layout(**options)``, each axis's ticks placed and labelled once for the
    whole measurement (``_ticks_computed_once``: the same layout, a third faster on a
    many-panel figure)."""
    with _ticks_computed_once(fig):
        fig.tight_layout(**options)


@contextlib.contextmanager
def _ticks_computed_once(fig):
    """Within the block, each axis of ``fig`` places and labels its ticks once: the draw
    and the tight box measured on it then share them (matplotlib redoes it for every
    call, several times per axis and per shared sibling: a quarter of a many-panel
    figure's drawing). Nothing in the block may change a limit, a position or the dpi.
    Where matplotlib has no such step (``Axis._update_ticks``), nothing is cached."""
    axes = [axis for ax in fig.axes
            for axis in (getattr(ax, "_axis_map", None) or {}).values()
            if callable(getattr(axis, "_update_ticks", None))]
    for axis in axes:
        axis._update_ticks = functools.cache(axis._update_ticks)
    try:
        yield
    finally:
        for axis in axes:
            del axis._update_ticks


def save_figure(fig: Figure | Axes, path: str | os.PathLike[str]) -> os.PathLike[str]:
    """Write ``fig`` (a Figure, or the Figure of an Axes) as PNG (dpi 120), atomically."""
    from pathlib import Path

    figure = getattr(fig, "figure", None) if not hasattr(fig, "savefig") else fig
    if figure is None or not hasattr(figure, "savefig"):
        raise DataError(f"save_figure: expected a matplotlib Figure or Axes, got {type(fig)}")
    target = Path(path)
    with atomic_write(target) as tmp:
        write_png(figure, tmp, PNG_DPI)
    return target


def plot_measured_and_model(entries: Sequence[tuple], signals: Sequence[str],
                            model_label: str = "model",
                            window: tuple[float, float] | None = None) -> Figure:
    """Per record (a panel of the grid, ``panel_grid``) and signal: measured and model
    against time, with the residual (measured − model) below, in display units.
    ``entries``: (title, time, measured, model, units), ``measured``/``model`` mapping each
    signal to values on ``time``, ``units`` each signal to its SI unit; ``window`` shades a
    time span."""
    k = len(signals)
    fig, panels = panel_grid(len(entries), rows_per=2 * k, width=4.6, height=2.3)
    for i, (title, time, measured, model, units) in enumerate(entries):
        axes = panels[i]
        for a in axes[1:]:
            a.sharex(axes[0])
        for j, s in enumerate(signals):
            unit, factor = DISPLAY_UNITS.get(units.get(s, ""), ("", 1.0))
            residual = measured[s] - model[s]
            unit_r, factor_r = shown_unit(units.get(s, ""), residual)
            ax, axr = axes[2 * j], axes[2 * j + 1]
            ax.plot(time, measured[s] * factor, "k.", ms=1.5, label="measured")
            ax.plot(time, model[s] * factor, "C0-", lw=1, label=model_label)
            axr.plot(time, residual * factor_r, "C3-", lw=0.8)
            if window is not None:
                for a in (ax, axr):
                    a.axvspan(max(window[0], time[0]), min(window[1], time[-1]), color="C2",
                              alpha=0.08, label="fitted window" if a is ax else None)
            ax.set_ylabel(f"{s} [{unit}]")
            axr.set_ylabel(f"measured − model [{unit_r}]")
            ax.set_title(title, fontsize=9)
            for a in (ax, axr):
                a.grid(True, alpha=0.3)
        axes[-1].set_xlabel("time [s]")
    panels[0][0].legend(fontsize=8)
    tight_layout(fig)
    return fig


def figure_writer(make):
    """A writer for ``write_files``: ``make()`` builds a Figure, written as PNG to the
    path it is given and closed (so a long study does not keep its figures open)."""

    def write(path):
        fig = make()
        try:
            write_png(fig, path, PNG_DPI)
        finally:
            close_figure(fig)

    return write
