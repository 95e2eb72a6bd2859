"""``pneumact reproduce --quick``: every figure, every table, and the report shows the
numbers that were computed."""

from __future__ import annotations

import dataclasses
import re
from html import unescape
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import reference as ref
from browser import assert_fits_the_page, needs_browser
from pneumact.cli import app
from pneumact.reproduction import SOBOL_TARGET_WIDTH, Sizes, reproduce
from pneumact.statements import STATEMENTS

SEAL_DATA = (Path(__file__).resolve().parents[3] / "shared" / "data"
             / "pneumatic_cylinder_friction_tudelft")
FIGURES = ("fig2_friction_velocity", "fig3_friction_variations", "fig5_loops",
           "fig5_changes_by_speed", "fig6_validation", "identification_spring",
           "identification_sliding", "identification_stribeck", "identification_presliding",
           "sobol_loop_width_pressure", "sobol_breakaway_pressure", "src_by_speed",
           "pneumatics_flow", "chamber_step", "fig6_richer",
           "identification_presliding_window")
TABLES = ("table_1", "chamber_time_constant", "natural_frequencies", "modelling_choices",
          "fig3_effects", "oat_runs", "conditions", "fig5_changes",
          "identification", "eq13", "validation_verdicts", "validation_metrics",
          "validation_loops", "validation_richer", "sensitivity_ranking", "oat_ranking",
          "global_by_condition", "fig5a_sigma0_factors", "law_changes", "statement_texts",
          "paper_statements", "statement_conditions", "sobol_convergence")


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


#: Per figure the reproduction draws: (x label, y label) of each panel with data, a
#: panel's empty label replaced by that of a panel it shares the axis with.
FIGURE_AXES: list[list[tuple[str, str]]] = []


def _axis_labels(fig) -> list[tuple[str, str]]:
    out = []
    for ax in fig.axes:
        if not ax.get_visible() or not (ax.lines or ax.collections or ax.patches):
            continue
        x = ax.get_xlabel() or next((o.get_xlabel() for o in
                                     ax.get_shared_x_axes().get_siblings(ax)
                                     if o.get_xlabel()), "")
        y = ax.get_ylabel() or next((o.get_ylabel() for o in
                                     ax.get_shared_y_axes().get_siblings(ax)
                                     if o.get_ylabel()), "")
        out.append((x, y))
    return out


@pytest.fixture(scope="module")
def quick_cli(tmp_path_factory):
    """One quick reproduction, run from the command line as a user runs it: (the CLI's
    result, the ``Reproduction`` the API returned to it, the folder). One run serves the
    command line's tests and the API's (it takes ~10 s)."""
    import pneumact.io.report as report
    import pneumact.reproduction as reproduction

    folder = tmp_path_factory.mktemp("cli")
    returned = []
    drawn = report.figure_png

    def keep(*args, **kwargs):
        returned.append(reproduce(*args, **kwargs))
        return returned[-1]

    def labels_then_png(fig, *args, **kwargs):
        FIGURE_AXES.append(_axis_labels(fig))
        return drawn(fig, *args, **kwargs)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(reproduction, "reproduce", keep)
        patch.setattr(report, "figure_png", labels_then_png)
        # every figure drawn in this process, where the spy above sees it (the quick
        # mode's worker would draw some: tests/unit/test_reproduction_parts.py holds a
        # section made there to the same blocks, figures and tables as made here)
        patch.setattr(reproduction, "BESIDE", False)
        patch.chdir(folder)
        result = CliRunner().invoke(app, ["reproduce", "--quick", "--out", "paper"])
    assert result.exit_code == 0, result.output
    assert len(returned) == 1
    # the command line passed the relative folder it was given: anchor its paths here
    made = returned[0]
    made = dataclasses.replace(made, out_dir=folder / made.out_dir,
                               files=[folder / p for p in made.files])
    return result, made, folder / "paper"


@pytest.fixture(scope="module")
def quick(quick_cli):
    return quick_cli[1]


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


def test_every_statement_is_shown_with_the_conditions_where_it_holds(quick):
    summary = quick.tables["paper_statements"]
    assert list(summary["statement"]) == [s.key for s in STATEMENTS]  # one per parameter
    assert {"Fig. 5a", "Fig. 5b", "Fig. 5c", "Fig. 5d, e", "Fig. 5e", "Fig. 5f",
            "Fig. 3"} <= set(summary["source"])
    assert summary["holds for"].str.len().gt(0).all()
    # the applied pressure leads, the command valve beside it: both computed, so studied
    assert not summary["holds for"].str.contains("not studied").any()
    loops = summary[summary["statement"].isin([s.key for s in STATEMENTS
                                               if s.axis == "v/vs"])]
    assert not loops["command valve"].str.contains("not studied").any()
    html = unescape(quick.report.read_text(encoding="utf-8"))
    for _, row in summary[summary["holds for"].str.startswith("nowhere")].iterrows():
        assert f"“{row['paper']}” ({row['criterion']}) holds nowhere" in html
    per = quick.tables["statement_conditions"]
    assert (per["holds"] == (per["margin"] >= 0)).all()
    within = per["margin"].abs() <= per["noise"]
    assert ((per["verdict"] == "within noise") == within).all()
    assert quick.tables["table_1"]["assumed"].any()  # the values the paper lacks


def test_the_verdicts_lead_the_report(quick):
    """Issue #40, item 2: the statements' verdicts come first, right after the
    introduction, before Table I."""
    html = unescape(quick.report.read_text(encoding="utf-8"))
    glance = html.index("The paper's statements at a glance")
    assert glance < html.index("values from the paper; ")  # Table I's section
    summary = quick.tables["paper_statements"]
    for key in summary.loc[summary["holds for"].str.startswith("nowhere"), "statement"]:
        assert key in html[glance:glance + 4000]


def test_the_sigma0_claim_read_as_written(quick):
    """Fig. 5a beyond ±50 %: on the 20 s command cycle the loop moves 17 % at σ0 ×0.1,
    10 % at ×0.2, 3 % at ×0.5 and 1.8–3.4 % at ×2 … ×10 (the referee's numbers, issue
    #40): the claim holds for a softer bristle, not a stiffer one."""
    table = quick.tables["fig5a_sigma0_factors"]
    row = table[(table["valve"] == "command") & (table["period"] == 20.0)].iloc[0]
    for factor, change in ref.SIGMA0_LOOP_CHANGE_COMMAND_20S.items():
        assert row[f"σ0 ×{factor:g}"] == pytest.approx(change, abs=ref.LOOP_CHANGE_ATOL)
    for factor in (2, 5, 10):
        assert ref.SIGMA0_STIFFER_CHANGE[0] <= row[f"σ0 ×{factor}"] \
            <= ref.SIGMA0_STIFFER_CHANGE[1]
    per = quick.tables["statement_conditions"].set_index(["statement", "condition"])
    assert per.loc[("5a_sigma0_x0.1", "command, 20 s"), "verdict"] == "holds"
    assert per.loc[("5a_sigma0_x2", "command, 20 s"), "verdict"] == "does not hold"


def test_fs_and_fc_matter_most_only_below_the_stribeck_velocity(quick):
    """Issue #19: the paper's conclusion holds at slow rates, not on the 20 s cycle; per
    parameter (issue #40) it is Fs that drops out above vs, Fc stays ahead there. Read
    under the applied pressure (issue #40 item 2: the paper's conditions; the quick mode
    runs its slowest cycle behind the source only), and on the command valve's 20 s
    cycle."""
    per = quick.tables["statement_conditions"]
    source = per[per["valve"] == "source"]
    for key in ("conclusion_oat_Fs", "conclusion_global_Fs"):
        rows = source[source["statement"] == key].sort_values("x")
        assert rows["x"].iloc[0] < 1.0 and rows["holds"].iloc[0], key
        assert rows["x"].iloc[-1] > 3.0 and not rows["holds"].iloc[-1], key
        command = per[(per["valve"] == "command") & (per["statement"] == key)]
        assert (command["x"] > 5.0).all() and not command["holds"].any(), key
    fc = per[(per["statement"] == "conclusion_oat_Fc") & (per["x"] > 1.0)]
    assert len(fc) >= 3 and fc["holds"].all()
    sigma2 = per[per["statement"] == "5c_sigma2"]
    assert sigma2[sigma2["x"] < 36]["holds"].all()  # σ2 ±90 % negligible up to 36·vs
    # ... but not beyond: the 1 s cycle under applied pressure (72·vs) shows its boundary
    assert not sigma2[sigma2["x"] > 50]["holds"].any()
    ranking = quick.tables["sensitivity_ranking"]
    first = ranking[(ranking["rank"] == 1) & (ranking["feature"] == "breakaway_pressure")]
    assert (first["parameter"] == "Fc").all()  # not σ0: no motion threshold any more
    assert (first["group"] == 1).all()
    # a ranking groups what its intervals cannot order: the five below Fc are one group
    below = ranking[(ranking["method"] == "SRC²") & (ranking["parameter"] != "Fc")]
    assert (below["group"] == 2).all()


def test_every_figure_has_axis_labels_with_units(quick):
    """Issue #40, item 6: every panel of every figure names its axes with a unit in
    brackets ([1] for a ratio), a categorical 'parameter' axis excepted."""
    assert len(FIGURE_AXES) >= len(FIGURES)
    for labels in FIGURE_AXES:
        assert labels
        for x, y in labels:
            assert "[" in y and "]" in y, (x, y)
            assert ("[" in x and "]" in x) or x == "parameter", (x, y)


def test_the_pneumatic_half_is_reported(quick):
    """Issue #40, item 5: Φ(r)'s choked limit with the paper's 'constant' corrected, the
    time constant along the stroke, the natural frequencies and every modelling choice."""
    html = unescape(quick.report.read_text(encoding="utf-8"))
    assert "Φ* = 0.5787" in html and "r_c = 0.5283" in html
    assert "the flow stays ∝ p_up" in html
    tau = quick.tables["chamber_time_constant"]
    ms = tau["τ isothermal [ms]"].to_numpy()
    assert ms[0] == pytest.approx(201, rel=ref.HAND_VALUE_RTOL) and (np.diff(ms) < 0).all()
    frequencies = quick.tables["natural_frequencies"].set_index("case")["frequency [Hz]"]
    assert frequencies["free"] == pytest.approx(ref.FREE_FREQUENCY_HZ, rel=ref.HAND_VALUE_RTOL)
    assert frequencies["stuck on the bristles"] == pytest.approx(ref.STUCK_FREQUENCY_HZ,
                                                                 rel=ref.HAND_VALUE_RTOL)
    choices = quick.tables["modelling_choices"]
    assert choices["source"].str.len().gt(10).all()


def test_lugre_and_dahl_are_similar_only_well_above_the_stribeck_velocity(quick):
    """Section III.1: 'LuGre and Dahl ... show similar results': under the applied
    pressure they do at 72·vs, not at 0.23·vs, where LuGre's Stribeck hump shows; δ = 2
    for δ = 1 stays below the visibility line at the conditions of the quick run."""
    laws = quick.tables["law_changes"]
    dahl = laws[laws["law"] == "Dahl"].sort_values("speed_vs")
    assert dahl["verdict"].iloc[0] == "differs" and dahl["speed_vs"].iloc[0] < 1
    assert dahl["verdict"].iloc[-1] == "similar" and dahl["speed_vs"].iloc[-1] > 50
    assert (laws.loc[laws["law"] == "δ = 2", "loop change"] < 0.05).all()


def test_fig6_is_labelled_self_consistent_and_rerun_on_richer_models(quick):
    """Issue #40, item 4: the held-back record made by the identified model itself is
    labelled so; records from richer models (δ = 2, a quantised and lagging sensor) are
    told apart by their residuals, not by the fit %."""
    html = unescape(quick.report.read_text(encoding="utf-8"))
    assert "Self-consistency, not validation" in html
    richer = quick.tables["validation_richer"].set_index("record made by")
    assert richer.loc["self-consistent", "verdict"] == "adequate"
    for case in ("δ = 2", "5 µm steps, 5 ms lag"):
        assert "residuals not white" in richer.loc[case, "verdict"], case
        assert richer.loc[case, "fit % position"] > 99.0  # the fit % alone would pass
    assert richer.loc["δ = 2", "loop width error"] > 3 * richer.loc["self-consistent",
                                                                      "loop width error"]


@needs_browser
def test_the_report_fits_a_1280_px_page(quick):
    found = assert_fits_the_page(quick.report)
    assert found["tables"] >= len(TABLES) and found["figures"] >= len(FIGURES)


def test_identified_parameters_are_close_to_table_one(quick):
    table = quick.tables["identification"].set_index("parameter")
    for name in ("F0", "k", "Fc", "Fs"):
        assert abs(table.loc[name, "error_%"]) < 2.0, name
    metrics = quick.tables["validation_metrics"]
    assert (metrics["fit_percent"] > 99.0).all()


def test_cli_reproduce_quick(quick_cli):
    _, returned, folder = quick_cli
    assert (folder / "index.html").exists()
    assert returned.report == folder / "index.html"
    assert "pneumact reproduce --quick --out paper" in (
        folder / "index.html").read_text(encoding="utf-8")


def test_sobol_sample_size_is_chosen_by_the_convergence_check(quick):
    """Issue #40, item 3: the Sobol ranking runs at the size the convergence check stopped
    at, and the report says whether that size settles the order or is too wide to rank
    (then only at the largest size)."""
    table = quick.tables["sobol_convergence"]
    sizes = Sizes.quick()
    n = int(table["n"].iloc[-1])
    assert list(table["n"]) == [sizes.sobol_min_n * 2**i for i in range(len(table))]
    assert n <= sizes.sobol_n
    html = unescape(quick.report.read_text(encoding="utf-8"))
    assert "chosen by the convergence check" in html
    assert f"Sobol total indices ({n * (6 + 2)} runs)" in html
    widest = float(table.filter(like="widest ST").iloc[-1].max())
    if "too wide to rank" in html:
        assert n == sizes.sobol_n and widest > SOBOL_TARGET_WIDTH
    else:
        assert "converged" in html or "the order is settled" in html


def test_quick_mode_says_which_richer_campaigns_it_left_out(quick):
    html = unescape(quick.report.read_text(encoding="utf-8"))
    assert ("Quick mode: not run on δ = 2, GMS-4, adiabatic chamber, 5 µm steps, 5 ms lag"
            in html)
    assert "identification_richer" not in quick.tables


def test_the_seal_section_says_how_to_run_it_without_the_data(quick):
    html = unescape(quick.report.read_text(encoding="utf-8"))
    assert "Real friction data: the TU Delft cylinder's O-ring seal" in html
    assert "--seal-data FOLDER" in html
    assert "seal_friction" not in quick.tables


@pytest.mark.skipif(not SEAL_DATA.is_dir(), reason="shared TU Delft data set not available")
def test_the_seal_section_on_the_tudelft_records():
    """Issue #40, item 4 (real data, friction alone): identified at 1 and 7 bar, the
    friction predicted at 3 and 5 bar within the real-data tolerance; the records show no
    Stribeck dip (the fitted vs lies below the speeds the 100 Hz laser resolves)."""
    from pneumact.io.report import Report
    from pneumact.reproduction import _Parts, _seal_friction

    parts = _Parts(Report("seal"))
    _seal_friction(parts, SEAL_DATA)
    table = parts.tables["seal_friction"].set_index("supply pressure [bar gauge]")
    assert list(table.index) == [1.0, 3.0, 5.0, 7.0]
    predicted = table[table["role"] == "validation"]
    assert list(predicted.index) == [3.0, 5.0]
    assert (predicted["relative force error"] < ref.TUDELFT_ACROSS_FORCE_ERROR).all()
    assert (table["Fc [N]"] > 0).all() and (table["σ2 (Fv) [N·s/m]"] > 0).all()
    assert (table["Stribeck fit's vs [mm/s]"].fillna(0.0) < ref.SEAL_NO_DIP_SPEED).all()
    assert "seal_friction.png" in parts.writers


def test_identification_on_a_campaign_made_with_delta_two(vgt):
    """Issue #40, item 4: section III.2 on records made by LuGre with δ = 2 (the quick
    mode skips the richer campaigns; this one runs here on the full mode's small
    campaign). The spring and Coulomb level stay right; the Stribeck pair is not
    identified and the identification says so itself (its verdict names Fs and vs; σ2
    too since a refit that frees a position lag moves it beyond its interval)."""
    import warnings

    from pneumact.identification import paper_campaign
    from pneumact.reproduction import identify_richer

    sizes = Sizes.full()
    tests = paper_campaign(vgt, speeds=sizes.richer_ramp_speeds,
                           sweep_period=sizes.richer_sweep_period)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        row = identify_richer(vgt, "δ = 2", tests)
    assert row["records made by"] == "δ = 2"
    refused = re.search(r"\(not: (.*)\)", row["identified"]).group(1).split(", ")
    assert {"Fs", "vs"} <= set(refused) and not {"F0", "k", "Fc"} & set(refused), row
    for name in ("F0", "k", "Fc"):
        assert abs(row[f"{name} error %"]) < ref.RICHER_DELTA2_SPRING_COULOMB_ERROR, name
    assert abs(row["Fs error %"]) > ref.RICHER_DELTA2_STRIBECK_ERROR
    assert "Fs" in row["truth outside 95 % interval"]


def test_cli_seal_data_without_the_records_is_refused_before_any_work(tmp_path):
    result = CliRunner().invoke(app, ["reproduce", "--quick", "--out", str(tmp_path / "out"),
                                      "--seal-data", str(tmp_path)])
    assert result.exit_code != 0
    assert "lacks O-ring_1bar.csv" in result.output
    assert not (tmp_path / "out").exists()
