"""``plotting.write_png``: the PNG savefig(bbox_inches="tight") writes, drawn once.

The one-draw path crops the drawn canvas to the tight box; where the box's padding
reaches past the figure (an axis label near its edge, as in a run's hysteresis figure)
the padding is filled with the figure's face colour instead of drawing it all again.
"""

from __future__ import annotations

import io

import matplotlib
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

import reference as ref
from pneumact.plotting import write_png

pytestmark = pytest.mark.unit
DPI = 100


def _figure(bottom: float) -> Figure:
    fig = Figure(figsize=(7, 4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot(np.linspace(0, 1, 50), np.sin(np.linspace(0, 6, 50)))
    ax.set_xlabel("pressure [kPa]")
    ax.set_ylabel("position [mm]")
    fig.subplots_adjust(bottom=bottom, left=0.13)
    return fig


def _pixels(png: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGBA")).astype(int)


@pytest.mark.parametrize("bottom", [0.11, 0.3])
def test_the_png_is_savefig_s_drawn_once(monkeypatch, bottom):
    """A label whose padding reaches below the figure (0.11) and one well inside (0.3):
    no second draw, and the image is savefig's to a pixel."""
    fig = _figure(bottom)
    fig.canvas.draw()
    drawn = fig.get_tightbbox(fig.canvas.get_renderer())
    padding_outside = drawn.y0 - matplotlib.rcParams["savefig.pad_inches"] < 0
    assert padding_outside == (bottom < 0.2) and drawn.y0 >= 0  # the cases meant

    expected = io.BytesIO()
    _figure(bottom).savefig(expected, format="png", dpi=DPI, bbox_inches="tight")

    def no_second_draw(*args, **kwargs):
        raise AssertionError("write_png fell back to savefig")

    monkeypatch.setattr(Figure, "savefig", no_second_draw)
    written = io.BytesIO()
    write_png(fig, written, DPI)
    a, b = _pixels(written.getvalue()), _pixels(expected.getvalue())
    assert abs(a.shape[0] - b.shape[0]) <= 1 and abs(a.shape[1] - b.shape[1]) <= 1
    h, w = min(a.shape[0], b.shape[0]) - 1, min(a.shape[1], b.shape[1]) - 1
    best = min(np.abs(a[i:i + h, j:j + w] - b[k:k + h, m:m + w]).mean()
               for i in range(2) for j in range(2) for k in range(2) for m in range(2))
    assert best <= ref.PNG_MEAN_DIFFERENCE, best


def _grid() -> Figure:
    """Panels whose ticks and labels differ (the layout depends on each one's width)."""
    fig = Figure(figsize=(9, 7))
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 3, sharex="col")
    for k, ax in enumerate(axes.flat):
        ax.plot(np.linspace(0, 10 ** k, 20), np.linspace(-(10 ** (k - 4)), 7 ** k, 20))
        ax.set_xlabel("pressure [kPa]")
        ax.set_ylabel("position [mm]")
        ax.set_title(f"panel {k}")
    return fig


def test_ticks_computed_once_lay_out_and_draw_as_matplotlib_does(monkeypatch):
    """``plotting.tight_layout`` places the panels where ``Figure.tight_layout`` does and
    the one-draw PNG has the same bytes as with ticks recomputed at every call; after
    either, matplotlib computes ticks again (a later change of limits is drawn)."""
    import contextlib

    import pneumact.plotting
    from pneumact.plotting import tight_layout

    ours, theirs = _grid(), _grid()
    tight_layout(ours)
    theirs.tight_layout()
    for a, b in zip(ours.axes, theirs.axes, strict=True):
        assert a.get_position().bounds == b.get_position().bounds
        assert "_update_ticks" not in vars(a.xaxis) and "_update_ticks" not in vars(a.yaxis)

    def pngs(fig: Figure) -> tuple[bytes, bytes]:
        first, second = io.BytesIO(), io.BytesIO()
        write_png(fig, first, DPI)
        fig.axes[0].set_xlim(0, 0.5)
        write_png(fig, second, DPI)
        return first.getvalue(), second.getvalue()

    cached = pngs(ours)
    monkeypatch.setattr(pneumact.plotting, "_ticks_computed_once",
                        lambda fig: contextlib.nullcontext())
    assert cached == pngs(theirs)
    assert cached[0] != cached[1]  # the new limits were drawn


@pytest.mark.parametrize("panels", [1, 3])
def test_a_figure_made_off_screen_writes_the_same_png_as_pyplot_s(panels):
    """``plotting.off_screen`` (the command line's figures: no pyplot) makes the figure
    pyplot would, on an Agg canvas of its own: the same PNG, byte for byte."""
    import matplotlib.pyplot as plt

    from pneumact.plotting import close_figure, new_axes, off_screen, panel_grid

    def draw() -> Figure:
        fig, axes = new_axes(panels) if panels == 1 else panel_grid(panels, rows_per=2)
        for k, ax in enumerate(np.ravel(axes)):
            ax.plot(np.linspace(0, 1, 80), np.cos(np.linspace(0, 5 + k, 80)), label="cos")
            ax.set_xlabel("time [s]")
        np.ravel(axes)[0].legend()
        return fig

    on_pyplot = draw()
    with off_screen():
        alone = draw()
    assert plt.fignum_exists(on_pyplot.number) and alone.canvas.manager is None  # no pyplot
    pngs = []
    for fig in (on_pyplot, alone):
        buffer = io.BytesIO()
        write_png(fig, buffer, DPI)
        pngs.append(buffer.getvalue())
        close_figure(fig)
    assert pngs[0] == pngs[1]
    assert not plt.fignum_exists(on_pyplot.number)  # closed
