"""Self-contained HTML reports: tables and figures of a study, the parameter set with its
provenance, the software version and the exact call, in one file readable offline.

A ``Report`` collects blocks (headings, paragraphs, notes, tables, figures) and renders
them with one Jinja2 template (``templates/report.html.j2``); figures are embedded as
PNG data URIs, so the file can be mailed to a colleague. Writing is atomic.
"""

from __future__ import annotations

import base64
import datetime as _dt
import io
import platform
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import pandas as pd

from ..plotting import write_png
from .tables import PathLike, atomic_write

__all__ = ["Block", "ParameterTable", "Report", "figure_png"]


@dataclass(frozen=True)
class Block:
    """One piece of a report: ``kind`` is heading, text, note, table or figure."""

    kind: str
    content: str
    caption: str = ""
    anchor: str = ""


def figure_png(fig, dpi: int = 110) -> bytes:
    """A matplotlib figure as PNG bytes (the figure is closed)."""
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    try:
        write_png(fig, buffer, dpi)
    finally:
        plt.close(fig)
    return buffer.getvalue()


PROSE_LENGTH = 40  # a text cell longer than this many characters is a sentence


def _has_prose(frame: pd.DataFrame) -> bool:
    """Whether a text column of ``frame`` holds a sentence."""
    for column in frame.columns:
        values = frame[column]
        if not pd.api.types.is_numeric_dtype(values) and len(values) and \
                values.astype(str).str.len().max() > PROSE_LENGTH:
            return True
    return False


class ParameterTable(Protocol):
    """What a report shows of a parameter set (a ``ParameterSet`` is one; io sits below
    the parameters, so it names only what it calls)."""

    def to_frame(self) -> pd.DataFrame: ...

    def notes(self) -> list[str]: ...


@dataclass
class Report:
    """An HTML report under construction. ``call``: how it was produced (the command
    line or the Python call); ``parameters``: the parameter set (a ``ParameterSet``: its
``to_frame()`` and its ``notes()``), shown with provenance."""

    title: str
    call: str = ""
    parameters: ParameterTable | None = None
    blocks: list[Block] = field(default_factory=list)

    def heading(self, text: str) -> Report:
        anchor = f"s{sum(b.kind == 'heading' for b in self.blocks) + 1}"
        self.blocks.append(Block("heading", text, anchor=anchor))
        return self

    def text(self, text: str) -> Report:
        self.blocks.append(Block("text", text))
        return self

    def note(self, text: str) -> Report:
        """A highlighted statement, e.g. where our numbers disagree with the paper."""
        self.blocks.append(Block("note", text))
        return self

    def table(self, frame: pd.DataFrame, caption: str = "", digits: int = 4,
              index: bool = True) -> Report:
        """A table (wider than the page: it scrolls in its own box); a table with
        sentences in it is set left-aligned, to be read."""
        classes = ["data", "prose"] if _has_prose(frame) else ["data"]
        html = frame.to_html(index=index, border=0, classes=classes, na_rep="–",
                             float_format=lambda v: f"{v:.{digits}g}")
        self.blocks.append(Block("table", html, caption))
        return self

    def figure(self, fig, caption: str = "") -> Report:
        return self.image(figure_png(fig), caption)

    def image(self, png: bytes, caption: str = "") -> Report:
        """An already rendered PNG (e.g. the file a command also writes)."""
        self.blocks.append(Block("figure", base64.b64encode(png).decode("ascii"), caption))
        return self

    def render(self) -> str:
        import jinja2

        from ..version import __version__

        env = jinja2.Environment(loader=jinja2.PackageLoader("pneumact.io", "templates"),
                                 autoescape=jinja2.select_autoescape(["html", "j2"]))
        parameters = None
        notes: list[str] = []
        if self.parameters is not None:
            parameters = self.parameters.to_frame().to_html(index=False, border=0,
                                                            classes="data", na_rep="")
            notes = self.parameters.notes()
        return env.get_template("report.html.j2").render(
            title=self.title, blocks=self.blocks, call=self.call, parameters=parameters,
            parameter_notes=notes,
            parameter_set=getattr(self.parameters, "name", ""), version=__version__,
            python=platform.python_version(),
            created=_dt.datetime.now().astimezone().isoformat(timespec="seconds"))

    def write(self, path: PathLike) -> Path:
        """Render and write atomically (nothing is left on disk if rendering fails)."""
        text = self.render()
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_write(path) as tmp:
            Path(tmp).write_text(text, encoding="utf-8")
        return path
