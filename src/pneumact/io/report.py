"""Self-contained HTML reports: tables and figures of a study, the parameter set with its
provenance, the software version and the exact call, in one file readable offline.

A ``Report`` collects blocks (headings, paragraphs, notes, tables, figures) and renders
them with one Jinja2 template (``templates/report.html.j2``); figures are embedded as
PNG data URIs, so the file can be mailed to a colleague. Writing is atomic.
"""

from __future__ import annotations

import base64
import datetime as _dt
import functools
import html
import io
import platform
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from ..errors import ArgumentError
from ..files import PathLike, atomic_write
from ..plotting import PNG_DPI, write_png
from .display import display_frame

if TYPE_CHECKING:  # pandas is imported on use: a result class costs nothing to import
    import pandas as pd
    from matplotlib.figure import Figure

__all__ = ["Block", "NotebookDisplay", "ParameterTable", "Report", "ResultVocabulary",
           "figure_png", "notebook_html", "table_writer"]

#: a table longer than this is cut in a report (its CSV file has every row)
REPORT_ROWS = 40
#: rows of the table a notebook shows, and the dpi of its inline figure
NOTEBOOK_ROWS = 12
NOTEBOOK_DPI = 80


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
    import pandas as pd
    for column in frame.columns:
        values = frame[column]
        if not pd.api.types.is_numeric_dtype(values) and len(values) and \
                values.astype(str).str.len().max() > PROSE_LENGTH:
            return True
    return False


class ParameterTable(Protocol):
    """What a report shows of a parameter set (a ``ParameterSet`` is one; io sits below
    the parameters, so it names only what it calls)."""

    def to_pandas(self) -> pd.DataFrame: ...

    def notes(self) -> list[str]: ...


@dataclass
class Report:
    """An HTML report under construction. ``call``: how it was produced (the command
    line or the Python call); ``parameters``: the parameter set (a ``ParameterSet``: its
``to_pandas()`` and its ``notes()``), shown with provenance."""

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
            parameters = self.parameters.to_pandas().to_html(index=False, border=0,
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


def _write_bytes(data: bytes, path: Path) -> None:
    Path(path).write_bytes(data)


def table_writer(frame: pd.DataFrame) -> Callable[[Path], object]:
    """A ``write_files`` writer of ``frame`` as CSV (its index too when it carries
    information: named, or not the plain row numbers)."""
    return lambda path: frame.to_csv(path, index=not _plain_index(frame))


def _plain_index(frame: pd.DataFrame) -> bool:
    """Whether the index of ``frame`` is only the row numbers."""
    import pandas as pd

    return frame.index.name is None and isinstance(frame.index, pd.RangeIndex)


def notebook_html(title: str, text: str = "", table: pd.DataFrame | None = None,
                  figure: Callable[[], Figure] | None = None) -> str:
    """The HTML a notebook shows for a result: its title and text, the first
    ``NOTEBOOK_ROWS`` rows of ``table`` in display units, and the figure ``figure()``
    draws as an inline PNG (left out, with its error, when drawing fails)."""
    parts = [f"<div class='pneumact'><strong>{html.escape(title)}</strong>"]
    if text:
        parts.append(f"<p>{html.escape(text)}</p>")
    if table is not None:
        shown = display_frame(table.head(NOTEBOOK_ROWS))
        parts.append(shown.to_html(index=not _plain_index(shown), border=0, na_rep="–",
                                   float_format=lambda v: f"{v:.4g}"))
        if len(table) > NOTEBOOK_ROWS:
            parts.append(f"<p>first {NOTEBOOK_ROWS} of {len(table)} rows "
                         "(<code>to_pandas()</code> has all, in SI)</p>")
    if figure is not None:
        try:
            png = figure_png(figure(), dpi=NOTEBOOK_DPI)
        except Exception as exc:  # a display must not raise: say why there is no figure
            parts.append(f"<p>(no figure: {html.escape(str(exc))})</p>")
        else:
            data = base64.b64encode(png).decode("ascii")
            parts.append(f"<img style='max-width:100%' src='data:image/png;base64,{data}'>")
    return "".join(parts) + "</div>"


class NotebookDisplay:
    """``_repr_html_`` for a notebook: the result's title, its main table
    (``notebook_table()``, default ``to_pandas()``) and, where ``inline_figure``, its
    figure (``plot()``) as an inline PNG. A result whose ``plot()`` simulates sets
    ``inline_figure = False`` (a display should not take seconds)."""

    __slots__ = ()
    inline_figure: ClassVar[bool] = True

    def notebook_title(self) -> str:
        return str(getattr(self, "report_title", "") or type(self).__name__)

    def notebook_text(self) -> str:
        text = getattr(self, "report_text", None)
        return text() if callable(text) else ""

    def notebook_table(self) -> pd.DataFrame | None:
        return self.to_pandas()  # type: ignore[attr-defined]

    def _repr_html_(self) -> str:
        return notebook_html(self.notebook_title(), self.notebook_text(),
                             self.notebook_table(),
                             self.plot if self.inline_figure else None)  # type: ignore[attr-defined]


class ResultVocabulary(NotebookDisplay):
    """What every result of pneumact speaks: ``to_pandas(name=None)`` (the main table,
    or the one named), ``plot()`` (a matplotlib ``Figure``) and ``write(folder)`` (each
    table as CSV, the figure as PNG, and ``report.html`` with both, all or nothing: a
    failed write leaves the previous results in place).

    A result names its tables in ``tables()`` (the first is the main one) and draws its
    figure in ``plot()``; ``report_title``, ``report_text()`` and ``report_parameters()``
    dress the report. A result with more to say overrides ``report()`` or ``write()``.
    """

    __slots__ = ()
    report_title: ClassVar[str] = "pneumact result"
    figure_name: ClassVar[str] = "figure"

    def tables(self) -> dict[str, pd.DataFrame]:
        """The result's tables by name, the main one first."""
        raise NotImplementedError

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """The main table, or the one ``name``d (see ``tables()``)."""
        tables = self.tables()
        if name is None:
            return next(iter(tables.values()))
        if name not in tables:
            raise ArgumentError(f"to_pandas: name = {name!r}; allowed: {', '.join(tables)}")
        return tables[name]

    def plot(self) -> Figure:
        raise NotImplementedError

    def figures(self) -> dict[str, Callable[[], Figure]]:
        """The figures ``write`` draws, by file name (default: ``plot()`` alone)."""
        return {self.figure_name: self.plot}

    def report_text(self) -> str:
        return ""

    def report_parameters(self) -> Any:
        """The parameter set shown at the end of the report (None: none)."""
        return None

    def report(self, call: str = "", png: bytes | None = None) -> Report:
        """The HTML report (the figures, the first as ``png`` if already drawn, and the
        tables), not yet written."""
        report = Report(self.report_title, call=call, parameters=self.report_parameters())
        if self.report_text():
            report.text(self.report_text())
        for i, (name, make) in enumerate(self.figures().items()):
            report.image(png if png is not None and i == 0 else
                         figure_png(make(), dpi=PNG_DPI), name.replace("_", " "))
        for name, frame in self.tables().items():
            cut = len(frame) > REPORT_ROWS
            report.table(display_frame(frame.head(REPORT_ROWS)),
                         f"{name.replace('_', ' ')}" + (
                f" (first {REPORT_ROWS} of {len(frame)} rows; all in {name}.csv)"
                if cut else ""), index=not _plain_index(frame))
        return report

    def write(self, out_dir: PathLike, *, call: str = "") -> list[Path]:
        """``<table>.csv`` for each table, ``<figure>.png`` and ``report.html`` in
        ``out_dir``, all or nothing (``pneumact.io.tables.write_files``)."""
        from .tables import write_files

        pngs = {name: figure_png(make(), dpi=PNG_DPI) for name, make in
                self.figures().items()}
        writers: dict[str, Callable[[Path], object]] = {
            f"{name}.csv": table_writer(frame) for name, frame in self.tables().items()}
        for name, png in pngs.items():
            writers[f"{name}.png"] = functools.partial(_write_bytes, png)
        writers.update(self.extra_files())
        writers["report.html"] = self.report(call, next(iter(pngs.values()), None)).write
        return write_files(out_dir, writers)

    def extra_files(self) -> dict[str, Callable[[Path], object]]:
        """Files beyond the tables, figures and report that ``write`` adds (name ->
        a function writing it to a path): none by default."""
        return {}
