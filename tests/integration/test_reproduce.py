"""``pneumact reproduce --quick``: every figure, every table, and the report shows the
numbers that were computed."""

from __future__ import annotations

from html.parser import HTMLParser

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import reference as ref
from pneumact.cli import app
from pneumact.reproduction import reproduce

FIGURES = ("fig2_friction_velocity", "fig3_friction_variations", "fig5_loops",
           "fig6_validation", "identification_spring", "identification_sliding",
           "identification_stribeck", "identification_presliding",
           "sobol_loop_width_pressure", "sobol_breakaway_pressure")
TABLES = ("table_1", "oat_runs", "identification", "validation_metrics", "validation_loops",
          "sensitivity_ranking", "paper_statements")


class _Tables(HTMLParser):
    """The cells of every <table> of an HTML page, row by row."""

    def __init__(self) -> None:
        super().__init__()
        self.tables: list[list[list[str]]] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr" and self.tables:
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _same(shown: str, value) -> bool:
    if isinstance(value, bool | np.bool_):
        return shown == str(bool(value))
    if isinstance(value, float | np.floating):
        if not np.isfinite(value):
            return shown in ("–", "nan", "inf", "-inf")
        return float(shown) == pytest.approx(float(value), rel=ref.REPORT_DIGITS_RTOL,
                                             abs=1e-300)
    return shown == str(value)


def _find(tables, frame: pd.DataFrame):
    header = [str(c) for c in frame.columns]
    for table in tables:
        if table and table[0] == header and len(table) == len(frame) + 1:
            return table[1:]
    raise AssertionError(f"no table with columns {header} and {len(frame)} rows")


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    return reproduce(out, quick=True)


def test_quick_reproduction_writes_every_figure_and_table(quick):
    names = {p.name for p in quick.files}
    assert {f"{f}.png" for f in FIGURES} <= names
    assert {f"{t}.csv" for t in TABLES} <= names
    assert "index.html" in names


def test_the_report_shows_the_computed_numbers(quick):
    parser = _Tables()
    parser.feed(quick.report.read_text(encoding="utf-8"))
    for name in TABLES:
        frame = quick.tables[name]
        rows = _find(parser.tables, frame)
        for shown, (_, row) in zip(rows, frame.iterrows(), strict=True):
            for cell, value in zip(shown, row.to_numpy(), strict=True):
                assert _same(cell, value), (name, cell, value)


def test_the_report_says_where_we_disagree_with_the_paper(quick):
    statements = quick.tables["paper_statements"]
    html = quick.report.read_text(encoding="utf-8")
    for _, row in statements[~statements["agrees"]].iterrows():
        assert "We disagree with the paper" in html and row["ours"].split(";")[0] in html
    assert quick.tables["table_1"]["assumed"].any()  # the values the paper lacks


def test_identified_parameters_are_close_to_table_one(quick):
    table = quick.tables["identification"].set_index("parameter")
    for name in ("F0", "k", "Fc", "Fs"):
        assert abs(table.loc[name, "error_%"]) < 2.0, name
    metrics = quick.tables["validation_metrics"]
    assert (metrics["fit_percent"] > 99.0).all()


def test_cli_reproduce_quick(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["reproduce", "--quick", "--out", "paper"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "paper" / "index.html").exists()
    assert "pneumact reproduce --quick --out paper" in (
        tmp_path / "paper" / "index.html").read_text(encoding="utf-8")
