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
